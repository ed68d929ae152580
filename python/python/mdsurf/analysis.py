"""MDAnalysis analysis of the Gaussian surface: area (Å²) and volume (Å³) per frame.

``GaussianSurface`` declares MDAnalysis's (>= 2.8) parallel backends ``serial``,
``multiprocessing`` and ``dask``; each worker computes its block of frames with its own engine
(the GPU is opened in the worker that uses it). With a ``dask.distributed`` client active
(``Client(cluster)``), ``run(backend="dask", n_workers=N)`` sends the blocks to that cluster;
without one, Dask's process scheduler runs them on this machine::

    import MDAnalysis as mda
    from dask.distributed import Client, LocalCluster
    from mdsurf.analysis import GaussianSurface

    u = mda.Universe("adk_open.pdb", "adk_dims.dcd")
    with LocalCluster(n_workers=2) as cluster, Client(cluster):
        surf = GaussianSurface(u, select="protein").run(backend="dask", n_workers=2)
    print(surf.results.area, surf.results.volume)
"""

import numpy as np
from MDAnalysis.analysis.backends import BackendDask
from MDAnalysis.analysis.base import AnalysisBase
from MDAnalysis.analysis.results import ResultsGroup

from . import _f32, _mdsurf, topology_radii
from .scene import Scene

__all__ = ["GaussianSurface", "atomgroup_radii"]

# Frames this process has measured for a GaussianSurface (tests check that workers took part).
_frames_measured = 0


def atomgroup_radii(atomgroup):
    """Radii in Å of the atoms of ``atomgroup`` as ``mdsurf surface`` assigns them for its file.

    Uses the universe's atom names, residue names and (when the topology has them) elements,
    and the current frame's positions for untyped particles.
    """
    atoms = atomgroup.universe.atoms
    elements = atoms.elements if hasattr(atoms, "elements") else None
    radii = topology_radii(atoms.names, atoms.resnames, elements, atoms.positions)
    return radii[atomgroup.ix]


class _DistributedBackend(BackendDask):
    """Sends the frame blocks to a ``dask.distributed`` client's cluster."""

    def __init__(self, client, n_workers):
        super().__init__(n_workers=n_workers)
        self.client = client

    def apply(self, func, computations):
        futures = self.client.map(func, computations, pure=False)
        return self.client.gather(futures)


def _default_client():
    """The active ``dask.distributed`` client, or None."""
    try:
        from distributed import default_client
    except ImportError:
        return None
    try:
        return default_client()
    except ValueError:
        return None


class GaussianSurface(AnalysisBase):
    """Area and volume of the Gaussian density surface of ``atomgroup`` in every frame.

    Frames go through the transformations of ``mdsurf surface``: molecules split by the
    periodic box are made whole by default when the frames have a box (``whole=False`` turns
    it off), and ``center``, ``fit`` and ``smooth`` act as ``--center``, ``--fit`` and
    ``--smooth``. So ``GaussianSurface(u, select="protein", engine="cpu")`` gives the numbers of
    ``mdsurf surface --select protein --backend cpu``.

    Parameters
    ----------
    atomgroup : MDAnalysis.AtomGroup or MDAnalysis.Universe
        The atoms whose surface is measured (all atoms of a universe).
    select : str, optional
        Instead of ``atomgroup``'s atoms, those this selection in mdsurf's selection language
        picks in each (transformed) frame, e.g. ``"protein"``, ``"within 5 of resname LIG"``.
        A selection that does not parse or picks no atom in the first frame raises
        ``ValueError``.
    radii : array_like, optional
        Radius in Å per atom of ``atomgroup`` (per atom of the universe with ``select``); by
        default the radii ``mdsurf surface`` gives the same file (:func:`atomgroup_radii`).
    spacing, radius_scale, isovalue, quality, vertices
        Surface parameters as in :func:`mdsurf.surface` (defaults H = 1 Å, R = 1, I = 0.5,
        quality "medium").
    engine : str
        The surface engine: "cpu", "gpu" or "auto" (the ``backend`` of :func:`mdsurf.surface`;
        named ``engine`` here because ``run(backend=...)`` is MDAnalysis's parallel backend).
    whole : bool, optional
        Make molecules whole (default: on when the frames have a box).
    center, fit : str, optional
        Selections (mdsurf's language) to centre in the box and to fit onto the first frame.
    smooth : int
        Average positions over ±``smooth`` frames.
    periodic : bool
        Periodic surfaces in each frame's box, as ``mdsurf surface --periodic``: Gaussians
        near a face reach across it, so a membrane patch or a liquid has no walls at the faces;
        area, volume and per-atom areas are per cell. Computed on the CPU (``engine`` "cpu" or
        "auto", interpolated vertices); a frame without a box raises ``ValueError``.
    per_residue : bool
        Also share each frame's area among the atoms (the rule of ``mdsurf surface
        --per-atom``: a triangle's area goes a third to each vertex, a vertex's share to the
        atoms by their Gaussians there) and sum it per residue, with each residue's exposure:
        its area over the largest area a residue of its name has alone (the first five of
        each name in the trajectory's first frame, computed alone on the CPU with the same
        settings, as :meth:`mdsurf.Scene.per_residue_areas` and ``mdsurf surface
        --per-residue`` build it from their first frame).

    Results
    -------
    results.area : numpy.ndarray, shape (n_frames,)
        Surface area in Å² per analysed frame.
    results.volume : numpy.ndarray, shape (n_frames,)
        Enclosed volume in Å³ per analysed frame.
    results.atom_area : numpy.ndarray, shape (n_frames, n_atoms)
        With ``per_residue``: each atom's area in Å² (atoms of ``atomgroup``, or of the universe
        with ``select``, where atoms not selected in a frame have 0); each row sums to
        ``results.area``.
    results.residue_area : numpy.ndarray, shape (n_frames, n_residues)
        With ``per_residue``: the sum over each residue's atoms, residues of
        ``results.residues`` (those of ``atomgroup``, or of the universe with ``select``).
    results.exposure : numpy.ndarray, shape (n_frames, n_residues)
        With ``per_residue``: ``residue_area`` over the residue name's area alone (see
        ``per_residue``); NaN for a residue with no atom in the frame's surface or whose name
        had no residue in the first frame.
    """

    _analysis_algorithm_is_parallelizable = True

    @classmethod
    def get_supported_backends(cls):
        return ("serial", "multiprocessing", "dask")

    def __init__(
        self,
        atomgroup,
        radii=None,
        spacing=1.0,
        radius_scale=1.0,
        isovalue=0.5,
        quality="medium",
        engine="auto",
        vertices="interpolated",
        select=None,
        whole=None,
        center=None,
        fit=None,
        smooth=0,
        periodic=False,
        per_residue=False,
        **kwargs,
    ):
        atomgroup = atomgroup.atoms
        super().__init__(atomgroup.universe.trajectory, **kwargs)
        self._ag = atomgroup
        self._select = None if select is None else str(select)
        self._per_residue = bool(per_residue)
        self._periodic = bool(periodic)
        # The atoms the per-atom columns stand for, and the residues of the per-residue ones.
        self._columns = atomgroup if self._select is None else atomgroup.universe.atoms
        self._transforms = dict(
            whole=None if whole is None else bool(whole),
            center=None if center is None else str(center),
            fit=None if fit is None else str(fit),
            smooth=int(smooth),
        )
        core = self._scene()
        if self._select is not None:
            dynamic = core._core.check_selection(self._select)
            if not dynamic:
                _, picked, _ = core._core.transformed(0, core._reader, self._select)
                if len(picked) == 0:
                    raise ValueError(f"selection '{self._select}' matches no atom")
        count = len(atomgroup) if self._select is None else atomgroup.universe.atoms.n_atoms
        if radii is None:
            radii = core.radii if self._select is not None else core.radii[atomgroup.ix]
        radii = _f32(radii, "radii")
        if radii.shape != (count,):
            who = "per atom" if self._select is None else "per atom of the universe"
            raise ValueError(
                f"radii must be an array of shape ({count},), one {who}, "
                f"got shape {radii.shape}"
            )
        self._radii = radii
        self._settings = dict(
            spacing=float(spacing),
            radius_scale=float(radius_scale),
            isovalue=float(isovalue),
            quality=str(quality),
            backend=str(engine),
            vertices=str(vertices),
        )
        # Check the settings now (one atom), not in the first worker.
        _mdsurf.measure(
            np.zeros((0, 1, 3), np.float32),
            np.ones(1, np.float32),
            *self._settings.values(),
            boxes=np.zeros((0, 3, 3), np.float32) if self._periodic else None,
        )
        if self._per_residue:
            self._exposure_reference = self._isolated_areas(core)

    def _isolated_areas(self, core):
        """The exposure denominator of each column residue (NaN where its name is missing):
        the table of the trajectory's first frame (see ``per_residue``)."""
        trajectory = self._ag.universe.trajectory
        was = trajectory.ts.frame
        positions, picked, box = core._core.transformed(0, core._reader, self._select)
        if trajectory.ts.frame != was:
            trajectory[was]
        if picked is None:
            atoms, radii = self._ag, self._radii
        else:
            atoms, radii = self._ag.universe.atoms[picked], self._radii[picked]
        residues = self._columns.residues
        owner = np.searchsorted(residues.resindices, atoms.resindices)
        names, areas = _mdsurf.exposure_table(
            np.ascontiguousarray(positions[atoms.ix], np.float32),
            radii,
            owner.astype(np.uint32).tolist(),
            [str(n) for n in residues.resnames],
            *(v for k, v in self._settings.items() if k != "backend"),
            box_=box,
        )
        table = dict(zip(names, areas))
        return np.array([table.get(str(n).strip(), np.nan) for n in residues.resnames])

    def _scene(self):
        """The frame reader through the transformations (built once per process)."""
        core = getattr(self, "_core", None)
        if core is None:
            core = Scene(self._ag.universe, _surfaces=False, **self._transforms)
            self._core = core
        return core

    def __getstate__(self):
        # The native scene is rebuilt in each worker.
        state = self.__dict__.copy()
        state.pop("_core", None)
        return state

    def _prepare(self):
        self.results.area = np.full(self.n_frames, np.nan)
        self.results.volume = np.full(self.n_frames, np.nan)
        if self._per_residue:
            n_atoms, n_residues = len(self._columns), len(self._columns.residues)
            self.results.atom_area = np.full((self.n_frames, n_atoms), np.nan)
            self.results.residue_area = np.full((self.n_frames, n_residues), np.nan)
            self.results.exposure = np.full((self.n_frames, n_residues), np.nan)

    def _single_frame(self):
        # The time step is updated in place by any read: its frame is taken first.
        frame = self._ts.frame
        scene = self._scene()
        trajectory = self._ag.universe.trajectory
        positions, picked, box = scene._core.transformed(frame, scene._reader, self._select)
        if trajectory.ts.frame != frame:
            trajectory[frame]  # smoothing read its neighbours: back to this frame
        if picked is None:
            picked = self._ag.ix
            radii = self._radii
        else:
            radii = self._radii[picked]
        boxes = None
        if self._periodic:
            if box is None:
                raise ValueError(f"frame {frame}: periodic=True needs a periodic box, and the "
                                 "frame has none")
            boxes = box[np.newaxis]
        shares = np.zeros(len(picked))
        if len(picked) == 0:
            area, volume = [0.0], [0.0]
        elif self._per_residue:
            area, volume, per_atom = _mdsurf.atom_areas(
                positions[picked][np.newaxis], radii, *self._settings.values(), boxes=boxes
            )
            shares = per_atom[0]
        else:
            area, volume = _mdsurf.measure(
                positions[picked][np.newaxis], radii, *self._settings.values(), boxes=boxes
            )
        self.results.area[self._frame_index] = area[0]
        self.results.volume[self._frame_index] = volume[0]
        if self._per_residue:
            row = np.zeros(len(self._columns))
            # Columns: atomgroup order without a selection, universe indices with one.
            row[np.arange(len(picked)) if self._select is None else picked] = shares
            self.results.atom_area[self._frame_index] = row
            residue_area = self._sum_per_residue(row)
            self.results.residue_area[self._frame_index] = residue_area
            present = np.zeros(len(self._columns))
            present[np.arange(len(picked)) if self._select is None else picked] = 1.0
            with np.errstate(divide="ignore", invalid="ignore"):
                exposure = residue_area / self._exposure_reference
            exposure[(self._sum_per_residue(present) == 0) | ~(self._exposure_reference > 0)] = np.nan
            self.results.exposure[self._frame_index] = exposure
        global _frames_measured
        _frames_measured += 1

    def _sum_per_residue(self, row):
        """Sums per-atom values (one per column atom) over the columns' residues."""
        residues = self._columns.residues.resindices
        owner = np.searchsorted(residues, self._columns.resindices)
        return np.bincount(owner, weights=row, minlength=len(residues))

    def _conclude(self):
        if self._per_residue:
            self.results.residues = self._columns.residues

    def _get_aggregator(self):
        lookup = {
            "area": ResultsGroup.ndarray_hstack,
            "volume": ResultsGroup.ndarray_hstack,
        }
        if self._per_residue:
            lookup["atom_area"] = ResultsGroup.ndarray_vstack
            lookup["residue_area"] = ResultsGroup.ndarray_vstack
            lookup["exposure"] = ResultsGroup.ndarray_vstack
        return ResultsGroup(lookup=lookup)

    def _configure_backend(self, backend, n_workers, unsupported_backend=False):
        executor = super()._configure_backend(
            backend=backend, n_workers=n_workers, unsupported_backend=unsupported_backend
        )
        if backend == "dask":
            client = _default_client()
            if client is not None:
                return _DistributedBackend(client, executor.n_workers)
        return executor
