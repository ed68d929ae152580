"""`mdsurf.Scene` and `GaussianSurface(select=...)` give the numbers of `mdsurf surface` on the
same files: the same topology, transformations (whole molecules by default) and
representations (`--select`, `--state`, the defaults), computed by the same frame path."""

import csv
import shutil
import subprocess
import warnings

import MDAnalysis as mda
import numpy as np
import pytest

import mdsurf
from mdsurf.analysis import GaussianSurface

# The CSV prints 4 decimals: 1e-6 relative is far above its rounding, far below any real change.
REL = 1e-6


def cli_rows(cli, tmp_path, *args):
    """`mdsurf surface ARGS --backend cpu --stats` rows."""
    stats = tmp_path / "stats.csv"
    cmd = [cli, "surface", *map(str, args), "--backend", "cpu", "--quiet", "--no-timings"]
    subprocess.run([*cmd, "--stats", str(stats)], check=True, capture_output=True, text=True)
    with open(stats, newline="") as f:
        return list(csv.DictReader(f))


def copies(tmp_path, data, *names):
    """Copies of test files (MDAnalysis writes an XTC offsets cache beside the trajectory)."""
    out = []
    for name in names:
        shutil.copy(data / name, tmp_path / name)
        out.append(tmp_path / name)
    return out


@pytest.fixture
def adk(tmp_path, data):
    gro, xtc = copies(tmp_path, data, "adk_oplsaa.gro", "adk_oplsaa.xtc")
    return gro, xtc, mda.Universe(str(gro), str(xtc))


def universe(path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # MDAnalysis' notes on missing PDB records
        return mda.Universe(str(path))


def assert_rows_equal(result, rows):
    """A SceneResults or a list of (name, frame, area, volume) equals the CLI's rows."""
    for row in rows:
        frame, rep = int(row["frame"]), row["rep"]
        k = list(result.frames).index(frame)
        assert result.area[rep][k] == pytest.approx(float(row["area_A2"]), rel=REL), row
        assert result.volume[rep][k] == pytest.approx(float(row["volume_A3"]), rel=REL), row
        assert result.atoms[rep][k] == int(row["atoms"]), row


def test_select_equals_cli_every_frame(cli, adk, tmp_path):
    """(a) adk_oplsaa (a protein split by the periodic box): whole molecules on both sides."""
    gro, xtc, u = adk
    rows = cli_rows(cli, tmp_path, gro, xtc, "--select", "protein")
    assert len(rows) == len(u.trajectory) == 10
    scene = mdsurf.Scene(u, select="protein")
    assert scene.representations == ["selection"]
    assert scene.transforms.startswith("whole")
    result = scene.run()
    assert list(result.frames) == list(range(10))
    assert_rows_equal(result, rows)
    cli_area = np.array([float(r["area_A2"]) for r in rows])
    worst = np.max(np.abs(result.area["selection"] / cli_area - 1))
    print(f"frame 0: Python {result.area['selection'][0]:.4f} Å², CLI {cli_area[0]:.4f} Å²; "
          f"largest relative difference {worst:.2e}")
    # Frame by frame through iteration and indexing too.
    frames = list(scene)
    assert frames[3]["selection"].area == result.area["selection"][3]
    assert scene[-1].frame == 9


def test_transforms_equal_cli(cli, adk, tmp_path):
    """--center, --fit and --smooth as on the command line (mass-weighted as the CLI weighs)."""
    gro, xtc, u = adk
    args = ["--center", "protein", "--fit", "protein and name CA", "--smooth", 1]
    rows = cli_rows(cli, tmp_path, gro, xtc, "--select", "protein", "--frames", "0:10:4", *args)
    scene = mdsurf.Scene(
        u, select="protein", center="protein", fit="protein and name CA", smooth=1
    )
    assert_rows_equal(scene.run(0, 10, 4), rows)


def test_whole_false_keeps_split_molecules(adk):
    _, _, u = adk
    whole = mdsurf.Scene(u, select="protein").frame(0)["selection"].area
    split = mdsurf.Scene(u, select="protein", whole=False).frame(0)["selection"].area
    assert split > whole * 1.05  # the split protein has extra surface at the box faces
    assert mdsurf.Scene(u, select="protein", whole=False).transforms == ""


STATE = """\
version = 1

[[representation]]
name = "protein"
selection = "protein"
style = "surface"

[[representation]]
name = "pocket"
selection = "protein and within 5 of resname 478"
style = "surface"
spacing = 0.8
isovalue = 0.6

[[representation]]
name = "ligand"
selection = "resname 478"
style = "ball-and-stick"

[[representation]]
name = "water"
selection = "water"
style = "surface"
visible = false
"""


def test_state_file_equals_cli(cli, data, tmp_path):
    """(b) Two visible surfaces, one of them a `within` selection, with their own H and I;
    atom styles and hidden representations are not computed (as --state)."""
    (pdb,) = copies(tmp_path, data, "1hpv.pdb")
    state = tmp_path / "view.toml"
    state.write_text(STATE)
    rows = cli_rows(cli, tmp_path, pdb, "--state", state)
    assert [r["rep"] for r in rows] == ["protein", "pocket"]
    scene = mdsurf.Scene(universe(pdb), state=state)
    assert scene.representations == ["protein", "pocket"]
    assert scene.selections[1] == "protein and within 5 of resname 478"
    assert_rows_equal(scene.run(), rows)


def test_state_file_over_frames_equals_cli(cli, adk, tmp_path):
    """A dynamic selection (the water shell) follows the whole, moving molecules."""
    gro, xtc, u = adk
    state = tmp_path / "shell.toml"
    state.write_text(
        'version = 1\n\n[[representation]]\nname = "protein"\nselection = "protein"\n\n'
        '[[representation]]\nname = "shell"\nselection = "resname SOL and same residue as '
        '(within 3 of protein)"\nspacing = 1.5\n'
    )
    rows = cli_rows(cli, tmp_path, gro, xtc, "--state", state, "--frames", "0:10:3")
    assert_rows_equal(mdsurf.Scene(u, state=state).run(0, 10, 3), rows)


def test_default_representations_equal_cli(cli, data, tmp_path):
    (pdb,) = copies(tmp_path, data, "1hpv.pdb")
    rows = cli_rows(cli, tmp_path, pdb)
    scene = mdsurf.Scene(universe(pdb))
    assert scene.representations == [r["rep"] for r in rows] == ["macromolecule"]
    assert_rows_equal(scene.run(), rows)


def test_default_representations_of_a_membrane_equal_cli(cli, data, tmp_path):
    """A coarse-grained membrane trajectory: macromolecule and the coarser lipid surface (the
    hidden solvent is not computed), molecules made whole."""
    gro, xtc = copies(tmp_path, data, "YiiP_lipids.gro.gz", "YiiP_lipids.xtc")
    rows = cli_rows(cli, tmp_path, gro, xtc, "--frames", "0:3")
    scene = mdsurf.Scene(mda.Universe(str(gro), str(xtc)))
    assert scene.representations == ["macromolecule", "lipids"]
    assert_rows_equal(scene.run(0, 3), rows)


def test_from_arrays_equals_universe(data):
    u = universe(data / "1hpv.pdb")
    scene = mdsurf.Scene.from_arrays(
        u.atoms.names,
        u.atoms.positions,
        resnames=u.atoms.resnames,
        resids=u.atoms.resids,
        elements=u.atoms.elements,
        select="protein",
    )
    expected = mdsurf.Scene(u, select="protein", whole=False).frame(0)["selection"]
    got = scene.frame(0)["selection"]
    assert (got.area, got.volume, got.atoms) == (expected.area, expected.volume, expected.atoms)
    assert len(scene) == 1 and scene.transforms == ""  # no box: nothing to make whole


def test_gaussian_surface_select_equals_cli(cli, adk, tmp_path):
    """(c) GaussianSurface(u, select="protein") measures the whole protein (~10,117 Å² in
    frame 0, not the 11,109 Å² of the protein split by the box)."""
    gro, xtc, u = adk
    rows = cli_rows(cli, tmp_path, gro, xtc, "--select", "protein", "--frames", "0:2")
    surf = GaussianSurface(u, select="protein", engine="cpu").run(stop=2)
    for k, row in enumerate(rows):
        assert surf.results.area[k] == pytest.approx(float(row["area_A2"]), rel=REL)
        assert surf.results.volume[k] == pytest.approx(float(row["volume_A3"]), rel=REL)
    # An AtomGroup gets whole molecules too.
    ag = GaussianSurface(u.select_atoms("protein"), engine="cpu").run(stop=1)
    assert ag.results.area[0] == pytest.approx(float(rows[0]["area_A2"]), rel=REL)
    split = GaussianSurface(u.select_atoms("protein"), engine="cpu", whole=False).run(stop=1)
    assert split.results.area[0] > ag.results.area[0] * 1.05


def test_gaussian_surface_smooth_keeps_frames(cli, adk, tmp_path):
    """Smoothing reads neighbouring frames; the analysis still walks its own frames."""
    gro, xtc, u = adk
    rows = cli_rows(cli, tmp_path, gro, xtc, "--select", "protein", "--smooth", 1,
                    "--frames", "2:5")
    surf = GaussianSurface(u, select="protein", engine="cpu", smooth=1).run(start=2, stop=5)
    np.testing.assert_allclose(
        surf.results.area, [float(r["area_A2"]) for r in rows], rtol=REL
    )


@pytest.mark.parametrize(
    "make",
    [
        lambda u: mdsurf.Scene(u, select="protein and resname"),
        lambda u: GaussianSurface(u, select="protein and resname"),
    ],
)
def test_bad_selection_is_one_line_value_error(data, make):
    """(d) A selection that does not parse: ValueError, one line, naming the selection."""
    u = universe(data / "1hpv.pdb")
    with pytest.raises(ValueError) as err:
        make(u)
    message = str(err.value)
    assert "\n" not in message
    assert "'protein and resname'" in message


def test_other_errors_are_value_errors(data, tmp_path):
    u = universe(data / "1hpv.pdb")
    with pytest.raises(ValueError, match="'resname XYZ'.*matches no atom"):
        mdsurf.Scene(u, select="resname XYZ")
    with pytest.raises(ValueError, match="matches no atom"):
        GaussianSurface(u, select="resname XYZ")
    with pytest.raises(ValueError, match="not both"):
        mdsurf.Scene(u, select="protein", state="view.toml")
    with pytest.raises(ValueError, match="view.toml"):
        mdsurf.Scene(u, state=tmp_path / "view.toml")
    with pytest.raises(ValueError, match="spacing"):
        mdsurf.Scene(u, select="protein", spacing=-1)
    with pytest.raises(ValueError, match="--center 'resname XYZ'"):
        mdsurf.Scene(u, select="protein", center="resname XYZ")
    with pytest.raises(IndexError):
        mdsurf.Scene(u, select="protein").frame(1)
    with pytest.raises(TypeError, match="select="):
        mdsurf.Scene(u.select_atoms("protein"))
    # Errors name their source, as the command line's name the file.
    positions = np.zeros((1, 2, 3), np.float32)
    with pytest.raises(ValueError, match="^Scene.from_arrays: --periodic needs a periodic box"):
        mdsurf.Scene.from_arrays(["C", "C"], positions, periodic=True)


MIRROR_SELECTIONS = [
    "protein", "backbone", "chain A", "segid A", "resid 10 to 20", "element C", "element H",
    "name CA", "type C", "water", "ion", "lipid", "ligand", "mass > 12", "residue 3",
    "same residue as (within 4 of resid 5)",
]


@pytest.mark.parametrize(
    "name", ["1hpv.pdb", "adk_oplsaa.gro", "martini_dppc_chol_bilayer.gro", "adk_open.pdb"]
)
def test_topology_mirrors_cli(cli, data, tmp_path, name):
    """The topology built from the universe selects what `mdsurf select` selects in the same
    file (names, elements, masses, residues, chains, segments), frame 0 as read."""
    (path,) = copies(tmp_path, data, name)
    scene = mdsurf.Scene(universe(path), whole=False, _surfaces=False)
    for sel in MIRROR_SELECTIONS:
        run = subprocess.run(
            [cli, "select", str(path), sel, "--indices"], capture_output=True, text=True
        )
        assert run.returncode == 0, run.stderr
        lines = run.stdout.strip().splitlines()
        expected = [int(i) for i in lines[1].split()] if len(lines) > 1 else []
        assert list(scene.select(sel)) == expected, sel


def test_masses_weigh_the_centre(adk):
    """Given masses replace mdsurf's element masses in the centring: another centre."""
    _, _, u = adk
    ours = mdsurf.Scene(u, select="protein", center="protein")
    same = mdsurf.Scene(u, select="protein", center="protein", masses=u.atoms.masses)
    other = np.where(u.atoms.ix < 1000, 100.0, 1.0)
    theirs = mdsurf.Scene(u, select="protein", center="protein", masses=other)
    a, b, c = ours.positions(0), same.positions(0), theirs.positions(0)
    assert a.shape == c.shape == (u.atoms.n_atoms, 3)
    np.testing.assert_allclose(a, b, atol=1e-3)  # MDAnalysis' guesses: the element masses
    assert np.abs(a - c).max() > 1.0


def test_gaussian_surface_workers_equal_serial(adk):
    """Blocks of frames in forked workers (after the parent computed on its threads), with
    smoothing reading frames outside each block: the serial numbers."""
    _, _, u = adk
    for smooth in (0, 1):
        serial = GaussianSurface(u, select="protein", engine="cpu", smooth=smooth).run(stop=4)
        forked = GaussianSurface(u, select="protein", engine="cpu", smooth=smooth).run(
            stop=4, backend="multiprocessing", n_workers=2
        )
        np.testing.assert_array_equal(forked.results.area, serial.results.area)
        np.testing.assert_array_equal(forked.results.volume, serial.results.volume)


def test_scene_leaves_the_trajectory_where_it_was(adk):
    _, _, u = adk
    u.trajectory[5]
    scene = mdsurf.Scene(u, select="protein", smooth=2)
    assert u.trajectory.ts.frame == 5
    assert len(scene) == 10


def test_scene_dropped_on_another_thread_is_freed(adk):
    """A scene whose last reference goes on another thread (a worker, a garbage collection run
    there) is dropped there like any Python object: no "unsendable ... dropped on another
    thread" leak reported through `sys.unraisablehook`."""
    import gc
    import sys
    import threading

    _, _, u = adk
    scene = mdsurf.Scene(u, select="protein")
    assert scene[0]["selection"].area > 0
    reported = []
    previous = sys.unraisablehook
    sys.unraisablehook = lambda info: reported.append(f"{info.exc_type.__name__}: {info.exc_value}")
    try:
        holder = [scene]
        del scene

        def drop():
            holder.clear()
            gc.collect()

        worker = threading.Thread(target=drop)
        worker.start()
        worker.join()
    finally:
        sys.unraisablehook = previous
    assert holder == [] and reported == [], reported


def test_exposure_of_residues_split_by_the_box_is_against_whole_ones(adk):
    """With ``whole=False`` the frames keep adk's split residues (9 of 214 in frame 0 span
    more than half the box), but each residue alone, the exposure's denominator, is made whole
    in the frame's box: the same table as with whole molecules, to the grid's placement."""
    _, _, u = adk
    tables = []
    for whole in (True, False):
        run = GaussianSurface(u, select="protein", per_residue=True, whole=whole).run(stop=1)
        names, areas = run.results.residues.resnames, run._exposure_reference
        tables.append({n: a for n, a in zip(names, areas) if np.isfinite(a)})
    assert set(tables[0]) == set(tables[1]) and len(tables[0]) >= 19
    for name, area in tables[0].items():
        assert tables[1][name] == pytest.approx(area, rel=0.01), name
    # The scene's own measurement path takes the same table.
    for whole, table in zip((True, False), tables):
        res = mdsurf.Scene(u, select="protein", whole=whole).per_residue_areas(frames=[0])
        with np.errstate(invalid="ignore", divide="ignore"):  # 0 / 0 for buried residues
            reference = res.area_A2[0] / res.exposure[0]
        for name, value in zip(res.resnames, reference):
            if np.isfinite(value):
                assert value == pytest.approx(table[name], rel=1e-6), (whole, name)
