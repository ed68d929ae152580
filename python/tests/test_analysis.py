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
