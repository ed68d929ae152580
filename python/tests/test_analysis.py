"""`GaussianSurface` gives the same per-frame results serially, in a multiprocessing pool and
on a Dask cluster (a `dask.distributed.LocalCluster` of 2 workers)."""

import MDAnalysis as mda
import numpy as np
import pytest

import mdsurf
from mdsurf.analysis import GaussianSurface

# Every 8th frame of 98: 13 frames, split into blocks over the workers.
STEP = 8


@pytest.fixture(scope="module")
def universe(data):
    return mda.Universe(str(data / "adk_open.pdb"), str(data / "adk_dims.dcd"))


@pytest.fixture(scope="module")
def serial(universe):
    return GaussianSurface(universe.atoms).run(step=STEP)


def test_serial_matches_measure(universe, serial):
    frames = range(0, universe.trajectory.n_frames, STEP)
    assert list(serial.frames) == list(frames)
    traj = np.stack([universe.trajectory[f].positions.copy() for f in frames])
    area, volume = mdsurf.measure(traj, mdsurf.analysis.atomgroup_radii(universe.atoms))
    np.testing.assert_array_equal(serial.results.area, area)
    np.testing.assert_array_equal(serial.results.volume, volume)
    assert np.all(serial.results.area > 8000) and np.all(serial.results.volume > 30000)


def test_declares_parallel_backends():
    assert set(GaussianSurface.get_supported_backends()) == {"serial", "multiprocessing", "dask"}


def test_multiprocessing_equals_serial(universe, serial):
    par = GaussianSurface(universe.atoms).run(step=STEP, backend="multiprocessing", n_workers=2)
    np.testing.assert_array_equal(par.frames, serial.frames)
    np.testing.assert_array_equal(par.results.area, serial.results.area)
    np.testing.assert_array_equal(par.results.volume, serial.results.volume)


def test_dask_cluster_equals_serial(universe, serial):
    distributed = pytest.importorskip("dask.distributed")
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster, distributed.Client(cluster) as client:
        par = GaussianSurface(universe.atoms).run(step=STEP, backend="dask", n_workers=2)
        # Both workers took part: each ran at least one block of frames.
        # A lambda travels by value (this test module is not importable in the workers).
        busy = client.run(lambda: __import__("mdsurf.analysis").analysis._frames_measured)
    np.testing.assert_array_equal(par.frames, serial.frames)
    np.testing.assert_array_equal(par.results.area, serial.results.area)
    np.testing.assert_array_equal(par.results.volume, serial.results.volume)
    assert len(busy) == 2 and all(n > 0 for n in busy.values()), busy


def test_dask_process_scheduler_equals_serial(universe, serial):
    """Without a distributed client, `backend="dask"` uses Dask's process scheduler."""
    par = GaussianSurface(universe.atoms).run(step=STEP * 4, backend="dask", n_workers=2)
    np.testing.assert_array_equal(par.results.area, serial.results.area[::4])


def test_selection_and_explicit_radii(universe):
    ca = universe.select_atoms("name CA")
    surf = GaussianSurface(ca, radii=np.full(len(ca), 2.0), spacing=2.0).run(stop=2)
    assert surf.results.area.shape == (2,) and np.all(surf.results.area > 0)
    with pytest.raises(ValueError, match=r"radii must be an array of shape \(214,\)"):
        GaussianSurface(ca, radii=[1.0, 2.0])
    with pytest.raises(ValueError, match="unknown quality 'fine'"):
        GaussianSurface(ca, quality="fine")


@pytest.fixture(scope="module")
def per_residue(universe):
    protein = universe.select_atoms("protein")
    return GaussianSurface(protein, per_residue=True).run(step=STEP)


def test_per_residue_areas_sum_to_the_area(universe, serial, per_residue):
    r = per_residue.results
    protein = universe.select_atoms("protein")
    assert r.atom_area.shape == (len(serial.frames), len(protein))
    assert r.residue_area.shape == (len(serial.frames), len(protein.residues))
    assert list(r.residues.resids) == list(protein.residues.resids)
    # The same surfaces: adk_open.pdb is all protein.
    np.testing.assert_array_equal(r.area, serial.results.area)
    np.testing.assert_allclose(r.atom_area.sum(axis=1), r.area, rtol=1e-9)
    np.testing.assert_allclose(r.residue_area.sum(axis=1), r.area, rtol=1e-9)
    assert np.all(r.atom_area >= 0) and np.count_nonzero(r.atom_area[0]) > len(protein) // 3


def test_per_residue_areas_equal_the_scenes(universe, per_residue):
    # The scene's measurement path (as `mdsurf surface --per-residue`) on the same frames.
    scene = mdsurf.Scene(universe, select="protein")
    frames = list(per_residue.frames)
    expected = scene.per_residue_areas("selection", frames=frames)
    assert list(expected.resids) == list(per_residue.results.residues.resids)
    np.testing.assert_allclose(per_residue.results.residue_area, expected.area_A2, rtol=1e-6)
    # Exposure: the same table (first frame, residues alone) and the same quotients.
    assert per_residue.frames[0] == 0
    np.testing.assert_allclose(per_residue.results.exposure, expected.exposure, rtol=1e-6)
    assert np.nanmax(per_residue.results.exposure) > 0.5
    assert np.all(per_residue.results.exposure[np.isfinite(per_residue.results.exposure)] >= 0)
    # Residues' areas change as adenylate kinase opens.
    spread = np.ptp(per_residue.results.residue_area, axis=0)
    assert spread.max() > 20.0


def test_per_residue_in_parallel_equals_serial(universe, per_residue):
    protein = universe.select_atoms("protein")
    par = GaussianSurface(protein, per_residue=True).run(
        step=STEP, backend="multiprocessing", n_workers=2
    )
    np.testing.assert_array_equal(par.results.residue_area, per_residue.results.residue_area)
    np.testing.assert_array_equal(par.results.atom_area, per_residue.results.atom_area)
    np.testing.assert_array_equal(par.results.exposure, per_residue.results.exposure)


def test_per_residue_with_a_selection_has_universe_columns(universe):
    run = GaussianSurface(universe, select="resid 1:30", per_residue=True).run(stop=2)
    r = run.results
    assert r.atom_area.shape == (2, universe.atoms.n_atoms)
    outside = universe.select_atoms("not resid 1:30").ix
    assert np.all(r.atom_area[:, outside] == 0)
    np.testing.assert_allclose(r.atom_area.sum(axis=1), r.area, rtol=1e-9)
    assert r.residue_area.shape == (2, len(universe.residues))
    assert np.all(r.residue_area[:, 30:] == 0) and np.all(r.residue_area[:, :30] > 0)
    # Residues outside the surface have no exposure; those inside their area over the table's.
    assert np.all(np.isnan(r.exposure[:, 30:])) and np.all(np.isfinite(r.exposure[:, :30]))
    scene = mdsurf.Scene(universe, select="resid 1:30")
    expected = scene.per_residue_areas("selection", frames=[0, 1])
    np.testing.assert_allclose(r.exposure[:, :30], expected.exposure, rtol=1e-6)
