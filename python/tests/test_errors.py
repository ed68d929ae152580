"""Bad input raises a Python exception with the command line's one-line message."""

import subprocess

import numpy as np
import pytest

import mdsurf

ATOMS = np.array([[0, 0, 0], [1.5, 0, 0], [0, 1.5, 0]], np.float32)
RADII = np.array([1.5, 1.5, 1.5], np.float32)


@pytest.mark.parametrize(
    "positions, radii, message",
    [
        (np.zeros((3, 2)), RADII, r"positions must be an array of shape \(N, 3\), got shape \(3, 2\)"),
        (np.zeros(3), RADII, r"positions must be an array of shape \(N, 3\), got shape \(3\)"),
        (ATOMS, RADII[:2], r"radii must be an array of shape \(3,\), one per atom, got shape \(2\)"),
        (np.zeros((0, 3)), np.zeros(0), "the system has no atoms"),
        ([[0, 0, 0], [np.nan, 0, 0]], [1, 1], "atom 1 has a NaN or infinite coordinate"),
        ([[0, 0, 0], [np.inf, 0, 0]], [1, 1], "atom 1 has a NaN or infinite coordinate"),
        (ATOMS, [1.5, -1.0, 1.5], "atom 1 has radius -1 Å; radii must be positive"),
        (ATOMS, [1.5, 0.0, 1.5], "atom 1 has radius 0 Å; radii must be positive"),
        ([["a", "b", "c"]], [1], "positions must be an array of numbers"),
    ],
)
def test_bad_atoms(positions, radii, message):
    with pytest.raises(ValueError, match=message):
        mdsurf.surface(positions, radii, backend="cpu")


def test_bad_colours():
    with pytest.raises(ValueError, match=r"colors must be an array of shape \(3, 3\)"):
        mdsurf.surface(ATOMS, RADII, colors=np.ones((3, 4)), backend="cpu")
    with pytest.raises(ValueError, match="atom 2 has a NaN or infinite colour"):
        mdsurf.surface(ATOMS, RADII, colors=[[1, 0, 0], [0, 1, 0], [0, 0, np.nan]], backend="cpu")


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(spacing=-1), "grid spacing H must be a positive number, got -1"),
        (dict(spacing=0), "grid spacing H must be a positive number, got 0"),
        (dict(radius_scale=float("nan")), "radius scale R must be a positive number, got NaN"),
        (dict(isovalue=-0.5), "isovalue I must be a positive number, got -0.5"),
        (dict(quality="fine"), r"unknown quality 'fine' \(expected low, medium, high or max\)"),
        (dict(backend="tpu"), r"unknown backend 'tpu' \(expected cpu, gpu or auto\)"),
        (dict(vertices="exact"), "unknown vertex mode 'exact'"),
    ],
)
def test_bad_parameters(kwargs, message):
    kwargs.setdefault("backend", "cpu")
    with pytest.raises(ValueError, match=message):
        mdsurf.surface(ATOMS, RADII, **kwargs)
    with pytest.raises(ValueError, match=message):
        mdsurf.measure(ATOMS[np.newaxis], RADII, **kwargs)


def test_measure_names_the_frame():
    traj = np.stack([ATOMS, ATOMS, ATOMS])
    traj[2, 0, 1] = np.nan
    with pytest.raises(ValueError, match="^frame 2: atom 0 has a NaN or infinite coordinate$"):
        mdsurf.measure(traj, RADII, backend="cpu")
    with pytest.raises(ValueError, match=r"trajectory must be an array of shape \(F, N, 3\)"):
        mdsurf.measure(ATOMS, RADII, backend="cpu")


def test_grid_too_large_is_memory_error():
    far = np.array([[0, 0, 0], [1e5, 1e5, 1e5]], np.float32)
    with pytest.raises(MemoryError, match="use a larger grid spacing H"):
        mdsurf.surface(far, [1.0, 1.0], spacing=0.01, backend="cpu")


def test_messages_equal_the_cli(cli, data):
    """The same bad parameter gives the same line from the command line (after `error: `)."""
    run = subprocess.run(
        [cli, "surface", str(data / "adk_open.pdb"), "--spacing", "-1", "--backend", "cpu"],
        capture_output=True, text=True,
    )
    assert run.returncode == 2
    with pytest.raises(ValueError) as err:
        mdsurf.surface(ATOMS, RADII, spacing=-1, backend="cpu")
    assert run.stderr.strip() == f"error: {err.value}"


def test_topology_radii_lengths():
    with pytest.raises(ValueError, match="resnames has 1 entries for 2 atoms"):
        mdsurf.topology_radii(["CA", "CB"], ["ALA"])
