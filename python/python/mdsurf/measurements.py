"""Measurements on a scene's surfaces, as ``mdsurf surface --per-atom/--per-residue/--cavities
/--interface`` computes them (docs/measure.md), as numpy arrays over a range of frames.

Each is one call of :class:`mdsurf.Scene` over the frames asked for (``frames=None``: every
frame; a ``slice``, a ``range`` or a list of indices), computed in that order as the command
line computes ``--frames``: the exposure table of :meth:`Scene.per_residue_areas` comes from the
first frame of the call, cavity ids start at 1 with it. Areas are in Å², volumes in Å³,
coordinates in Å; the attribute names say so (``area_A2``, ``volume_A3``, ``centroid_A``)::

    scene = mdsurf.Scene(u, select="protein")
    res = scene.per_residue_areas("selection", frames=slice(0, 10))
    res.area_A2.shape            # (10, n_residues); each row sums to the surface's area
    res.area_A2.sum(axis=1)      # == res.total_area_A2
    iface = scene.interface("chain A", "chain B")
    iface.buried_A2              # one value per frame
    cav = scene.cavities("selection")
    cav.cavity_id, cav.volume_A3, cav.lining[0]
"""

from dataclasses import dataclass

import numpy as np

from . import _mdsurf

__all__ = ["AtomAreas", "ResidueAreas", "InterfaceAreas", "Cavities"]


@dataclass(frozen=True)
class AtomAreas:
    """Area per atom of one representation (:meth:`Scene.per_atom_areas`).

    ``frames`` (F,) and ``times`` (F,) in ps (NaN when unknown); ``atoms`` (N,) the 0-based
    indices of the atoms the representation held in any of the frames, with their ``serials``,
    ``names``, ``resids``, ``resnames``, ``chains`` (the chain, else the segment) and
    ``labels`` of their residues (``A:LEU12``); ``area_A2`` (F, N) float64, 0 where an atom was
    not in the representation that frame; each row sums to ``total_area_A2`` (F,), the
    surface's area (one cell's for a periodic surface shown as several images)."""

    rep: str
    frames: np.ndarray
    times: np.ndarray
    atoms: np.ndarray
    serials: np.ndarray
    names: np.ndarray
    resids: np.ndarray
    resnames: np.ndarray
    chains: np.ndarray
    labels: np.ndarray
    area_A2: np.ndarray
    total_area_A2: np.ndarray


@dataclass(frozen=True)
class ResidueAreas:
    """Area per residue of one representation (:meth:`Scene.per_residue_areas`).

    ``frames`` (F,), ``times`` (F,) in ps; ``residues`` (R,) residue indices (topology order)
    of the residues with atoms in the representation in any of the frames, with ``resids``,
    ``resnames``, ``chains`` (chain, else segment) and ``labels`` (``A:LEU12``); ``area_A2``
    (F, R) float64 (0 where the residue had no atom in it), each row summing to
    ``total_area_A2`` (F,) (as for :class:`AtomAreas`); ``exposure`` (F, R): area over the largest area a residue of the
    same name has alone (NaN where unknown or absent)."""

    rep: str
    frames: np.ndarray
    times: np.ndarray
    residues: np.ndarray
    resids: np.ndarray
    resnames: np.ndarray
    chains: np.ndarray
    labels: np.ndarray
    area_A2: np.ndarray
    exposure: np.ndarray
    total_area_A2: np.ndarray


@dataclass(frozen=True)
class InterfaceAreas:
    """Buried area between two selections per frame (:meth:`Scene.interface`).

    ``frames``, ``times`` (ps); ``area_a_A2``, ``area_b_A2`` (each side alone),
    ``area_ab_A2`` (both together) and ``buried_A2`` = (area_a + area_b - area_ab) / 2, all
    (F,) float64, the three surfaces on one grid. Contact residues (those losing more than the
    threshold, 1 Å² by default) per frame: ``contacts_a[k]`` / ``contacts_b[k]`` lists of
    labels (``A:LEU12``), ``contacts_a_residues[k]`` residue indices and
    ``contacts_a_buried_A2[k]`` the area each lost (likewise for B)."""

    selection_a: str
    selection_b: str
    frames: np.ndarray
    times: np.ndarray
    area_a_A2: np.ndarray
    area_b_A2: np.ndarray
    area_ab_A2: np.ndarray
    buried_A2: np.ndarray
    contacts_a: list
    contacts_b: list
    contacts_a_residues: list
    contacts_b_residues: list
    contacts_a_buried_A2: list
    contacts_b_buried_A2: list


@dataclass(frozen=True)
class Cavities:
    """Enclosed cavities of one representation, tracked over the frames of the call
    (:meth:`Scene.cavities`), one row per cavity and frame, in frame order.

    ``frame`` (C,), ``time`` (C,) ps; ``cavity_id`` (C,) stable while the cavity persists
    (from 1), ``born`` (C,) the first frame of the id; ``volume_A3``, ``area_A2`` (C,);
    ``centroid_A`` (C, 3); ``lining`` (C lists of residue labels, ``A:LEU12``) and
    ``lining_atoms`` (C arrays of atom indices). ``frames`` (F,) are the frames measured."""

    rep: str
    frames: np.ndarray
    frame: np.ndarray
    time: np.ndarray
    cavity_id: np.ndarray
    born: np.ndarray
    volume_A3: np.ndarray
    area_A2: np.ndarray
    centroid_A: np.ndarray
    lining: list
    lining_atoms: list

    def __len__(self):
        return len(self.cavity_id)


def _time(t):
    return np.nan if t is None else float(t)


def _union(index_lists, values_lists, fill):
    """The sorted union of the index arrays, and a (F, union) array of the values (``fill``
    where an index is absent)."""
    union = np.unique(np.concatenate([np.asarray(i, np.int64) for i in index_lists] or [[]]))
    union = union.astype(np.int64)
    out = np.full((len(index_lists), len(union)), fill, dtype=np.float64)
    for k, (idx, values) in enumerate(zip(index_lists, values_lists)):
        out[k, np.searchsorted(union, np.asarray(idx, np.int64))] = values
    return union, out


class _Residues:
    """The topology's residues and atoms as the CSV tables label them (built once)."""

    def __init__(self, core):
        first, labels, chains, resids, resnames = _mdsurf.scene_residues(core)
        self.first = np.asarray(first, np.int64)
        self.labels = np.array(labels, dtype=object)
        self.chains = np.array(chains, dtype=object)
        self.resids = np.asarray(resids, np.int64)
        self.resnames = np.array(resnames, dtype=object)
        serials, names, residue_index = _mdsurf.scene_atoms(core)
        self.serials = np.asarray(serials, np.int64)
        self.names = np.array(names, dtype=object)
        self.residue_index = np.asarray(residue_index, np.int64)


def atom_areas(scene, rep, frames):
    rows = _mdsurf.scene_atom_areas(scene._core, rep, frames, scene._reader)
    top = scene._residues()
    atoms, area = _union([r[3] for r in rows], [r[4] for r in rows], 0.0)
    res = top.residue_index[atoms]
    return AtomAreas(
        rep=rep,
        frames=np.array([r[0] for r in rows], dtype=np.int64),
        times=np.array([_time(r[1]) for r in rows]),
        atoms=atoms,
        serials=top.serials[atoms],
        names=top.names[atoms],
        resids=top.resids[res],
        resnames=top.resnames[res],
        chains=top.chains[res],
        labels=top.labels[res],
        area_A2=area,
        total_area_A2=np.array([r[2] for r in rows]),
    )


def residue_areas(scene, rep, frames):
    rows = _mdsurf.scene_residue_areas(scene._core, rep, frames, scene._reader)
    top = scene._residues()
    residues, area = _union([r[3] for r in rows], [r[4] for r in rows], 0.0)
    _, exposure = _union([r[3] for r in rows], [r[5] for r in rows], np.nan)
    return ResidueAreas(
        rep=rep,
        frames=np.array([r[0] for r in rows], dtype=np.int64),
        times=np.array([_time(r[1]) for r in rows]),
        residues=residues,
        resids=top.resids[residues],
        resnames=top.resnames[residues],
        chains=top.chains[residues],
        labels=top.labels[residues],
        area_A2=area,
        exposure=exposure,
        total_area_A2=np.array([r[2] for r in rows]),
    )


def interface(scene, a, b, frames, threshold, probe=None):
    rows = _mdsurf.scene_interface(scene._core, a, b, frames, scene._reader, threshold, probe)

    def side(s):
        picked = [[c for c in r[6] if c[0] == s] for r in rows]
        return (
            [[c[2] for c in p] for p in picked],
            [np.array([c[1] for c in p], dtype=np.int64) for p in picked],
            [np.array([c[5] for c in p], dtype=np.float64) for p in picked],
        )

    (la, ra, ba), (lb, rb, bb) = side(0), side(1)
    column = lambda k: np.array([r[k] for r in rows], dtype=np.float64)  # noqa: E731
    return InterfaceAreas(
        selection_a=a,
        selection_b=b,
        frames=np.array([r[0] for r in rows], dtype=np.int64),
        times=np.array([_time(r[1]) for r in rows]),
        area_a_A2=column(2),
        area_b_A2=column(3),
        area_ab_A2=column(4),
        buried_A2=column(5),
        contacts_a=la,
        contacts_b=lb,
        contacts_a_residues=ra,
        contacts_b_residues=rb,
        contacts_a_buried_A2=ba,
        contacts_b_buried_A2=bb,
    )


def cavities(scene, rep, frames, min_volume, probe=None):
    rows = _mdsurf.scene_cavities(scene._core, rep, frames, scene._reader, min_volume, probe)
    flat = [(f, t, c) for f, t, cavs in rows for c in cavs]
    return Cavities(
        rep=rep,
        frames=np.array([r[0] for r in rows], dtype=np.int64),
        frame=np.array([f for f, _, _ in flat], dtype=np.int64),
        time=np.array([_time(t) for _, t, _ in flat]),
        cavity_id=np.array([c[0] for _, _, c in flat], dtype=np.int64),
        born=np.array([c[1] for _, _, c in flat], dtype=np.int64),
        volume_A3=np.array([c[2] for _, _, c in flat], dtype=np.float64),
        area_A2=np.array([c[3] for _, _, c in flat], dtype=np.float64),
        centroid_A=np.array([c[4] for _, _, c in flat], dtype=np.float64).reshape(-1, 3),
        lining=[list(c[5]) for _, _, c in flat],
        lining_atoms=[np.asarray(c[6], dtype=np.int64) for _, _, c in flat],
    )
