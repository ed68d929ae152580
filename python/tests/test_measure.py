"""`Scene.per_atom_areas`, `per_residue_areas`, `interface` and `cavities` equal the tables of
`mdsurf surface --per-atom/--per-residue/--interface/--cavities` on the same files and frames,
and bad selections raise one-line `ValueError`s naming them."""

import csv
import shutil
import subprocess
import warnings

import MDAnalysis as mda
import numpy as np
import pytest

import mdsurf


def close(value, text, decimals):
    """`value` equals the CSV's `text` (printed with `decimals`): within its rounding, and
    1e-6 relative beyond it."""
    expected = float(text)
    return abs(value - expected) <= 0.5 * 10.0**-decimals + 1e-9 + 1e-6 * abs(expected)


def run_cli(cli, tmp_path, *args):
    cmd = [cli, "surface", *map(str, args), "--backend", "cpu", "--quiet", "--no-timings"]
    return subprocess.run(cmd, capture_output=True, text=True, cwd=tmp_path)


def rows_of(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def universe(*paths):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # MDAnalysis' notes on missing PDB records
        return mda.Universe(*map(str, paths))


@pytest.fixture
def adk(tmp_path, data):
    """Copies (MDAnalysis writes an XTC offsets cache beside the trajectory)."""
    out = []
    for name in ["adk_oplsaa.gro", "adk_oplsaa.xtc"]:
        shutil.copy(data / name, tmp_path / name)
        out.append(tmp_path / name)
    return out


def test_per_residue_and_per_atom_areas_equal_cli(cli, adk, tmp_path):
    gro, xtc = adk
    run = run_cli(cli, tmp_path, gro, xtc, "--select", "protein", "--frames", "0:3",
                  "--per-residue", "res.csv", "--per-atom", "atoms.csv", "--stats", "s.csv")
    assert run.returncode == 0, run.stderr
    res_rows, atom_rows = rows_of(tmp_path / "res.csv"), rows_of(tmp_path / "atoms.csv")
    frames = sorted({int(r["frame"]) for r in res_rows})
    assert len(frames) == 3
    scene = mdsurf.Scene(universe(gro, xtc), select="protein")

    res = scene.per_residue_areas("selection", frames=frames)
    assert list(res.frames) == frames
    assert res.area_A2.shape == (3, len(res.residues))
    assert len(res_rows) == 3 * len(res.residues)
    for row in res_rows:
        k, j = frames.index(int(row["frame"])), list(res.resids).index(int(row["resid"]))
        assert row["rep"] == "selection"
        assert (res.chains[j], res.resnames[j]) == (row["chain"], row["resname"]), row
        assert close(res.area_A2[k, j], row["area_A2"], 3), (res.area_A2[k, j], row)
        assert close(res.exposure[k, j], row["exposure"], 4), (res.exposure[k, j], row)
    # Rows sum to the surface's area, which is the stats table's.
    np.testing.assert_allclose(res.area_A2.sum(axis=1), res.total_area_A2, rtol=1e-9)
    stats = rows_of(tmp_path / "s.csv")
    assert all(close(t, s["area_A2"], 4) for t, s in zip(res.total_area_A2, stats))

    atoms = scene.per_atom_areas(frames=slice(0, 3))
    assert list(atoms.frames) == frames
    assert len(atom_rows) == 3 * len(atoms.atoms)
    for n, row in enumerate(atom_rows):
        k, j = divmod(n, len(atoms.atoms))
        assert int(row["frame"]) == frames[k]
        assert (atoms.serials[j], atoms.names[j]) == (int(row["serial"]), row["name"]), row
        assert close(atoms.area_A2[k, j], row["area_A2"], 3), (atoms.area_A2[k, j], row)
    np.testing.assert_allclose(atoms.area_A2.sum(axis=1), atoms.total_area_A2, rtol=1e-9)
    # Per residue is the sum over its atoms.
    for j, r in enumerate(res.residues[:20]):
        mine = scene._residues().residue_index[atoms.atoms] == r
        np.testing.assert_allclose(atoms.area_A2[:, mine].sum(axis=1), res.area_A2[:, j],
                                   rtol=1e-12, atol=1e-12)


def test_interface_equals_cli(cli, data, tmp_path):
    pdb = data / "1hpv.pdb"
    a, b = "protein and chain A", "protein and chain B"
    run = run_cli(cli, tmp_path, pdb, "--select", "protein", "--interface", a, b,
                  "--interface-csv", "i.csv")
    assert run.returncode == 0, run.stderr
    (row,) = rows_of(tmp_path / "i.csv")
    scene = mdsurf.Scene(universe(pdb), select="protein")
    got = scene.interface(a, b)
    assert list(got.frames) == [0]
    for name, column in [("area_a_A2", "area_a_A2"), ("area_b_A2", "area_b_A2"),
                         ("area_ab_A2", "area_ab_A2"), ("buried_A2", "buried_A2")]:
        assert close(getattr(got, name)[0], row[column], 4), (name, getattr(got, name), row)
    assert got.buried_A2[0] > 800
    assert " ".join(got.contacts_a[0]) == row["contacts_a"]
    assert " ".join(got.contacts_b[0]) == row["contacts_b"]
    assert np.all(got.contacts_a_buried_A2[0] > 1.0)
    assert len(got.contacts_b_residues[0]) == len(got.contacts_b[0]) > 10


def test_probe_interface_equals_cli(cli, data, tmp_path):
    pdb = data / "1hpv.pdb"
    a, b = "protein and chain A", "protein and chain B"
    run = run_cli(cli, tmp_path, pdb, "--select", "protein", "--interface", a, b,
                  "--interface-csv", "i.csv", "--interface-probe", "1.4")
    assert run.returncode == 0, run.stderr
    (row,) = rows_of(tmp_path / "i.csv")
    scene = mdsurf.Scene(universe(pdb), select="protein")
    got = scene.interface(a, b, probe_A=1.4)
    for name in ["area_a_A2", "area_b_A2", "area_ab_A2", "buried_A2"]:
        assert close(getattr(got, name)[0], row[name], 4), (name, getattr(got, name), row)
    assert " ".join(got.contacts_a[0]) == row["contacts_a"]
    # MSMS buries 1,193.0 Å² (tests/data/msms_interface.csv); the Gaussian default differs.
    assert abs(got.buried_A2[0] / 1193.0 - 1) < 0.05
    with pytest.raises(ValueError, match="probe_A must be a probe radius"):
        scene.interface(a, b, probe_A=0.0)


def test_cavities_equal_cli(cli, adk, tmp_path):
    gro, xtc = adk
    run = run_cli(cli, tmp_path, gro, xtc, "--select", "protein", "--frames", "0:4",
                  "--cavities", "cav.csv")
    assert run.returncode == 0, run.stderr
    rows = rows_of(tmp_path / "cav.csv")
    assert rows, "adenylate kinase has cavities"
    scene = mdsurf.Scene(universe(gro, xtc), select="protein")
    cav = scene.cavities(frames=range(4))
    assert len(cav) == len(rows)
    for k, row in enumerate(rows):
        assert (cav.frame[k], cav.cavity_id[k]) == (int(row["frame"]), int(row["cavity_id"]))
        assert close(cav.volume_A3[k], row["volume_A3"], 3), (cav.volume_A3[k], row)
        assert close(cav.area_A2[k], row["area_A2"], 3), (cav.area_A2[k], row)
        for axis, c in enumerate(["cx", "cy", "cz"]):
            assert close(cav.centroid_A[k, axis], row[c], 3), (cav.centroid_A[k], row)
        assert " ".join(cav.lining[k]) == row["lining"]
        assert len(cav.lining_atoms[k]) >= len(cav.lining[k])
    assert np.all(cav.volume_A3 >= 1.0)
    # An id seen in several frames: the tracking ran over the call's frames.
    ids, counts = np.unique(cav.cavity_id, return_counts=True)
    assert counts.max() >= 2


def test_periodic_measurements_equal_cli(cli, data, tmp_path):
    """A state file with periodic surfaces: the per-residue areas (over the periodic images,
    per cell), the cavities of the mesh welded across the faces and the interface's three
    periodic surfaces equal the command line's."""
    gro = tmp_path / "bilayer.gro"
    shutil.copy(data / "martini_dppc_chol_bilayer.gro", gro)
    state = tmp_path / "periodic.toml"
    state.write_text(
        'version = 1\n\n[trajectory]\nperiodic = true\n\n[[representation]]\n'
        'name = "lipids"\nselection = "resname DPPC CHOL"\nstyle = "surface"\n'
    )
    a, b = "resname DPPC", "resname CHOL"
    run = run_cli(cli, tmp_path, gro, "--state", state, "--per-residue", "res.csv",
                  "--stats", "s.csv", "--interface", a, b, "--interface-csv", "i.csv",
                  "--cavities", "c.csv", "--min-cavity-volume", "0")
    assert run.returncode == 0, run.stderr
    rows, (stats,), (row,) = (rows_of(tmp_path / n) for n in ["res.csv", "s.csv", "i.csv"])
    scene = mdsurf.Scene(universe(gro), state=str(state))
    res = scene.per_residue_areas("lipids")
    assert len(rows) == len(res.residues) == 450
    for j, r in enumerate(rows):
        assert close(res.area_A2[0, j], r["area_A2"], 3), (res.area_A2[0, j], r)
    # Per cell: the rows sum to the periodic surface's area.
    assert close(res.total_area_A2[0], stats["area_A2"], 4)
    got = scene.interface(a, b)
    for name in ["area_a_A2", "area_b_A2", "area_ab_A2", "buried_A2"]:
        assert close(getattr(got, name)[0], row[name], 4), (name, getattr(got, name), row)
    assert close(got.area_ab_A2[0], stats["area_A2"], 4)
    cavities = rows_of(tmp_path / "c.csv")
    cav = scene.cavities("lipids", min_volume_A3=0)
    assert len(cav) == len(cavities) >= 3  # voids between the lipids' tails
    # MDAnalysis reads GRO coordinates as f32 nm times 10 in f32 (84.20999 Å), mdsurf's reader
    # in f64 (84.21): the atoms differ by an f32 step, and a small void's walls by up to 2e-5.
    near = lambda value, text: abs(value - float(text)) <= 1e-4 * float(text) + 5e-4  # noqa: E731
    for k, row in enumerate(cavities):
        assert cav.cavity_id[k] == int(row["cavity_id"])
        assert near(cav.volume_A3[k], row["volume_A3"]), (cav.volume_A3[k], row)
        assert near(cav.area_A2[k], row["area_A2"]), (cav.area_A2[k], row)
        assert " ".join(cav.lining[k]) == row["lining"], (cav.lining[k], row)
    with pytest.raises(ValueError, match="periodic"):
        scene.interface(a, b, probe_A=1.4)
    with pytest.raises(ValueError, match="periodic"):
        scene.cavities("lipids", probe_A=1.4)


def test_periodic_keywords_equal_cli(cli, data, tmp_path):
    """``Scene(..., periodic=True)`` and ``replicate=`` are ``--periodic`` and ``--replicate``:
    the same areas, per-residue areas per cell whatever the images shown, and one-line
    errors."""
    gro = tmp_path / "bilayer.gro"
    shutil.copy(data / "martini_dppc_chol_bilayer.gro", gro)
    lipids = "resname DPPC CHOL"
    for flags, keywords in [
        (["--periodic"], dict(periodic=True)),
        (["--replicate", "2,2,1"], dict(replicate=(2, 2, 1))),
    ]:
        run = run_cli(cli, tmp_path, gro, "--select", lipids, *flags, "--stats", "s.csv",
                      "--per-residue", "r.csv")
        assert run.returncode == 0, run.stderr
        (stats,), rows = rows_of(tmp_path / "s.csv"), rows_of(tmp_path / "r.csv")
        scene = mdsurf.Scene(universe(gro), select=lipids, **keywords)
        assert "periodic" in scene.transforms, scene.transforms
        assert close(scene.run().area["selection"][0], stats["area_A2"], 4)
        res = scene.per_residue_areas()
        assert len(rows) == len(res.residues) == 450
        for j, r in enumerate(rows):
            assert close(res.area_A2[0, j], r["area_A2"], 3), (keywords, res.area_A2[0, j], r)
        if "replicate" in keywords:
            # Four images shown, the residues' areas still one cell's.
            assert close(res.total_area_A2[0] * 4, stats["area_A2"], 3)
    for bad in [(2, 2), (0, 1, 1)]:
        with pytest.raises(ValueError, match="replicate"):
            mdsurf.Scene(universe(gro), select=lipids, replicate=bad)


def test_gaussian_surface_periodic_equals_the_scene(data, tmp_path):
    """``GaussianSurface(periodic=True)`` computes the scene's periodic surfaces: the same
    area, per-residue areas and exposure; a GPU asked for is refused in one line."""
    from mdsurf.analysis import GaussianSurface

    gro = tmp_path / "bilayer.gro"
    shutil.copy(data / "martini_dppc_chol_bilayer.gro", gro)
    u = universe(gro)
    lipids = "resname DPPC CHOL"
    run = GaussianSurface(u, select=lipids, periodic=True, per_residue=True).run()
    scene = mdsurf.Scene(u, select=lipids, periodic=True)
    assert run.results.area[0] == pytest.approx(scene.run().area["selection"][0], rel=1e-9)
    res = scene.per_residue_areas()
    np.testing.assert_allclose(run.results.residue_area[0][res.residues], res.area_A2[0],
                               rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(run.results.exposure[0][res.residues], res.exposure[0],
                               rtol=1e-6)
    # Open surfaces have walls at the box's faces.
    walls = GaussianSurface(u, select=lipids).run()
    assert walls.results.area[0] > 1.3 * run.results.area[0]
    with pytest.raises(ValueError, match="on the CPU"):
        GaussianSurface(u, select=lipids, periodic=True, engine="gpu")
    with pytest.raises(ValueError, match="boxes must be an array of shape"):
        mdsurf.measure(np.zeros((2, 3, 3)), np.ones(3), boxes=np.zeros((1, 3, 3)))


def test_probe_cavities_equal_cli(cli, adk, tmp_path):
    gro, xtc = adk
    run = run_cli(cli, tmp_path, gro, xtc, "--select", "protein", "--frames", "0:2",
                  "--cavity-probe", "1.4", "--min-cavity-volume", "15", "--cavities", "cav.csv")
    assert run.returncode == 0, run.stderr
    rows = rows_of(tmp_path / "cav.csv")
    assert len(rows) >= 4, "adenylate kinase has probe-sized cavities"
    scene = mdsurf.Scene(universe(gro, xtc), select="protein")
    cav = scene.cavities(frames=range(2), min_volume_A3=15, probe_A=1.4)
    assert len(cav) == len(rows)
    for k, row in enumerate(rows):
        assert (cav.frame[k], cav.cavity_id[k]) == (int(row["frame"]), int(row["cavity_id"]))
        assert close(cav.volume_A3[k], row["volume_A3"], 3), (cav.volume_A3[k], row)
        assert close(cav.area_A2[k], row["area_A2"], 3), (cav.area_A2[k], row)
        assert " ".join(cav.lining[k]) == row["lining"]
    # The probe's voids hold at least one probe (4/3 pi 1.4^3 = 11.5 A^3, a little less on the
    # grid); the Gaussian surface's do not need to.
    assert np.all(cav.volume_A3 >= 15.0)
    with pytest.raises(ValueError, match="probe_A must be a probe radius"):
        scene.cavities(frames=[0], probe_A=0.0)


@pytest.fixture(scope="module")
def hpv(data):
    return mdsurf.Scene(universe(data / "1hpv.pdb"), select="protein")


@pytest.mark.parametrize(
    "a, b, message",
    [
        ("chain A", "resname XYZ", "interface: selection 'resname XYZ' matches no atom in frame 0"),
        ("chain A and", "chain B", "selection 'chain A and'"),
        ("chain A", "bogus(", "selection 'bogus\\('"),
        ("protein", "chain A", "selections 'protein' and 'chain A' share 758 atom"),
    ],
)
def test_interface_bad_selections(hpv, a, b, message):
    with pytest.raises(ValueError, match=message) as err:
        hpv.interface(a, b)
    assert "\n" not in str(err.value)


def test_measure_bad_arguments(hpv):
    with pytest.raises(ValueError, match="no surface representation named 'nope'"):
        hpv.per_residue_areas("nope")
    with pytest.raises(ValueError, match="min_volume_A3 must be a finite volume"):
        hpv.cavities(min_volume_A3=-1)
    with pytest.raises(ValueError, match="contact_threshold_A2"):
        hpv.interface("chain A", "chain B", contact_threshold_A2=float("nan"))
    with pytest.raises(IndexError):
        hpv.per_atom_areas(frames=[5])
