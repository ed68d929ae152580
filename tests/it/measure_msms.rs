//! mdsurf's buried interface area and cavities under `--preset ses` against MSMS 2.6.1's
//! analytical solvent-excluded surface (issue 32): `tests/data/msms_interface.csv` and
//! `tests/data/msms_cavities.csv`, written by `scripts/measure_reference.py` on the same atoms
//! (the `protein` selection; Bondi radii and a 1.4 Å probe on MSMS's side). The numbers and
//! what they mean are in docs/measure.md ("Against MSMS").

use std::collections::HashMap;

use glam::{DVec3, Vec3};
use mdsurf::measure::{
    Cavity, CavityOptions, ProbeOptions, cavities, interface, interface_with, ses_probe_interface,
};
use mdsurf::surface::{AtomSet, CpuEngine, Preset, SurfaceEngine, SurfaceParams, VertexMode};

use crate::cli_common::{Csv, mdsurf};
use crate::data_support::DATA;
use crate::measure_areas::selected_atoms;

/// Positions and `--preset ses` radii (Å; exposure applied over the selected atoms, as the
/// command line does for each side of `--interface`) of `selection`'s atoms in the first frame
/// of `file`.
fn ses_atoms(file: &str, selection: &str) -> (Vec<Vec3>, Vec<f32>) {
    let (_, _, positions, radii) = selected_atoms(file, selection, Some(Preset::Ses));
    (positions, radii)
}

fn set<'a>(positions: &'a [Vec3], radii: &'a [f32]) -> AtomSet<'a> {
    AtomSet {
        positions,
        radii,
        colours: None,
    }
}

/// Rows of a reference CSV (`tests/data/NAME`) as fields, the header left out.
fn rows(name: &str) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(format!("{DATA}{name}"))
        .unwrap_or_else(|e| panic!("tests/data/{name}: {e} (scripts/measure_reference.py)"));
    text.lines()
        .skip(1)
        .map(|l| l.split(',').map(str::to_owned).collect())
        .collect()
}

fn num(text: &str) -> f64 {
    text.parse().expect("number")
}

/// The preset's radii (Å) of the atoms of `(sel_a) or (sel_b)` in `file`, by topology index:
/// each atom's neighbours counted over both selections together.
fn radii_in_complex(file: &str, sel_a: &str, sel_b: &str) -> HashMap<u32, f32> {
    let both = format!("({sel_a}) or ({sel_b})");
    let (_, indices, _, radii) = selected_atoms(file, &both, Some(Preset::Ses));
    indices.into_iter().zip(radii).collect()
}

/// The `external` row of `complex` in `tests/data/msms_interface.csv`.
fn interface_row(complex: &str) -> Vec<String> {
    rows("msms_interface.csv")
        .into_iter()
        .find(|r| r[0] == complex && r[6] == "external")
        .unwrap_or_else(|| panic!("no row for {complex}"))
}

/// MSMS's buried SES area of `complex` (Å², the external surface: MSMS's default, what the
/// preset was fitted to), mdsurf's under `--preset ses` with `vertices` on the same sides, and
/// mdsurf's deviation from MSMS in %.
fn buried_against_msms(complex: &str, vertices: VertexMode) -> (f64, f64, f64) {
    let row = interface_row(complex);
    let (_, ia, a, ra) = selected_atoms(&row[1], &row[2], Some(Preset::Ses));
    let (_, ib, b, rb) = selected_atoms(&row[1], &row[3], Some(Preset::Ses));
    assert_eq!(
        (a.len(), b.len()),
        (num(&row[4]) as usize, num(&row[5]) as usize),
        "{complex}: not MSMS's atoms"
    );
    // The complex's radii count each atom's neighbours over the complex, as `--interface` does.
    let in_complex = radii_in_complex(&row[1], &row[2], &row[3]);
    let complex_radii: Vec<f32> = ia.iter().chain(&ib).map(|i| in_complex[i]).collect();
    let params = Preset::Ses.apply(SurfaceParams::default());
    let mut engine = CpuEngine::new().with_vertices(vertices);
    let r = interface_with(
        &mut engine,
        &set(&a, &ra),
        &set(&b, &rb),
        Some(&complex_radii),
        &params,
        true,
    )
    .expect("interface");
    let msms = num(&row[10]);
    let dev = 100.0 * (r.buried / msms - 1.0);
    eprintln!(
        "{complex} ({} / {}): buried {:.1} Å² (A {:.1}, B {:.1}, A+B {:.1}) vs MSMS {msms:.1} Å² \
         (A {}, B {}, A+B {}): {dev:+.2} %",
        row[2], row[3], r.buried, r.area_a, r.area_b, r.area_complex, row[7], row[8], row[9]
    );
    (msms, r.buried, dev)
}

/// The protease dimer's large interface (about 1,200 Å²): within the 5 %.
#[test]
fn measure_msms_buried_area_of_1hpv_within_5_percent() {
    let (_, _, dev) = buried_against_msms("1hpv", Preset::Ses.vertices());
    assert!(dev.abs() <= 5.0, "1hpv: {dev:+.2} %");
}

/// The two small interfaces (300 to 400 Å², under 2 % of the complex's area) miss the issue's
/// 5 %: mdsurf buries 20 % more than MSMS on 7ddo and 11 % more on 1a28 (80 and 34 Å²), on
/// the atoms in contact with the other side (3 to 5 Å from it); none of the preset's values
/// tried (R, I, radii, exposure counts and weight, and a search over them) brings them and 1hpv
/// within 5 % while whole proteins keep 2 % (docs/measure.md, "Where the small interfaces'
/// excess comes from"). This test holds them to what they meet: 25 %.
#[test]
fn measure_msms_buried_area_of_7ddo_and_1a28_within_25_percent() {
    for complex in ["7ddo", "1a28"] {
        let (_, _, dev) = buried_against_msms(complex, Preset::Ses.vertices());
        assert!(dev.abs() <= 25.0, "{complex}: {dev:+.2} %");
    }
}

/// The exposure counts do not make the small interfaces' excess: the complex's surface with
/// its radii counted over the complex (as `--select` of both sides and `--interface` give it)
/// instead of over each side alone (as `--interface` fed it before 2026-11-29) moves the buried
/// area by at most 2 % (measured: -0.9 % on 7ddo, -0.06 % on 1a28), against the 11 to 20 % by
/// which it exceeds MSMS's.
#[test]
fn measure_msms_small_interfaces_hardly_move_with_the_exposure_counts() {
    for complex in ["7ddo", "1a28"] {
        let row = interface_row(complex);
        let (_, ia, a, ra) = selected_atoms(&row[1], &row[2], Some(Preset::Ses));
        let (_, ib, b, rb) = selected_atoms(&row[1], &row[3], Some(Preset::Ses));
        let in_complex = radii_in_complex(&row[1], &row[2], &row[3]);
        assert_eq!(
            in_complex.len(),
            ia.len() + ib.len(),
            "{complex}: sides overlap"
        );
        let counted_over_complex =
            |idx: &[u32]| -> Vec<f32> { idx.iter().map(|i| in_complex[i]).collect() };
        let (rca, rcb) = (counted_over_complex(&ia), counted_over_complex(&ib));
        assert!(
            rca.iter().zip(&ra).any(|(c, s)| c > s),
            "{complex}: no radius grows in the complex"
        );
        let params = Preset::Ses.apply(SurfaceParams::default());
        let mut engine = CpuEngine::new().with_vertices(Preset::Ses.vertices());
        let own = interface(&mut engine, &set(&a, &ra), &set(&b, &rb), &params).expect("sides");
        let counted =
            interface(&mut engine, &set(&a, &rca), &set(&b, &rcb), &params).expect("complex");
        let buried = 0.5 * (own.area_a + own.area_b - counted.area_complex);
        let change = 100.0 * (buried / own.buried - 1.0);
        eprintln!(
            "{complex}: buried {:.1} Å² with each side's counts, {buried:.1} Å² with the \
             complex's counts for the complex ({change:+.2} %); MSMS {}",
            own.buried, row[10]
        );
        assert!(change.abs() <= 2.0, "{complex}: {change:+.2} %");
    }
}

/// `mdsurf surface --preset ses --interface` computes the interface with the preset's radii and
/// vertices (refined unless `--vertices` says otherwise), not mdsurf's default radii and the CPU
/// engine's interpolated vertices: its buried area is the library's, and its complex the
/// surface `--select` shows of both sides.
#[test]
fn measure_msms_cli_interface_follows_the_preset_vertices() {
    let dir = tempfile::tempdir().expect("tempdir");
    let pdb = crate::cli_common::data("1hpv.pdb");
    for (flags, mode) in [
        (&["--preset", "ses"][..], VertexMode::Refined),
        (
            &["--preset", "ses", "--vertices", "interpolated"][..],
            VertexMode::Interpolated,
        ),
    ] {
        let mut args = vec![
            "surface",
            pdb.as_str(),
            "--select",
            "protein",
            "--backend",
            "cpu",
            "--interface",
            "protein and chain A",
            "protein and chain B",
            "--interface-csv",
            "i.csv",
            "--stats",
            "s.csv",
        ];
        args.extend_from_slice(flags);
        let run = mdsurf(dir.path(), &args);
        assert_eq!(run.code, 0, "{}", run.stderr);
        let cli = Csv::read(&dir.path().join("i.csv")).col("buried_A2")[0];
        // The complex is the surface of both chains as `--select protein` shows it: the same
        // radii (the preset's exposure counted over the complex), the same area.
        let complex = Csv::read(&dir.path().join("i.csv")).col("area_ab_A2")[0];
        let shown = Csv::read(&dir.path().join("s.csv")).col("area_A2")[0];
        assert!((complex - shown).abs() < 0.01, "{complex} vs {shown}");
        let (_, library, _) = buried_against_msms("1hpv", mode);
        eprintln!("{flags:?}: command line {cli:.2} Å², library {library:.2} Å²");
        assert!(
            (cli - library).abs() <= 1e-3 * library,
            "{flags:?}: {cli} vs {library}"
        );
    }
}

/// An MSMS cavity: its number, volume (Å³) and the centroid of the volume it encloses (Å).
struct MsmsCavity {
    number: usize,
    volume: f64,
    centroid: DVec3,
}

/// MSMS's cavities of `protein` and mdsurf's (every one, largest first) under `--preset ses`.
fn cavities_against_msms(protein: &str) -> (Vec<MsmsCavity>, Vec<Cavity>) {
    let reference: Vec<MsmsCavity> = rows("msms_cavities.csv")
        .iter()
        .filter(|r| r[0] == protein)
        .map(|r| MsmsCavity {
            number: num(&r[4]) as usize,
            volume: num(&r[5]),
            centroid: DVec3::new(num(&r[7]), num(&r[8]), num(&r[9])),
        })
        .collect();
    let row = rows("msms_cavities.csv")
        .into_iter()
        .find(|r| r[0] == protein)
        .unwrap_or_else(|| panic!("no rows for {protein}"));
    let (pos, radii) = ses_atoms(&row[1], &row[2]);
    assert_eq!(
        pos.len(),
        num(&row[3]) as usize,
        "{protein}: not MSMS's atoms"
    );
    let atoms = set(&pos, &radii);
    let params = Preset::Ses.apply(SurfaceParams::default());
    let mut engine = CpuEngine::new().with_vertices(Preset::Ses.vertices());
    let out = engine.compute(&atoms, &params).expect("surface");
    let found = cavities(&out.mesh, &atoms, &params, &CavityOptions::default()).expect("cavities");
    (reference, found)
}

/// Distance (Å) from `point` to the nearest of `centroids`.
fn nearest(point: DVec3, centroids: impl Iterator<Item = DVec3>) -> f64 {
    centroids
        .map(|c| c.distance(point))
        .fold(f64::INFINITY, f64::min)
}

/// A cavity counts as found when the two centroids are within this distance (Å; the issue's).
const CENTROID_TOLERANCE: f64 = 2.0;
/// The smallest MSMS cavity looked for (Å³): a void that holds a 1.4 Å probe has about 11.5 Å³
/// of SES volume, so 10 Å³ keeps every void a water fits in.
const MSMS_MIN_VOLUME: f64 = 10.0;

/// The issue asks that every MSMS cavity above a stated volume be found; the Gaussian
/// surface's voids miss that badly (`--cavity-probe` meets it: `measure_probe_cavities`) (no probe: most probe-sized voids connect to the outside
/// through gaps a water cannot pass, or close). What it meets: of the MSMS cavities of at
/// least 10 Å³, at least a third have an mdsurf cavity within 2 Å (measured: 16 of 41 on 1a28,
/// 71 of 199 on 6msm's chain A).
#[test]
fn measure_msms_cavities_over_10_a3_found_in_part() {
    for (protein, share) in [("1a28", 1.0 / 3.0), ("6msm_A", 1.0 / 3.0)] {
        let (reference, found) = cavities_against_msms(protein);
        let big: Vec<&MsmsCavity> = reference
            .iter()
            .filter(|c| c.volume >= MSMS_MIN_VOLUME)
            .collect();
        let mut hits = 0;
        for c in &big {
            let d = nearest(c.centroid, found.iter().map(|f| f.centroid));
            let matched = found.iter().find(|f| f.centroid.distance(c.centroid) == d);
            if d <= CENTROID_TOLERANCE {
                hits += 1;
            }
            eprintln!(
                "{protein} MSMS cavity {} {:.1} Å³: nearest mdsurf cavity {d:.2} Å away ({:.1} \
                 Å³){}",
                c.number,
                c.volume,
                matched.map_or(0.0, |f| f.volume),
                if d <= CENTROID_TOLERANCE {
                    " found"
                } else {
                    ""
                }
            );
        }
        eprintln!(
            "{protein}: {hits} of {} MSMS cavities of at least {MSMS_MIN_VOLUME} Å³ found within \
             {CENTROID_TOLERANCE} Å ({} mdsurf cavities)",
            big.len(),
            found.len()
        );
        assert!(
            hits as f64 >= share * big.len() as f64,
            "{protein}: {hits} of {}",
            big.len()
        );
    }
}

/// The other direction: at least two thirds of mdsurf's cavities of at least 1 Å³ have an MSMS
/// cavity (of any size) within 2 Å (measured: 10 of 14 on 1a28, 50 of 58 on 6msm's chain A).
/// Not all do: a Gaussian surface also encloses voids too small or too narrow for MSMS's
/// probe, and pieces of MSMS cavities it does not enclose whole.
#[test]
fn measure_msms_cavities_of_mdsurf_mostly_msms_cavities() {
    for (protein, share) in [("1a28", 2.0 / 3.0), ("6msm_A", 2.0 / 3.0)] {
        let (reference, found) = cavities_against_msms(protein);
        let ours: Vec<&Cavity> = found.iter().filter(|f| f.volume >= 1.0).collect();
        let mut hits = 0;
        for f in &ours {
            let d = nearest(f.centroid, reference.iter().map(|c| c.centroid));
            if d <= CENTROID_TOLERANCE {
                hits += 1;
            }
            eprintln!(
                "{protein} mdsurf cavity {:.1} Å³ at {:.2?}: nearest MSMS cavity {d:.2} Å away",
                f.volume, f.centroid
            );
        }
        eprintln!(
            "{protein}: {hits} of {} mdsurf cavities of at least 1 Å³ have an MSMS cavity within \
             {CENTROID_TOLERANCE} Å",
            ours.len()
        );
        assert!(
            hits as f64 >= share * ours.len() as f64,
            "{protein}: {hits} of {}",
            ours.len()
        );
    }
}

/// MSMS's buried SES area of `complex` and mdsurf's on the probe's SES (Bondi radii, a 1.4 Å
/// probe: `--interface-probe 1.4`), with mdsurf's deviation in %.
fn probe_buried_against_msms(complex: &str) -> (f64, f64, f64) {
    let row = interface_row(complex);
    let (top, ia, a, ra) = selected_atoms(&row[1], &row[2], None);
    let (_, ib, b, rb) = selected_atoms(&row[1], &row[3], None);
    let options = ProbeOptions::default();
    let started = std::time::Instant::now();
    let r = ses_probe_interface(
        &top,
        (Some(&ia), &set(&a, &ra)),
        (Some(&ib), &set(&b, &rb)),
        &options,
    )
    .expect("probe interface");
    let msms = num(&row[10]);
    let dev = 100.0 * (r.buried / msms - 1.0);
    eprintln!(
        "{complex} probe: buried {:.1} Å² (A {:.1}, B {:.1}, A+B {:.1}) vs MSMS {msms:.1} Å² \
         (A {}, B {}, A+B {}): {dev:+.2} % in {:.1} s",
        r.buried,
        r.area_a,
        r.area_b,
        r.area_complex,
        row[7],
        row[8],
        row[9],
        started.elapsed().as_secs_f64()
    );
    (msms, r.buried, dev)
}

/// On the probe's own SES the three interfaces, large and small, bury what MSMS's do to
/// within the 5 %.
#[test]
fn measure_msms_probe_buried_area_within_5_percent() {
    for complex in ["1hpv", "7ddo", "1a28"] {
        let (msms, ours, dev) = probe_buried_against_msms(complex);
        assert!(
            dev.abs() <= 5.0,
            "{complex}: {ours:.1} against {msms:.1} ({dev:+.2} %)"
        );
    }
}

/// `mdsurf surface --interface A B --interface-probe 1.4` writes the library's probe interface
/// (1hpv within 5 % of MSMS) with its contact residues; a probe radius out of range or the
/// flag without `--interface` is refused in one line.
#[test]
fn measure_msms_cli_interface_probe_is_the_librarys() {
    let dir = tempfile::tempdir().expect("tempdir");
    let pdb = crate::cli_common::data("1hpv.pdb");
    let args = |probe: &'static str| {
        vec![
            "surface",
            pdb.as_str(),
            "--select",
            "protein",
            "--backend",
            "cpu",
            "--interface",
            "protein and chain A",
            "protein and chain B",
            "--interface-csv",
            "i.csv",
            "--interface-probe",
            probe,
        ]
    };
    let run = mdsurf(dir.path(), &args("1.4"));
    assert_eq!(run.code, 0, "{}", run.stderr);
    let csv = Csv::read(&dir.path().join("i.csv"));
    let (msms, library, _) = probe_buried_against_msms("1hpv");
    let cli = csv.col("buried_A2")[0];
    assert!(
        (cli - library).abs() <= 1e-3 * library,
        "{cli} vs {library}"
    );
    assert!((cli / msms - 1.0).abs() <= 0.05, "{cli} vs MSMS {msms}");
    let contacts = csv.text_col("contacts_a")[0].clone();
    assert!(contacts.split(' ').count() > 10, "{contacts}");
    for bad in ["0", "11", "nan"] {
        let run = mdsurf(dir.path(), &args(bad));
        assert_eq!(run.code, 2, "{bad}: {}", run.stderr);
        assert!(run.stderr.contains("--interface-probe"), "{}", run.stderr);
        assert_eq!(run.stderr.trim().lines().count(), 1, "{}", run.stderr);
    }
    let run = mdsurf(dir.path(), &["surface", &pdb, "--interface-probe", "1.4"]);
    assert_eq!(run.code, 2, "{}", run.stderr);
    assert!(run.stderr.contains("--interface"), "{}", run.stderr);
}
