"""Scenes: the representations of ``mdsurf surface`` measured frame by frame from Python.

A :class:`Scene` is built from an MDAnalysis ``Universe`` (or plain arrays) and EITHER
``select="protein"`` (one surface representation named ``selection``, as ``--select``) OR
``state="view.toml"`` (the visible surface representations of a state file, as ``--state``)
OR neither (the default representations: macromolecule, lipids). Frames go through the command
line's transformations: molecules are made whole when the frames have a box (``whole=False``
turns it off), ``center=SEL``, ``fit=SEL`` and ``smooth=K`` as ``--center``, ``--fit`` and
``--smooth``. Each frame's area (Å²) and volume (Å³) per representation are computed by the
command line's own frame path on the CPU engine, so they equal ``mdsurf surface --stats``::

    import MDAnalysis as mda
    import mdsurf

    u = mda.Universe("adk_oplsaa.gro", "adk_oplsaa.xtc")
    scene = mdsurf.Scene(u, select="protein")
    print(scene.frame(0)["selection"].area)
    results = scene.run()                     # every frame
    print(results.area["selection"])          # numpy array, one value per frame

The topology mirrors what the command line reads from the same file: names, residue names and
numbers, chains, segments, elements where the file gives valid ones (else guessed from names as
mdsurf guesses them), bonds the file lists, radii and masses from mdsurf's element table (the
universe's guessed masses are not used, so ``center`` and ``fit`` weigh atoms as the CLI does).
"""

import warnings
from dataclasses import dataclass, field

import numpy as np

from . import _f32, _mdsurf
from . import measurements as _measure

__all__ = ["Scene", "SceneFrame", "RepSurface", "SceneResults", "universe_columns"]


@dataclass(frozen=True)
class RepSurface:
    """One surface representation in one frame: ``area`` in Å², ``volume`` in Å³, the number of
    ``atoms`` (particles) it was computed from, the grid ``dims``, and the mesh's ``vertices``
    and ``triangles`` counts."""

    name: str
    selection: str
    area: float
    volume: float
    atoms: int
    dims: tuple
    vertices: int
    triangles: int


@dataclass(frozen=True)
class SceneFrame:
    """Every visible surface representation of frame ``frame`` (``time`` in ps or None)."""

    frame: int
    time: object
    surfaces: list

    def __getitem__(self, name):
        """The representation named ``name`` (the first one, when names repeat)."""
        for s in self.surfaces:
            if s.name == name:
                return s
        raise KeyError(f"no representation named '{name}' (have {self.names})")

    @property
    def names(self):
        return [s.name for s in self.surfaces]


@dataclass
class SceneResults:
    """Results of :meth:`Scene.run`: ``frames`` (indices), ``times`` (ps, NaN when unknown),
    and per representation name ``area`` (Å²), ``volume`` (Å³) and ``atoms``, numpy arrays with
    one value per frame."""

    frames: np.ndarray
    times: np.ndarray
    area: dict = field(default_factory=dict)
    volume: dict = field(default_factory=dict)
    atoms: dict = field(default_factory=dict)


def _strings(values):
    return [str(v) for v in values]


def _attr(atoms, name):
    """``atoms.<name>`` or None when the topology does not have it."""
    try:
        return getattr(atoms, name)
    except (AttributeError, ValueError):
        return None


def universe_columns(universe):
    """The per-atom columns of ``universe`` as the command line reads them from its file."""
    atoms = universe.atoms
    n = len(atoms)
    cols = {
        "names": _strings(atoms.names),
        "resnames": _strings(atoms.resnames),
        "resids": [int(r) for r in atoms.resids],
        "residues": [int(r) for r in atoms.resindices],
    }
    chains = _attr(atoms, "chainIDs")
    if chains is not None:
        cols["chains"] = _strings(chains)
    segids = _attr(atoms, "segids")
    if segids is not None:
        segids = _strings(segids)
        # MDAnalysis names the one segment of a GRO file SYSTEM, and copies chain IDs into
        # empty PDB segment columns; mdsurf's readers leave both empty.
        if not all(s == "SYSTEM" for s in segids) and segids != cols.get("chains"):
            cols["segments"] = segids
    elements = _attr(atoms, "elements")
    if elements is not None:
        cols["elements"] = _strings(elements)
        # chemfiles' atom type of a file with an element column is that column.
        cols["types"] = _strings(elements)
    for column, attr, convert in [
        ("serials", "ids", int),
        ("b_factors", "tempfactors", float),
        ("occupancies", "occupancies", float),
        ("charges", "formalcharges", float),
    ]:
        values = _attr(atoms, attr)
        if values is not None and len(values) == n:
            cols[column] = [convert(v) for v in values]
    bonds = _attr(universe, "bonds")
    if bonds is not None and len(bonds) > 0:
        cols["bonds"] = [(int(a), int(b)) for a, b in bonds.indices]
    return cols


def _box_of(dimensions):
    """MDAnalysis ``dimensions`` (a, b, c, alpha, beta, gamma) as (3, 3) edge vectors, or None."""
    if dimensions is None:
        return None
    dims = np.asarray(dimensions, dtype=np.float64)
    if dims.shape != (6,) or not np.all(dims[:3] > 0):
        return None
    from MDAnalysis.lib.mdamath import triclinic_vectors

    return np.ascontiguousarray(triclinic_vectors(dims), dtype=np.float32)


class _UniverseReader:
    """Frame ``i`` of a universe's trajectory as ``(positions, box, time)``."""

    def __init__(self, universe):
        self.trajectory = universe.trajectory

    def __call__(self, i):
        ts = self.trajectory.ts
        if ts.frame != i:
            ts = self.trajectory[i]
        positions = np.array(ts.positions, dtype=np.float32, order="C")
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # "Reader has no dt information": time not needed
            time = float(ts.time)
        return positions, _box_of(ts.dimensions), time


class _ArrayReader:
    """Frame ``i`` of arrays ``positions`` (F, N, 3), ``boxes`` (F, 3, 3) and ``times`` (F,)."""

    def __init__(self, positions, boxes, times):
        self.positions, self.boxes, self.times = positions, boxes, times

    def __call__(self, i):
        box = None if self.boxes is None else self.boxes[i]
        time = None if self.times is None else float(self.times[i])
        return self.positions[i], box, time


class Scene:
    """Per-frame area and volume of the surface representations of a system.

    Parameters
    ----------
    universe : MDAnalysis.Universe
        The system and its trajectory (for plain arrays use :meth:`Scene.from_arrays`).
    select : str, optional
        One surface representation (named ``selection``) of the atoms this selection picks, in
        mdsurf's selection language (as ``mdsurf surface --select``).
    state : str or path, optional
        A state file: its visible surface representations, with their own H, R, I, quality and
        vertices, and, unless a transformation keyword is given, its transformations (as
        ``--state``). Not together with ``select``.
    spacing, radius_scale, isovalue, quality
        Surface parameters of ``select`` and the default representations (defaults H = 1 Å,
        R = 1, I = 0.5, "medium").
    vertices : str, optional
        "interpolated" (default) or "refined"; for a state file, replaces the file's setting.
    whole : bool, optional
        Make molecules whole across the periodic box; by default on when the frames have a box
        (and bonds or residues), as on the command line.
    center, fit : str, optional
        Selections to centre in the box and to fit onto the first frame (``--center``,
        ``--fit``).
    smooth : int
        Average positions over ±``smooth`` frames (``--smooth``).
    periodic : bool
        Periodic surfaces in each frame's box (``--periodic``): Gaussians near a face reach
        across it, the mesh is one cell's, and area, volume and every measurement are per cell
        (a membrane patch or a liquid without walls at the faces; rectangular or triclinic
        boxes).
    replicate : tuple of 3 ints, optional
        With ``periodic`` (implied): show A x B x C images of the cell (``--replicate``); the
        area and volume are then those of all the images, the measurements still per cell.
    masses : array_like, optional
        Mass per atom in amu for ``center`` and ``fit`` (e.g. ``universe.atoms.masses``); by
        default mdsurf's element masses, as the command line uses for GRO and PDB files.

    Errors (a selection that does not parse or matches no atom, a bad state file, bad
    parameters) raise ``ValueError`` with the command line's one-line message.
    """

    def __init__(
        self,
        universe=None,
        *,
        select=None,
        state=None,
        spacing=1.0,
        radius_scale=1.0,
        isovalue=0.5,
        quality="medium",
        vertices=None,
        whole=None,
        center=None,
        fit=None,
        smooth=0,
        periodic=False,
        replicate=None,
        masses=None,
        _columns=None,
        _reader=None,
        _n_frames=None,
        _file="",
        _surfaces=True,
    ):
        if universe is not None:
            if getattr(universe, "universe", universe) is not universe:
                raise TypeError(
                    "Scene takes the whole Universe (as the command line takes the file); "
                    "pick atoms with select=, e.g. Scene(u, select='protein')"
                )
            columns = universe_columns(universe)
            reader = _UniverseReader(universe)
            n_frames = len(universe.trajectory)
            # Errors name the file, as on the command line (an in-memory universe has none).
            file = str(getattr(universe.trajectory, "filename", "") or "") or "the universe"
        elif _columns is not None:
            columns, reader, n_frames, file = _columns, _reader, _n_frames, _file
        else:
            raise ValueError("Scene needs a universe (or use Scene.from_arrays)")
        if masses is not None:
            columns = dict(columns, masses=[float(m) for m in np.asarray(masses).ravel()])
        if n_frames < 1:
            raise ValueError("the trajectory has no frames")
        if replicate is not None:
            replicate = [int(n) for n in replicate]
            if len(replicate) != 3 or min(replicate) < 1:
                raise ValueError(
                    f"replicate {tuple(replicate)}: expected three whole numbers of at least 1, "
                    "e.g. (2, 2, 1)"
                )
        self._reader = reader
        self._n_frames = n_frames
        # Reading frame 0 (and its smoothing window) moves the universe's trajectory: it is put
        # back where it was.
        current = None if universe is None else universe.trajectory.ts.frame
        try:
            self._core = self._build(columns, n_frames, reader, file, select, state, spacing,
                                     radius_scale, isovalue, quality, vertices, whole, center,
                                     fit, smooth, (bool(periodic), replicate), _surfaces)
        finally:
            if current is not None and universe.trajectory.ts.frame != current:
                universe.trajectory[current]

    @staticmethod
    def _build(columns, n_frames, reader, file, select, state, spacing, radius_scale, isovalue,
               quality, vertices, whole, center, fit, smooth, periodic, surfaces):
        first, box, _ = reader(0)
        periodic, replicate = periodic
        return _mdsurf.SceneCore(
            columns,
            _f32(first, "positions"),
            None if box is None else _f32(box, "box"),
            n_frames,
            reader,
            select=None if select is None else str(select),
            state=None if state is None else str(state),
            spacing=float(spacing),
            radius_scale=float(radius_scale),
            isovalue=float(isovalue),
            quality=str(quality),
            vertices=None if vertices is None else str(vertices),
            whole=None if whole is None else bool(whole),
            center=None if center is None else str(center),
            fit=None if fit is None else str(fit),
            smooth=int(smooth),
            periodic=periodic,
            replicate=replicate,
            file=file,
            surfaces=surfaces,
        )

    @classmethod
    def from_arrays(
        cls,
        names,
        positions,
        boxes=None,
        times=None,
        *,
        resnames=None,
        resids=None,
        chains=None,
        segments=None,
        elements=None,
        masses=None,
        bonds=None,
        **kwargs,
    ):
        """A scene of plain arrays: atom ``names`` (N,), ``positions`` (F, N, 3) or (N, 3) in
        Å, ``boxes`` (F, 3, 3) or (3, 3) edge vectors in Å (or None), ``times`` (F,) in ps;
        optional per-atom ``resnames``, ``resids``, ``chains``, ``segments``, ``elements``,
        ``masses`` (amu; missing or 0: from the element) and ``bonds`` (B, 2) atom indices.
        Keywords as for :class:`Scene`."""
        positions = _f32(positions, "positions")
        if positions.ndim == 2:
            positions = positions[np.newaxis]
        if positions.ndim != 3 or positions.shape[2] != 3:
            raise ValueError(
                f"positions must be an array of shape (F, N, 3) or (N, 3), got shape "
                f"{positions.shape}"
            )
        frames = positions.shape[0]
        if boxes is not None:
            boxes = _f32(boxes, "boxes")
            if boxes.ndim == 2:
                boxes = np.broadcast_to(boxes, (frames, 3, 3))
            if boxes.shape != (frames, 3, 3):
                raise ValueError(
                    f"boxes must be an array of shape ({frames}, 3, 3) or (3, 3), got shape "
                    f"{boxes.shape}"
                )
            boxes = np.ascontiguousarray(boxes)
        if times is not None:
            times = np.asarray(times, dtype=np.float64)
        columns = {"names": _strings(names)}
        for key, values, convert in [
            ("resnames", resnames, str),
            ("resids", resids, int),
            ("chains", chains, str),
            ("segments", segments, str),
            ("elements", elements, str),
        ]:
            if values is not None:
                columns[key] = [convert(v) for v in values]
        if bonds is not None:
            columns["bonds"] = [(int(a), int(b)) for a, b in np.asarray(bonds).reshape(-1, 2)]
        reader = _ArrayReader(positions, boxes, times)
        return cls(
            None, masses=masses, _columns=columns, _reader=reader, _n_frames=frames,
            _file="Scene.from_arrays", **kwargs
        )

    def __len__(self):
        return self._n_frames

    @property
    def n_frames(self):
        return self._n_frames

    @property
    def n_atoms(self):
        return self._core.n_atoms

    @property
    def representations(self):
        """Names of the visible surface representations, in order."""
        return [name for name, _ in self._core.representations()]

    @property
    def selections(self):
        """Selection of each visible surface representation, in order."""
        return [sel for _, sel in self._core.representations()]

    @property
    def transforms(self):
        """What is done to each frame, e.g. ``"whole (bonds guessed from distances)"``."""
        return self._core.transforms

    @property
    def radii(self):
        """Radius of every atom in Å, as the command line assigns them."""
        return self._core.radii()

    @property
    def elements(self):
        """Element of every atom (from the file, else guessed)."""
        return self._core.elements()

    def _index(self, i):
        i = int(i)
        if i < 0:
            i += self._n_frames
        if not 0 <= i < self._n_frames:
            raise IndexError(f"frame {i} is outside 0..{self._n_frames}")
        return i

    def positions(self, i):
        """Frame ``i``'s positions (N, 3) in Å after the transformations."""
        positions, _, _ = self._core.transformed(self._index(i), self._reader)
        return positions

    def select(self, selection, frame=0):
        """Indices (uint32) of the atoms ``selection`` (mdsurf's language) picks in ``frame``
        after the transformations."""
        _, indices, _ = self._core.transformed(self._index(frame), self._reader, str(selection))
        return indices

    def frame(self, i):
        """Frame ``i``: a :class:`SceneFrame` with one :class:`RepSurface` per visible surface
        representation."""
        i = self._index(i)
        rows, time = self._core.frame(i, self._reader)
        return SceneFrame(i, time, [RepSurface(*row) for row in rows])

    def __getitem__(self, i):
        return self.frame(i)

    def __iter__(self):
        for i in range(self._n_frames):
            yield self.frame(i)

    def run(self, start=None, stop=None, step=None):
        """Every frame of ``range(n_frames)[start:stop:step]``: a :class:`SceneResults`."""
        frames = range(self._n_frames)[slice(start, stop, step)]
        names = self.representations
        area = {n: np.full(len(frames), np.nan) for n in names}
        volume = {n: np.full(len(frames), np.nan) for n in names}
        atoms = {n: np.zeros(len(frames), dtype=np.int64) for n in names}
        times = np.full(len(frames), np.nan)
        for k, i in enumerate(frames):
            f = self.frame(i)
            if f.time is not None:
                times[k] = f.time
            for s in f.surfaces:
                area[s.name][k] = s.area
                volume[s.name][k] = s.volume
                atoms[s.name][k] = s.atoms
        return SceneResults(np.array(frames, dtype=np.int64), times, area, volume, atoms)

    # Measurements (mdsurf/measurements.py, docs/measure.md): one call per range of frames.

    def _frames(self, frames):
        """Frame indices of ``frames``: None (all), an int, a slice, a range or indices."""
        if frames is None:
            return list(range(self._n_frames))
        if isinstance(frames, slice):
            return list(range(self._n_frames)[frames])
        if np.ndim(frames) == 0:
            return [self._index(frames)]
        return [self._index(i) for i in frames]

    def _rep(self, rep):
        """The representation ``rep`` names, or the only one when None."""
        if rep is None:
            names = self.representations
            if len(names) != 1:
                raise ValueError(f"name a representation: the scene has {names}")
            return names[0]
        return str(rep)

    def _residues(self):
        if getattr(self, "_residue_table", None) is None:
            self._residue_table = _measure._Residues(self._core)
        return self._residue_table

    def per_atom_areas(self, rep=None, frames=None):
        """Area per atom (Å²) of representation ``rep`` (default: the only one) in ``frames``
        (None: every frame; an int, a slice, a range or a list of indices): an
        :class:`mdsurf.measurements.AtomAreas` with an (n_frames, n_atoms) ``area_A2`` array whose
        rows sum to the surface's area (``--per-atom``). Each vertex's share of the surface goes
        to the atoms in proportion to their Gaussians there (docs/measure.md)."""
        return _measure.atom_areas(self, self._rep(rep), self._frames(frames))

    def per_residue_areas(self, rep=None, frames=None):
        """Area per residue (Å²) and exposure of representation ``rep`` in ``frames``: a
        :class:`mdsurf.measurements.ResidueAreas` with (n_frames, n_residues) ``area_A2`` and
        ``exposure`` arrays and the residues' ``resids``, ``resnames``, ``chains``
        (``--per-residue``). Exposure's reference areas (each residue name alone) come from the
        first frame of ``frames``, as the command line takes them from its first frame."""
        return _measure.residue_areas(self, self._rep(rep), self._frames(frames))

    def interface(self, selection_a, selection_b, frames=None, contact_threshold_A2=1.0,
                  probe_A=None):
        """Buried area between two selections (mdsurf's language) in ``frames``, as
        ``--interface A B``: (area(A) + area(B) - area(A and B)) / 2 in Å², the three surfaces
        on one grid with the scene's H, R, I and quality (CPU engine), and the residues losing
        more than ``contact_threshold_A2``: an :class:`mdsurf.measurements.InterfaceAreas`. With
        ``probe_A`` (1.4 for water) the surfaces are the solvent-excluded surfaces of a probe of
        that radius with Bondi's radii, as MSMS computes them (``--interface-probe``). A
        selection that does not parse or matches no atom in a frame raises ``ValueError``
        naming it."""
        probe = None if probe_A is None else float(probe_A)
        return _measure.interface(self, str(selection_a), str(selection_b),
                                  self._frames(frames), float(contact_threshold_A2), probe)

    def cavities(self, rep=None, frames=None, min_volume_A3=1.0, probe_A=None):
        """Enclosed cavities of representation ``rep`` in ``frames``, tracked over them (ids
        from 1, kept while a cavity overlaps its previous self): an
        :class:`mdsurf.measurements.Cavities` table with ``cavity_id``, ``volume_A3``, ``area_A2``,
        ``centroid_A`` and ``lining`` residues per cavity and frame (``--cavities``); voids
        under ``min_volume_A3`` are left out (``--min-cavity-volume``). With ``probe_A`` (1.4
        for water) the cavities are those of a probe of that radius with Bondi's radii, as the
        solvent-excluded surface has them (``--cavity-probe``), instead of the Gaussian
        surface's enclosed voids."""
        probe = None if probe_A is None else float(probe_A)
        return _measure.cavities(self, self._rep(rep), self._frames(frames), float(min_volume_A3),
                                 probe)

    def __repr__(self):
        return (
            f"Scene({self.n_atoms} atoms, {self._n_frames} frames, representations "
            f"{self.representations}, transforms '{self.transforms}')"
        )
