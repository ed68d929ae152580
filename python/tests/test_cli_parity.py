"""The package's numbers equal `mdsurf surface --stats` on the same frames of real files."""

import csv
import shutil
import subprocess

import MDAnalysis as mda
import numpy as np
import pytest

import mdsurf
import mdsurf.analysis

REL = 1e-4


def cli_stats(cli, tmp_path, *args):
    """Runs `mdsurf surface ARGS --backend cpu --stats` and returns its CSV rows."""
    stats = tmp_path / "stats.csv"
    cmd = [cli, "surface", *map(str, args), "--backend", "cpu", "--quiet", "--no-timings"]
    subprocess.run([*cmd, "--stats", str(stats)], check=True, capture_output=True, text=True)
    with open(stats, newline="") as f:
        return list(csv.DictReader(f))


def universe_radii(u):
    return mdsurf.analysis.atomgroup_radii(u.atoms)


def test_adk_frames_equal_cli(cli, data, tmp_path):
    rows = cli_stats(cli, tmp_path, data / "adk_open.pdb", data / "adk_dims.dcd", "--frames", "0:98:24")
    u = mda.Universe(str(data / "adk_open.pdb"), str(data / "adk_dims.dcd"))
    radii = universe_radii(u)
    frames = [int(r["frame"]) for r in rows]
    assert frames == [0, 24, 48, 72, 96]
    traj = np.stack([u.trajectory[f].positions.copy() for f in frames])
    assert all(int(r["atoms"]) == u.atoms.n_atoms for r in rows)

    area, volume = mdsurf.measure(traj, radii, backend="cpu")
    np.testing.assert_allclose(area, [float(r["area_A2"]) for r in rows], rtol=REL)
    np.testing.assert_allclose(volume, [float(r["volume_A3"]) for r in rows], rtol=REL)

    # One frame as a mesh: the same grid, counts and measures as the CLI's row.
    s = mdsurf.surface(traj[1], radii, backend="cpu")
    row = rows[1]
    assert s.grid.dims == (int(row["nx"]), int(row["ny"]), int(row["nz"]))
    assert s.vertices.shape == (int(row["vertices"]), 3)
    assert s.triangles.shape == (int(row["triangles"]), 3)
    assert s.area == pytest.approx(area[1], rel=1e-12)
    assert s.volume == pytest.approx(volume[1], rel=1e-12)


def test_gro_xtc_and_parameters_equal_cli(cli, data, tmp_path):
    """Other H, R, I and quality; a GRO topology (no elements) with hydrogens."""
    # Copies: MDAnalysis writes an XTC offsets cache beside the trajectory it reads.
    gro, xtc = tmp_path / "md_1u19.gro", tmp_path / "md_1u19.xtc"
    shutil.copy(data / gro.name, gro)
    shutil.copy(data / xtc.name, xtc)
    params = dict(spacing=1.5, radius_scale=1.2, isovalue=0.6, quality="high")
    rows = cli_stats(
        cli, tmp_path, gro, xtc, "--frames", "0:51:25", "--spacing", 1.5,
        "--radius-scale", 1.2, "--isovalue", 0.6, "--quality", "high", "--select", "all",
    )
    u = mda.Universe(str(gro), str(xtc))
    frames = [int(r["frame"]) for r in rows]
    traj = np.stack([u.trajectory[f].positions.copy() for f in frames])
    area, volume = mdsurf.measure(traj, universe_radii(u), backend="cpu", **params)
    np.testing.assert_allclose(area, [float(r["area_A2"]) for r in rows], rtol=REL)
    np.testing.assert_allclose(volume, [float(r["volume_A3"]) for r in rows], rtol=REL)


def test_wwpdb_elements_and_ligand_equal_cli(cli, data, tmp_path):
    """A wwPDB file with element columns, a ligand and water: every atom."""
    pdb = data / "1hpv.pdb"
    rows = cli_stats(cli, tmp_path, pdb, "--select", "all")
    u = mda.Universe(str(pdb))
    assert int(rows[0]["atoms"]) == u.atoms.n_atoms
    s = mdsurf.surface(u.atoms.positions, universe_radii(u), backend="cpu")
    assert s.area == pytest.approx(float(rows[0]["area_A2"]), rel=REL)
    assert s.volume == pytest.approx(float(rows[0]["volume_A3"]), rel=REL)


def test_auto_backend_matches_cli_auto(cli, data, tmp_path):
    """`backend="auto"` picks the engine the CLI's `--backend auto` picks, with its numbers."""
    pdb = data / "adk_open.pdb"
    stats = tmp_path / "auto.csv"
    run = subprocess.run(
        [cli, "surface", str(pdb), "--backend", "auto", "--no-timings", "--stats", str(stats)],
        check=True, capture_output=True, text=True,
    )
    note = next(line for line in run.stderr.splitlines() if line.startswith("backend: "))
    info = mdsurf.engine_info("auto")
    assert info.split(" ")[0] == note.split(" ")[1], (info, note)
    with open(stats, newline="") as f:
        row = next(csv.DictReader(f))
    u = mda.Universe(str(pdb))
    s = mdsurf.surface(u.atoms.positions, universe_radii(u))
    rel = REL if s.engine == "cpu" else 1e-3  # the GPU engine's CPU-parity tolerance
    assert s.area == pytest.approx(float(row["area_A2"]), rel=rel)
