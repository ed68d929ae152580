//! Measurements on periodic surfaces (`--periodic`, `src/measure/periodic.rs`): per-atom areas
//! over the atoms' images (so they do not depend on where the cell is cut) and per cell with
//! `--replicate`; cavities of the mesh welded across the faces, which with the surface's own
//! volume fill the cell, in rectangular and triclinic cells, tracked across a face; the
//! interface's three periodic surfaces; the probes' refusals.

use glam::{DVec3, Vec3};
use mdsurf::measure::{self, CavityOptions, CavityTracker};
use mdsurf::scene::cavity_layer::{CavitySource, find_cavities};
use mdsurf::surface::periodic::density::PeriodicGrid;
use mdsurf::surface::periodic::{PeriodicBox, PeriodicEngine, Replicate, TriclinicCell};
use mdsurf::surface::{AtomSet, SurfaceOutput, SurfaceParams};

use crate::cli_common::{Csv, mdsurf};
use crate::data_support::data;
use crate::surface_periodic::{ARGON, BILAYER, load, params, shifted};

fn atoms<'a>(positions: &'a [Vec3], radii: &'a [f32]) -> AtomSet<'a> {
    AtomSet {
        positions,
        radii,
        colours: None,
    }
}

fn surface(
    positions: &[Vec3],
    radii: &[f32],
    p: &SurfaceParams,
    pbox: &PeriodicBox,
    replicate: Replicate,
) -> SurfaceOutput {
    PeriodicEngine::new()
        .compute(&atoms(positions, radii), p, pbox, replicate)
        .expect("periodic surface")
}

/// A shift of whole grid steps (7, 3 and 5 samples), so that the sampled density moves with the
/// atoms and the surface is the same up to rounding.
fn grid_shift(pbox: &PeriodicBox, p: &SurfaceParams) -> Vec3 {
    let grid = PeriodicGrid::new(pbox, pbox.samples(p.spacing));
    grid.spacing * Vec3::new(7.0, 3.0, 5.0)
}

fn no_minimum() -> CavityOptions {
    CavityOptions {
        min_volume: 0.0,
        ..CavityOptions::default()
    }
}

#[test]
fn per_atom_areas_of_a_periodic_membrane_do_not_depend_on_where_the_cell_is_cut() {
    let (radii, frame, pbox) = load(BILAYER);
    let p = params(1.5, 1.0);
    let base = surface(&frame.positions, &radii, &p, &pbox, Replicate::default());
    let moved_positions = shifted(&frame.positions, grid_shift(&pbox, &p), pbox.lengths);
    let moved = surface(&moved_positions, &radii, &p, &pbox, Replicate::default());
    let a = measure::atom_areas_of(&base, &atoms(&frame.positions, &radii), &p).unwrap();
    let b = measure::atom_areas_of(&moved, &atoms(&moved_positions, &radii), &p).unwrap();
    let sum: f64 = a.iter().sum();
    assert!(
        (sum - base.area).abs() < 1e-9 * base.area,
        "{sum} against {}",
        base.area
    );
    let largest = a.iter().fold(0.0f64, |m, &x| m.max(x));
    let worst = a
        .iter()
        .zip(&b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0f64, f64::max);
    // Weighed without the images across the faces, lipids at the cut lost or gained up to
    // ~100 Å² of their ~120 Å² when the cell was cut elsewhere.
    assert!(
        worst < 1e-3 * largest,
        "an atom's area moved by {worst} Å² (largest {largest} Å²)"
    );
}

#[test]
fn replicated_periodic_surfaces_give_per_atom_areas_per_cell() {
    let (radii, frame, pbox) = load(BILAYER);
    let p = params(2.0, 1.0);
    let set = atoms(&frame.positions, &radii);
    let one = surface(&frame.positions, &radii, &p, &pbox, Replicate::default());
    let four = surface(&frame.positions, &radii, &p, &pbox, Replicate([2, 1, 2]));
    assert!((four.area - 4.0 * one.area).abs() < 1e-9 * four.area);
    let a = measure::atom_areas_of(&one, &set, &p).unwrap();
    let b = measure::atom_areas_of(&four, &set, &p).unwrap();
    let largest = a.iter().fold(0.0f64, |m, &x| m.max(x));
    for (i, (x, y)) in a.iter().zip(&b).enumerate() {
        assert!((x - y).abs() < 1e-9 * largest, "atom {i}: {x} against {y}");
    }
}

/// Checks that `found` (cavities of `out`, every void finite) with the surface's own volume
/// fill the cell, and that their walls are the whole surface.
fn assert_fills_cell(found: &[measure::Cavity], out: &SurfaceOutput, cell_volume: f64) {
    assert!(found.len() >= 5, "{} cavities", found.len());
    let voids: f64 = found.iter().map(|c| c.volume).sum();
    let walls: f64 = found.iter().map(|c| c.area).sum();
    assert!(
        (voids + out.volume - cell_volume).abs() < 1e-6 * cell_volume,
        "voids {voids} + matter {} against the cell's {cell_volume} Å³",
        out.volume
    );
    assert!(
        (walls - out.area).abs() < 1e-6 * out.area,
        "{walls} against {}",
        out.area
    );
    assert!(found.iter().all(|c| !c.lining_atoms.is_empty()));
}

#[test]
fn a_liquids_cavities_and_its_surface_fill_the_cell_wherever_it_is_cut() {
    // Liquid argon at the defaults fills the box; its surface is the walls of finite voids,
    // some cut by the faces (none was found before the mesh was welded across them).
    let (radii, frame, pbox) = load(ARGON);
    let p = params(1.0, 1.0);
    let cell_volume = pbox.lengths.as_dvec3().element_product();
    let out = surface(&frame.positions, &radii, &p, &pbox, Replicate::default());
    let set = atoms(&frame.positions, &radii);
    let found = measure::cavities_of(&out, &set, &p, &no_minimum()).unwrap();
    assert_fills_cell(&found, &out, cell_volume);
    let seams = out.periodic.as_deref().expect("a periodic surface");
    assert!(!seams.face_twins.is_empty() && seams.unmatched.is_empty());
    for c in &found {
        let f = c.centroid - pbox.origin.as_dvec3();
        let l = pbox.lengths.as_dvec3();
        assert!(
            f.cmpge(DVec3::ZERO).all() && f.cmplt(l).all(),
            "{:?}",
            c.centroid
        );
    }
    // The same liquid cut elsewhere (moved by whole grid steps): the same cavities, moved.
    let shift = grid_shift(&pbox, &p);
    let moved_positions = shifted(&frame.positions, shift, pbox.lengths);
    let moved = surface(&moved_positions, &radii, &p, &pbox, Replicate::default());
    let set = atoms(&moved_positions, &radii);
    let again = measure::cavities_of(&moved, &set, &p, &no_minimum()).unwrap();
    assert_eq!(again.len(), found.len());
    for (c, d) in found.iter().zip(&again) {
        assert!((c.volume - d.volume).abs() < 1e-4 * c.volume.max(1.0));
        assert_eq!(c.lining_atoms, d.lining_atoms);
        let mut back = d.clone();
        back.centroid -= shift.as_dvec3();
        assert!(c.centroid_distance(&back) < 1e-3, "{:?} {:?}", c, d);
    }
}

#[test]
fn a_triclinic_cell_of_the_same_lattice_has_cavities_that_fill_it() {
    // The cubic argon box described by the triclinic cell a, b, a + c: the same periodic
    // liquid, sampled along other axes.
    let (radii, frame, pbox) = load(ARGON);
    let l = pbox.lengths;
    let cell = TriclinicCell {
        origin: pbox.origin,
        rows: [Vec3::X * l.x, Vec3::Y * l.y, Vec3::new(l.x, 0.0, l.z)],
    };
    let p = params(1.0, 1.0);
    let set = atoms(&frame.positions, &radii);
    let out = PeriodicEngine::new()
        .compute_triclinic(&set, &p, &cell, Replicate::default())
        .unwrap();
    let found = measure::cavities_of(&out, &set, &p, &no_minimum()).unwrap();
    assert_fills_cell(&found, &out, cell.signed_volume().abs());
    // The same voids as the rectangular box's, to the sampling on other axes.
    let square = surface(&frame.positions, &radii, &p, &pbox, Replicate::default());
    let voids = |c: &[measure::Cavity]| c.iter().map(|c| c.volume).sum::<f64>();
    let rect = voids(&measure::cavities_of(&square, &set, &p, &no_minimum()).unwrap());
    assert!(
        (voids(&found) - rect).abs() < 0.1 * rect,
        "{} against {rect}",
        voids(&found)
    );
}

#[test]
fn a_cavity_keeps_its_id_as_the_liquid_carries_it_across_a_face() {
    let (radii, frame, pbox) = load(ARGON);
    let p = params(1.0, 1.0);
    let step = PeriodicGrid::new(&pbox, pbox.samples(p.spacing)).spacing.x;
    let mut tracker = CavityTracker::new();
    let mut crossed = false;
    let mut first_id = None;
    for k in 0..8 {
        let positions = shifted(&frame.positions, Vec3::X * step * k as f32, pbox.lengths);
        let out = surface(&positions, &radii, &p, &pbox, Replicate::default());
        // Cavities whose bounding radius is over the step (smaller ones move by more than their
        // size each frame, and tracking gives them new ids wherever they are).
        let options = CavityOptions {
            min_volume: 5.0,
            ..CavityOptions::default()
        };
        let found =
            measure::cavities_of(&out, &atoms(&positions, &radii), &p, &options).expect("cavities");
        assert!(found.len() >= 5 && found.iter().all(|c| c.radius > f64::from(step)));
        let update = tracker.update(k, &found);
        if k > 0 {
            assert!(update.events.is_empty(), "frame {k}: {:?}", update.events);
        }
        // The largest cavity (centroid 4 Å from the +x face at first) is carried across it.
        let largest = &update.cavities[0];
        first_id.get_or_insert(largest.id);
        assert_eq!(Some(largest.id), first_id, "frame {k}");
        crossed |= largest.cavity.centroid.x < pbox.origin.x as f64 + l_half(&pbox);
    }
    assert!(crossed, "the largest cavity never crossed the face");
}

fn l_half(pbox: &PeriodicBox) -> f64 {
    0.5 * pbox.lengths.x as f64
}

#[test]
fn cli_measures_periodic_cavities_residues_and_interfaces_and_refuses_the_probes() {
    let dir = tempfile::tempdir().unwrap();
    let path = |name: &str| dir.path().join(name).display().to_string();
    let (argon, bilayer) = (data(ARGON), data(BILAYER));
    let (argon, bilayer) = (argon.display().to_string(), bilayer.display().to_string());
    let run = mdsurf(
        dir.path(),
        &[
            "surface",
            &argon,
            "--frames",
            "0:2",
            "--periodic",
            "--cavities",
            &path("c.csv"),
        ],
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    let cavities = Csv::read(&dir.path().join("c.csv"));
    assert!(cavities.rows.len() >= 10);
    assert!(
        cavities
            .text_col("lining")
            .iter()
            .all(|l| l.starts_with("Ar"))
    );
    // The interface between the two lipids: its complex is the periodic surface of both.
    let both = "resname DPPC CHOL";
    let run = mdsurf(
        dir.path(),
        &[
            "surface",
            &bilayer,
            "--periodic",
            "--select",
            both,
            "--stats",
            &path("s.csv"),
            "--per-residue",
            &path("r.csv"),
            "--interface",
            "resname DPPC",
            "resname CHOL",
            "--interface-csv",
            &path("i.csv"),
        ],
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    let stats = Csv::read(&dir.path().join("s.csv"));
    let rows = Csv::read(&dir.path().join("i.csv"));
    let (area, together) = (stats.col("area_A2")[0], rows.col("area_ab_A2")[0]);
    assert!((area - together).abs() < 1e-3, "{area} against {together}");
    assert!(rows.col("buried_A2")[0] > 1000.0);
    let residues = Csv::read(&dir.path().join("r.csv")).col("area_A2");
    assert_eq!(residues.len(), 450);
    assert!((residues.iter().sum::<f64>() - area).abs() < 0.01 * residues.len() as f64);
    for extra in [
        [
            "--interface",
            "resname DPPC",
            "resname CHOL",
            "--interface-probe",
            "1.4",
        ]
        .as_slice(),
        ["--cavities", "x.csv", "--cavity-probe", "1.4"].as_slice(),
    ] {
        let mut args = vec!["surface", bilayer.as_str(), "--periodic"];
        args.extend_from_slice(extra);
        let run = mdsurf(dir.path(), &args);
        assert_ne!(run.code, 0);
        assert!(run.last_line().contains("periodic"), "{}", run.stderr);
        assert_eq!(run.stderr.trim().lines().count(), 1, "{}", run.stderr);
    }
}

#[test]
fn the_windows_cavities_of_a_periodic_surface_have_walls_and_refuse_the_probe() {
    let (radii, frame, pbox) = load(ARGON);
    let p = params(1.0, 1.0);
    let out = surface(&frame.positions, &radii, &p, &pbox, Replicate::default());
    let t = mdsurf::io::open(&data(ARGON), None).expect("open");
    let set = atoms(&frame.positions, &radii);
    let mut source = CavitySource {
        subset: None,
        beads: false,
        probe: None,
    };
    let seams = out.periodic.as_deref();
    let layer = find_cavities(t.topology(), &source, (&out.mesh, seams), &set, &p).unwrap();
    // The window keeps cavities of 1 Å³ or more.
    let options = CavityOptions {
        min_volume: 1.0,
        ..CavityOptions::default()
    };
    let table = measure::cavities_of(&out, &set, &p, &options).unwrap();
    assert_eq!(layer.cavities, table);
    // Each wall is its cavity's sheet: its triangles' area is the cavity's.
    assert_eq!(layer.wall_vertices.len(), table.len());
    let wall_area: f64 = layer.mesh.area();
    let areas: f64 = table.iter().map(|c| c.area).sum();
    assert!(
        (wall_area - areas).abs() < 1e-6 * areas,
        "{wall_area} against {areas}"
    );
    source.probe = Some(1.4);
    let refused = find_cavities(t.topology(), &source, (&out.mesh, seams), &set, &p);
    let Err(refusal) = refused else {
        panic!("a probe on a periodic surface was not refused")
    };
    let message = refusal.to_string();
    assert!(message.contains("periodic"), "{message}");
}

#[test]
fn exposure_tables_make_residues_split_by_a_face_whole() {
    use mdsurf::measure::ExposureTable;
    use mdsurf::model::pbc::PbcCell;
    use mdsurf::surface::CpuEngine;

    let opened = mdsurf::io::open(&data(BILAYER), None).expect("bilayer");
    let top = opened.topology().clone();
    let (radii, frame, pbox) = load(BILAYER);
    let cell = PbcCell::of(&frame).expect("the bilayer's box");
    // Move the box so that a face cuts the first lipid and the first cholesterol through
    // their middles, as a trajectory written without whole molecules has them.
    let centre_of = |name: &str| {
        let first = top
            .residue_names
            .iter()
            .position(|n| n.trim() == name)
            .unwrap();
        let residue = top.residue_index[first];
        let members: Vec<Vec3> = (0..top.len())
            .filter(|&i| top.residue_index[i] == residue)
            .map(|i| frame.positions[i])
            .collect();
        members.iter().sum::<Vec3>() / members.len() as f32
    };
    let (dppc, chol) = (centre_of("DPPC"), centre_of("CHOL"));
    let shift = Vec3::new(-dppc.x, -dppc.y, -chol.z);
    let split = shifted(&frame.positions, shift, pbox.lengths);
    let p = SurfaceParams::default();
    let table = |positions: &[Vec3], cell: Option<&PbcCell>| {
        ExposureTable::from_isolated_residues(
            &mut CpuEngine::new(),
            &top,
            None,
            &atoms(positions, &radii),
            cell,
            &p,
        )
        .expect("exposure table")
    };
    let whole = table(&frame.positions, Some(&cell));
    let made_whole = table(&split, Some(&cell));
    let in_pieces = table(&split, None);
    for name in ["DPPC", "CHOL"] {
        let reference = whole.max_area(name).unwrap();
        let (a, b) = (
            made_whole.max_area(name).unwrap(),
            in_pieces.max_area(name).unwrap(),
        );
        println!("{name}: whole {reference:.1} Å², split and made whole {a:.1}, in pieces {b:.1}");
        // The grid lies differently about the moved residue: a few tenths of a per cent.
        assert!(
            (a / reference - 1.0).abs() < 0.01,
            "{name}: {a} against {reference}"
        );
    }
    // Without the box the split lipid counts as pieces, each with its own surface.
    let dppc_pieces = in_pieces.max_area("DPPC").unwrap() / whole.max_area("DPPC").unwrap();
    assert!(
        dppc_pieces > 1.05,
        "pieces {dppc_pieces} of the whole lipid's area"
    );
}
