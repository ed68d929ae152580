//! Area per atom and per residue, exposure and buried interface area (issue 32, `src/measure`).

use glam::Vec3;
use mdsurf::measure::{
    AtomCsv, ExposureTable, ResidueCsv, atom_areas, atom_areas_of, contact_residues, interface,
    residue_areas,
};
use mdsurf::model::{ParticleOptions, Particles, Topology};
use mdsurf::selection::Selection;
use mdsurf::surface::{AtomSet, CpuEngine, Preset, SurfaceEngine, SurfaceParams};

use crate::data_support::{DATA, data};
use crate::surface_common::surface;

/// `a` and `b` agree to `rel` of the larger.
fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs())
}

fn set<'a>(positions: &'a [Vec3], radii: &'a [f32]) -> AtomSet<'a> {
    AtomSet {
        positions,
        radii,
        colours: None,
    }
}

/// 1hpv's topology, the indices of `selection`'s atoms, their positions and radii (`preset`'s
/// radius set, exposure applied, or the default radii).
fn hpv(selection: &str, preset: Option<Preset>) -> (Topology, Vec<u32>, Vec<Vec3>, Vec<f32>) {
    selected_atoms("1hpv.pdb", selection, preset)
}

/// The topology of the first frame of `file` (under `tests/data`), the indices of
/// `selection`'s atoms, their positions and radii (`preset`'s radius set with exposure applied
/// over the selected atoms, as the command line does, or the default radii).
pub(crate) fn selected_atoms(
    file: &str,
    selection: &str,
    preset: Option<Preset>,
) -> (Topology, Vec<u32>, Vec<Vec3>, Vec<f32>) {
    let traj = mdsurf::io::open(&data(file), None).expect("open");
    let frame = traj.read_frame(0).expect("frame 0");
    let options = match preset {
        Some(p) => p.radius_set().particle_options(ParticleOptions::default()),
        None => ParticleOptions::default(),
    };
    let idx = Selection::parse(selection)
        .expect("selection")
        .bind(traj.topology())
        .indices(&frame);
    let particles =
        Particles::new_subset(traj.topology(), &frame, &options, Some(&idx)).expect("particles");
    let pos = particles.positions(&frame).expect("positions");
    let radii = particles
        .frame_radii(&pos)
        .unwrap_or_else(|| particles.radii().to_vec());
    (traj.topology().clone(), idx, pos, radii)
}

#[test]
fn measure_one_atom_owns_the_whole_area() {
    let (pos, radii) = ([Vec3::new(0.3, -1.2, 2.0)], [1.6f32]);
    let params = SurfaceParams {
        spacing: 0.5,
        ..SurfaceParams::default()
    };
    let out = surface(&pos, &radii, None, &params);
    let areas = atom_areas(&out.mesh, &set(&pos, &radii), &params).expect("areas");
    assert_eq!(areas.len(), 1);
    assert!(close(areas[0], out.mesh.area(), 1e-12), "{areas:?}");
    assert!(close(areas[0], out.area, 1e-9));
}

#[test]
fn measure_two_symmetric_atoms_get_equal_shares() {
    // Mirror images about x = 0 on a grid that is symmetric too: pad = q alpha + H = 4.25 Å
    // and (2 + 2 pad) / H is whole.
    let pos = [Vec3::new(-1.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0)];
    let radii = [1.5f32; 2];
    let params = SurfaceParams {
        spacing: 0.5,
        ..SurfaceParams::default()
    };
    let out = surface(&pos, &radii, None, &params);
    assert_eq!(out.grid.origin.x, -5.25, "the grid is not symmetric");
    let areas = atom_areas(&out.mesh, &set(&pos, &radii), &params).expect("areas");
    assert!(close(areas[0], areas[1], 1e-6), "{areas:?}");
    assert!(close(areas[0] + areas[1], out.area, 1e-9));
}

#[test]
fn measure_atom_areas_sum_to_the_area_on_1hpv() {
    let (top, idx, pos, radii) = hpv("protein", None);
    let atoms = set(&pos, &radii);
    let params = SurfaceParams::default();
    let out = CpuEngine::new().compute(&atoms, &params).expect("surface");
    let areas = atom_areas(&out.mesh, &atoms, &params).expect("areas");
    let sum: f64 = areas.iter().sum();
    assert!(
        close(sum, out.mesh.area(), 1e-9),
        "{sum} vs {}",
        out.mesh.area()
    );
    assert!(areas.iter().all(|a| *a >= 0.0));
    // Residues: 2 chains of 99, the areas sum to the same total.
    let residues = residue_areas(&top, Some(&idx), &areas).expect("residues");
    assert_eq!(residues.len(), 198);
    assert_eq!(residues.iter().map(|r| r.atoms).sum::<usize>(), idx.len());
    let total: f64 = residues.iter().map(|r| r.area).sum();
    assert!(close(total, out.area, 1e-9));
    assert_eq!(residues[0].names(&top).label(), "A:PRO1");
    assert_eq!(residues[99].names(&top).label(), "B:PRO1");
    // Atoms given in any order give the same residues, in topology order.
    let (rev_idx, rev_areas): (Vec<u32>, Vec<f64>) =
        idx.iter().zip(&areas).rev().map(|(&i, &a)| (i, a)).unzip();
    let reversed = residue_areas(&top, Some(&rev_idx), &rev_areas).expect("residues");
    assert_eq!(reversed.len(), residues.len());
    for (r, s) in reversed.iter().zip(&residues) {
        assert_eq!(
            (r.residue, r.atoms, r.names(&top).label()),
            (s.residue, s.atoms, s.names(&top).label())
        );
        assert!(
            close(r.area, s.area, 1e-12),
            "{} {} {}",
            r.names(&top).label(),
            r.area,
            s.area
        );
    }
    // Wrong lengths and indices are errors, not panics.
    assert!(residue_areas(&top, Some(&idx), &areas[1..]).is_err());
    assert!(residue_areas(&top, Some(&[u32::MAX]), &[1.0]).is_err());

    // Exposure: a residue never has much more area than alone.
    let mut engine = CpuEngine::new();
    let table =
        ExposureTable::from_isolated_residues(&mut engine, &top, Some(&idx), &atoms, None, &params)
            .expect("exposure table");
    assert_eq!(table.entries().count(), 20, "amino acids of 1hpv");
    for r in &residues {
        let names = r.names(&top);
        let e = table
            .exposure(names.resname, r.area)
            .expect("every name has a maximum");
        assert!((0.0..1.3).contains(&e), "{}: exposure {e}", names.label());
    }
    let buried = residues
        .iter()
        .filter(|r| {
            let resname = r.names(&top).resname;
            table.exposure(resname, r.area).unwrap_or(1.0) < 0.05
        })
        .count();
    assert!(buried > 10, "only {buried} residues buried");

    // The CSV tables, written atomically.
    let dir = tempfile::tempdir().expect("tempdir");
    let mut csv = ResidueCsv::new();
    csv.push(0, "protein", &top, &residues, Some(&table));
    csv.push(1, "a, \"b\"", &top, &residues[..1], None);
    let path = dir.path().join("residues.csv");
    csv.write(&path, None).expect("write");
    let text = std::fs::read_to_string(&path).expect("read");
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(
        lines[0],
        "frame,rep,chain,resid,resname,area_A2,exposure,residue"
    );
    assert_eq!(lines.len(), 1 + 198 + 1);
    assert!(lines[1].starts_with("0,protein,A,1,PRO,"), "{}", lines[1]);
    assert!(lines[199].starts_with("1,\"a, \"\"b\"\"\",A,1,PRO,"));
    let first = format!(",,{}", residues[0].residue);
    assert!(lines[199].ends_with(&first), "no exposure without a table");
    let mut atoms_csv = AtomCsv::new();
    atoms_csv
        .push(0, "protein", &top, Some(&idx), &areas)
        .expect("atom rows");
    let path = dir.path().join("atoms.csv");
    // A chunk's part: its header line first, then the table.
    atoms_csv.write(&path, Some("# part")).expect("write");
    let text = std::fs::read_to_string(&path).expect("read");
    assert_eq!(text.lines().count(), 2 + idx.len());
    assert_eq!(text.lines().next(), Some("# part"));
    assert!(
        text.lines()
            .nth(2)
            .expect("row")
            .starts_with("0,protein,1,N,A,1,PRO,")
    );
}

/// Pearson correlation of two equally long series.
fn pearson(x: &[f64], y: &[f64]) -> f64 {
    let n = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for (a, b) in x.iter().zip(y) {
        sxy += (a - mx) * (b - my);
        sxx += (a - mx) * (a - mx);
        syy += (b - my) * (b - my);
    }
    sxy / (sxx * syy).sqrt()
}

/// Per-residue areas of `--preset ses` against MSMS's analytical SES per residue
/// (`tests/data/1hpv_residue_ses.csv`, `scripts/measure_reference.py`): Pearson r >= 0.9.
#[test]
fn measure_residue_areas_follow_msms_ses_on_1hpv() {
    let (top, idx, pos, radii) = hpv("protein", Some(Preset::Ses));
    let atoms = set(&pos, &radii);
    let params = Preset::Ses.apply(SurfaceParams::default());
    let mut engine = CpuEngine::new().with_vertices(Preset::Ses.vertices());
    let out = engine.compute(&atoms, &params).expect("surface");
    let measured = engine.vertices().effective(&params);
    let areas = atom_areas_of(&out, &atoms, &measured).expect("areas");
    assert!(close(areas.iter().sum(), out.area, 1e-9));
    let residues = residue_areas(&top, Some(&idx), &areas).expect("residues");
    let text = std::fs::read_to_string(format!("{DATA}1hpv_residue_ses.csv"))
        .expect("tests/data/1hpv_residue_ses.csv (scripts/measure_reference.py writes it)");
    let reference: Vec<(String, i64, String, f64)> = text
        .lines()
        .skip(1)
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            let num = |s: &str| s.parse::<f64>().expect("number");
            (f[0].into(), num(f[1]) as i64, f[2].into(), num(f[3]))
        })
        .collect();
    assert_eq!(reference.len(), residues.len());
    for (r, (chain, resid, name, _)) in residues.iter().zip(&reference) {
        let names = r.names(&top);
        assert_eq!(
            (names.chain, names.resid, names.resname),
            (chain.as_str(), *resid, name.as_str())
        );
    }
    let ours: Vec<f64> = residues.iter().map(|r| r.area).collect();
    let theirs: Vec<f64> = reference.iter().map(|r| r.3).collect();
    let r = pearson(&ours, &theirs);
    eprintln!("1hpv per-residue area vs MSMS SES: Pearson r = {r:.4}");
    assert!(r >= 0.9, "Pearson r = {r:.4}");
}

/// One protein of `tests/data/msms_residue_ses.csv`: its name, file and mdsurf selection, and
/// MSMS's residues in file order (name, SES area in Å²).
struct ReferenceProtein {
    name: String,
    file: String,
    selection: String,
    residues: Vec<(String, f64)>,
}

/// The check on every protein in `tests/data`: per-residue areas of `--preset ses`
/// against MSMS's analytical SES per residue (its atoms' `-af` areas summed;
/// `tests/data/msms_residue_ses.csv`, `scripts/measure_reference.py`), Pearson r >= 0.9 on
/// each of the 20 proteins of `ses_reference.csv` (1hpv's chains alone left out), and the
/// residues' total within 2 % of MSMS's. The residues are matched in file order by name.
#[test]
fn measure_residue_areas_follow_msms_ses_on_every_protein() {
    let text = std::fs::read_to_string(format!("{DATA}msms_residue_ses.csv"))
        .expect("tests/data/msms_residue_ses.csv (scripts/measure_reference.py writes it)");
    let mut proteins: Vec<ReferenceProtein> = Vec::new();
    for line in text.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let area: f64 = f[7].parse().expect("an area");
        if proteins.last().is_none_or(|p| p.name != f[0]) {
            proteins.push(ReferenceProtein {
                name: f[0].into(),
                file: f[1].into(),
                selection: f[2].into(),
                residues: Vec::new(),
            });
        }
        let residues = &mut proteins.last_mut().expect("a protein").residues;
        residues.push((f[6].into(), area));
    }
    assert_eq!(proteins.len(), 20, "proteins in the reference");
    let params = Preset::Ses.apply(SurfaceParams::default());
    let mut engine = CpuEngine::new().with_vertices(Preset::Ses.vertices());
    let measured = engine.vertices().effective(&params);
    let mut misses = Vec::new();
    for ReferenceProtein {
        name,
        file,
        selection,
        residues: reference,
    } in &proteins
    {
        let (top, idx, pos, radii) = selected_atoms(file, selection, Some(Preset::Ses));
        let atoms = set(&pos, &radii);
        let out = engine.compute(&atoms, &params).expect("surface");
        let areas = atom_areas_of(&out, &atoms, &measured).expect("areas");
        let residues = residue_areas(&top, Some(&idx), &areas).expect("residues");
        let names: Vec<&str> = residues.iter().map(|r| r.names(&top).resname).collect();
        let theirs: Vec<&str> = reference.iter().map(|r| r.0.as_str()).collect();
        assert_eq!(names, theirs, "{name}: residues");
        let ours: Vec<f64> = residues.iter().map(|r| r.area).collect();
        let msms: Vec<f64> = reference.iter().map(|r| r.1).collect();
        let r = pearson(&ours, &msms);
        let (total, msms_total) = (ours.iter().sum::<f64>(), msms.iter().sum::<f64>());
        let off = total / msms_total - 1.0;
        eprintln!(
            "{name}: {} residues, Pearson r = {r:.4}, total {total:.1} against {msms_total:.1} Å² \
             ({:+.2} %)",
            ours.len(),
            100.0 * off
        );
        if r < 0.9 || off.abs() > 0.02 {
            misses.push(format!("{name}: r = {r:.4}, total {:+.2} %", 100.0 * off));
        }
    }
    assert!(misses.is_empty(), "{misses:?}");
}

#[test]
fn measure_interface_of_separated_groups_is_zero() {
    let params = SurfaceParams::default();
    let (a_pos, a_rad) = crate::surface_common::cluster(30, 8.0, Vec3::ZERO, 7);
    let (b_pos, b_rad) = crate::surface_common::cluster(25, 8.0, Vec3::new(40.0, 3.0, -2.0), 9);
    let mut engine = CpuEngine::new();
    let r = interface(
        &mut engine,
        &set(&a_pos, &a_rad),
        &set(&b_pos, &b_rad),
        &params,
    )
    .expect("interface");
    assert!(r.buried.abs() < 1e-6, "buried {} Å²", r.buried);
    assert!(r.area_a > 100.0 && r.area_b > 100.0);
    // The engine is back on its own grid.
    let alone = engine.compute(&set(&a_pos, &a_rad), &params).expect("A");
    assert_ne!(alone.grid, r.grid);
    // A forced grid that does not hold B's padded box, or has another spacing, is refused.
    let a_grid = alone.grid;
    assert!(engine.set_grid(Some(a_grid)));
    assert!(engine.compute(&set(&b_pos, &b_rad), &params).is_err());
    let coarse = SurfaceParams {
        spacing: 2.0,
        ..params
    };
    assert!(engine.compute(&set(&a_pos, &a_rad), &coarse).is_err());
    // Forced to its own grid, A's surface is the same.
    let again = engine
        .compute(&set(&a_pos, &a_rad), &params)
        .expect("A forced");
    assert_eq!(again.mesh, alone.mesh);
    engine.set_grid(None);
}

/// Atoms on a cubic lattice of 1.5 Å filling a ball of `radius` Å around `centre`, radius
/// 1.5 Å each: a sphere of atoms.
fn ball(radius: f32, centre: Vec3) -> (Vec<Vec3>, Vec<f32>) {
    let n = (radius / 1.5).floor() as i32;
    let pos: Vec<Vec3> = (-n..=n)
        .flat_map(|i| (-n..=n).flat_map(move |j| (-n..=n).map(move |k| (i, j, k))))
        .map(|(i, j, k)| 1.5 * Vec3::new(i as f32, j as f32, k as f32))
        .filter(|p| p.length() <= radius)
        .map(|p| centre + p)
        .collect();
    let radii = vec![1.5; pos.len()];
    (pos, radii)
}

#[test]
fn measure_interface_of_touching_spheres_is_positive_and_symmetric() {
    let params = SurfaceParams {
        spacing: 0.5,
        ..SurfaceParams::default()
    };
    // Two balls of atoms whose surfaces (about 6.8 Å and 5.3 Å from their centres) touch.
    let (a, ra) = ball(5.0, Vec3::ZERO);
    let (b, rb) = ball(3.5, Vec3::new(11.0, 0.7, -0.4));
    let mut engine = CpuEngine::new();
    let ab = interface(&mut engine, &set(&a, &ra), &set(&b, &rb), &params).expect("A-B");
    let ba = interface(&mut engine, &set(&b, &rb), &set(&a, &ra), &params).expect("B-A");
    eprintln!(
        "touching balls: A {:.2} Å², B {:.2} Å², A with B {:.2} Å², buried {:.3} Å²",
        ab.area_a, ab.area_b, ab.area_complex, ab.buried
    );
    assert!(ab.buried > 10.0, "buried {} Å²", ab.buried);
    assert!(
        close(ab.buried, ba.buried, 1e-6),
        "{} vs {}",
        ab.buried,
        ba.buried
    );
    assert!(close(ab.area_a, ba.area_b, 1e-9));
    let sum = |v: &[f64]| v.iter().sum::<f64>();
    // Each ball loses area; the per-atom sums hold.
    assert!(sum(&ab.atoms_a_complex) < sum(&ab.atoms_a_alone));
    assert!(sum(&ab.atoms_b_complex) < sum(&ab.atoms_b_alone));
    let complex = sum(&ab.atoms_a_complex) + sum(&ab.atoms_b_complex);
    assert!(close(complex, ab.area_complex, 1e-9));
}

#[test]
fn measure_interface_of_the_1hpv_dimer_names_contact_residues() {
    let (top, a_idx, a_pos, a_rad) = hpv("protein and chain A", None);
    let (_, b_idx, b_pos, b_rad) = hpv("protein and chain B", None);
    let mut engine = CpuEngine::new();
    let params = SurfaceParams::default();
    let r = interface(
        &mut engine,
        &set(&a_pos, &a_rad),
        &set(&b_pos, &b_rad),
        &params,
    )
    .expect("interface");
    // The protease dimer buries a large interface (about 2,000 Å² per side in the literature
    // with a probe; a Gaussian surface lands in the same range).
    assert!(
        (800.0..4000.0).contains(&r.buried),
        "buried {} Å²",
        r.buried
    );
    let contacts = contact_residues(&top, Some(&a_idx), Some(&b_idx), &r, 1.0).expect("contacts");
    let count = |side| contacts.iter().filter(|c| c.side == side).count();
    use mdsurf::measure::interface::Side;
    let (na, nb) = (count(Side::A), count(Side::B));
    assert!(na > 10 && nb > 10, "{na} and {nb} contact residues");
    // The dimer is nearly symmetric: as many contacts on each side, within a few.
    assert!(na.abs_diff(nb) <= 6, "{na} vs {nb}");
    assert!(contacts.iter().all(|c| c.buried > 1.0));
    assert!(contact_residues(&top, Some(&a_idx), Some(&b_idx), &r, f64::NAN).is_err());
}

/// OmpK36 (1osm) numbers a loop 163, 163A to 163J in chain A: each residue is its own, and
/// its label carries the insertion code (`A:GLY163C`), so no two residues of a chain share a
/// label.
#[test]
fn measure_labels_carry_insertion_codes() {
    let traj = mdsurf::io::open(&data("1osm.pdb.gz"), None).expect("open");
    let top = traj.topology();
    let mut firsts = Vec::new();
    for a in 0..top.len() {
        if a == 0 || top.residue_index[a] != top.residue_index[a - 1] {
            firsts.push(a);
        }
    }
    let labels: Vec<String> = firsts
        .iter()
        .map(|&a| mdsurf::measure::ResidueNames::of_atom(top, a).label())
        .collect();
    let loop_a: Vec<&str> = labels
        .iter()
        .map(String::as_str)
        .filter(|l| l.starts_with("A:") && l.contains("163"))
        .collect();
    assert_eq!(loop_a.len(), 11, "{loop_a:?}");
    assert!(
        loop_a.contains(&"A:VAL163A") && loop_a.contains(&"A:GLY163J"),
        "{loop_a:?}"
    );
    let distinct: std::collections::BTreeSet<&String> = labels.iter().collect();
    assert_eq!(distinct.len(), labels.len(), "two residues share a label");
    assert!(labels.len() > 150, "{} residues", labels.len());
}
