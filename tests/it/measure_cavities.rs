//! Cavities of a surface and their tracking over frames (issue 32, `src/measure`), on a
//! synthetic hollow shell of atoms whose void's volume is known independently.

use glam::{DVec3, Vec3};
use mdsurf::measure::{
    Cavity, CavityCsv, CavityEvent, CavityOptions, CavityTracker, cavities, components,
};
use mdsurf::model::Topology;
use mdsurf::surface::{AtomSet, CpuEngine, SurfaceEngine, SurfaceParams};

/// `n` points spread evenly on a sphere of radius `radius` (Å) around `centre` (Fibonacci).
pub(crate) fn shell(n: usize, radius: f32, centre: Vec3) -> Vec<Vec3> {
    mdsurf::synthetic::sphere_points(n, radius, centre)
}

/// The shell's atoms: 600 of radius 1.5 Å on a sphere of 7 Å (about 1 Å apart, so their
/// Gaussians close the wall).
const SHELL_ATOMS: usize = 600;
const SHELL_RADIUS: f32 = 7.0;
const ATOM_RADIUS: f32 = 1.5;

fn params() -> SurfaceParams {
    SurfaceParams {
        spacing: 0.25,
        ..SurfaceParams::default()
    }
}

fn set<'a>(positions: &'a [Vec3], radii: &'a [f32]) -> AtomSet<'a> {
    AtomSet {
        positions,
        radii,
        colours: None,
    }
}

/// The density of DESIGN section 2 at `x`, in f64.
fn density(atoms: &[Vec3], alpha: f64, q: f64, x: DVec3) -> f64 {
    atoms
        .iter()
        .map(|p| x.distance_squared(p.as_dvec3()))
        .filter(|&d2| d2 < (q * alpha).powi(2))
        .map(|d2| (-d2 / (2.0 * alpha * alpha)).exp())
        .sum()
}

/// Volume (Å³) of the void of the shell around `centre`, from the exact density: the void is
/// star-shaped around the centre, so its volume is the mean over directions of `r(u)^3` times
/// `4 pi / 3`, where `r(u)` is the first radius along `u` at which the density reaches I
/// (bisection to 1e-6 Å); 4,000 directions spread evenly (Fibonacci).
fn void_volume(atoms: &[Vec3], centre: Vec3, p: &SurfaceParams) -> f64 {
    let alpha = f64::from(ATOM_RADIUS * p.radius_scale);
    let q = f64::from(p.cutoff());
    let iso = f64::from(p.isovalue);
    let c = centre.as_dvec3();
    let dirs = shell(4000, 1.0, Vec3::ZERO);
    let mean: f64 = dirs
        .iter()
        .map(|u| {
            let u = u.as_dvec3().normalize();
            let (mut lo, mut hi) = (0.0f64, f64::from(SHELL_RADIUS));
            assert!(
                density(atoms, alpha, q, c) < iso && density(atoms, alpha, q, c + hi * u) > iso
            );
            while hi - lo > 1e-6 {
                let mid = 0.5 * (lo + hi);
                if density(atoms, alpha, q, c + mid * u) < iso {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            (0.5 * (lo + hi)).powi(3)
        })
        .sum::<f64>()
        / dirs.len() as f64;
    4.0 / 3.0 * std::f64::consts::PI * mean
}

fn shell_cavities(positions: &[Vec3], radii: &[f32]) -> Vec<Cavity> {
    let p = params();
    let atoms = set(positions, radii);
    let out = CpuEngine::new().compute(&atoms, &p).expect("surface");
    cavities(&out.mesh, &atoms, &p, &CavityOptions::default()).expect("cavities")
}

#[test]
fn measure_hollow_shell_has_one_cavity_of_the_right_volume() {
    let centre = Vec3::new(1.0, -2.0, 0.5);
    let positions = shell(SHELL_ATOMS, SHELL_RADIUS, centre);
    let radii = vec![ATOM_RADIUS; positions.len()];
    let p = params();
    let atoms = set(&positions, &radii);
    let out = CpuEngine::new().compute(&atoms, &p).expect("surface");
    let parts = components(&out.mesh).expect("components");
    assert_eq!(parts.len(), 2, "outer wall and void");
    assert!(parts[0].volume > 0.0 && parts[1].volume < 0.0);
    let found = cavities(&out.mesh, &atoms, &p, &CavityOptions::default()).expect("cavities");
    assert_eq!(found.len(), 1);
    let cavity = &found[0];
    let reference = void_volume(&positions, centre, &p);
    let dev = cavity.volume / reference - 1.0;
    eprintln!(
        "shell void: {:.1} Å³ measured, {reference:.1} Å³ from the exact density ({:+.2} %)",
        cavity.volume,
        100.0 * dev
    );
    assert!(
        dev.abs() < 0.02,
        "{:.1} vs {reference:.1} Å³",
        cavity.volume
    );
    assert!(cavity.centroid.distance(centre.as_dvec3()) < 0.05);
    assert!(cavity.area > 0.0 && cavity.radius < f64::from(SHELL_RADIUS));
    // Every shell atom faces the void; the lining is most of them.
    assert!(
        cavity.lining_atoms.len() > SHELL_ATOMS / 2,
        "{} lining atoms",
        cavity.lining_atoms.len()
    );
    // A minimum volume above the void's leaves it out.
    let options = CavityOptions {
        min_volume: cavity.volume * 1.01,
        ..CavityOptions::default()
    };
    assert!(
        cavities(&out.mesh, &atoms, &p, &options)
            .expect("ok")
            .is_empty()
    );
    let bad = CavityOptions {
        min_volume: f64::NAN,
        ..CavityOptions::default()
    };
    assert!(cavities(&out.mesh, &atoms, &p, &bad).is_err());
}

#[test]
fn measure_cavity_keeps_its_id_when_moved_and_dies_when_filled() {
    let radii = vec![ATOM_RADIUS; SHELL_ATOMS];
    let mut tracker = CavityTracker::new();
    let first = shell_cavities(&shell(SHELL_ATOMS, SHELL_RADIUS, Vec3::ZERO), &radii);
    let t0 = tracker.update(0, &first);
    assert_eq!(t0.cavities.len(), 1);
    let id = t0.cavities[0].id;
    assert_eq!(t0.events, vec![CavityEvent::Birth { id }]);

    let moved = shell_cavities(
        &shell(SHELL_ATOMS, SHELL_RADIUS, Vec3::new(0.6, -0.4, 0.3)),
        &radii,
    );
    let t1 = tracker.update(1, &moved);
    assert_eq!(t1.cavities.len(), 1);
    assert_eq!(t1.cavities[0].id, id, "same cavity, moved 0.8 Å");
    assert_eq!(t1.cavities[0].born, 0);
    assert!(t1.events.is_empty(), "{:?}", t1.events);

    // An atom of radius 4 Å in the middle fills the void.
    let mut filled = shell(SHELL_ATOMS, SHELL_RADIUS, Vec3::new(0.6, -0.4, 0.3));
    filled.push(Vec3::new(0.6, -0.4, 0.3));
    let mut filled_radii = radii.clone();
    filled_radii.push(4.0);
    let t2 = tracker.update(2, &shell_cavities(&filled, &filled_radii));
    assert!(t2.cavities.is_empty());
    assert_eq!(t2.events, vec![CavityEvent::Death { id }]);

    // The CSV of a frame with the cavity names its lining residues.
    let mut top = Topology::default();
    for k in 0..SHELL_ATOMS {
        top.names.push("C");
        top.residue_names.push("LEU");
        top.chains.push("A");
        top.residue_ids.push(k as i64 / 10 + 1);
        top.residue_index.push(k as u32 / 10);
    }
    let mut csv = CavityCsv::new();
    csv.push(1, "shell", &top, None, &t1.cavities)
        .expect("rows");
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("cavities.csv");
    csv.write(&path, None).expect("write");
    let text = std::fs::read_to_string(&path).expect("read");
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(
        lines[0],
        "frame,rep,cavity_id,volume_A3,area_A2,cx,cy,cz,lining"
    );
    assert_eq!(lines.len(), 2);
    assert!(
        lines[1].starts_with(&format!("1,shell,{id},")),
        "{}",
        lines[1]
    );
    assert!(lines[1].contains("A:LEU1 A:LEU2 "), "{}", lines[1]);
}

/// A cavity for the tracker alone: volume (Å³), centroid and bounding radius (Å).
fn blob(volume: f64, centre: [f64; 3], radius: f64) -> Cavity {
    Cavity {
        volume,
        area: 0.0,
        centroid: DVec3::from_array(centre),
        radius,
        vertex_count: 0,
        lining_atoms: Vec::new(),
        cell: None,
    }
}

#[test]
fn measure_tracker_reports_merges_and_splits() {
    let mut t = CavityTracker::new();
    let u = t.update(
        0,
        &[blob(10.0, [0.0; 3], 1.0), blob(20.0, [3.0, 0.0, 0.0], 1.0)],
    );
    let (small, big) = (u.cavities[0].id, u.cavities[1].id);
    // One cavity of radius 3 between them: both overlap it; it keeps the larger's id.
    let u = t.update(1, &[blob(40.0, [1.5, 0.0, 0.0], 3.0)]);
    assert_eq!(u.cavities[0].id, big);
    assert_eq!(
        u.events,
        vec![CavityEvent::Merge {
            from: vec![small],
            into: big
        }]
    );
    // It splits again: the larger part keeps the id, the other is new.
    let u = t.update(
        2,
        &[blob(5.0, [0.0; 3], 1.0), blob(30.0, [3.0, 0.0, 0.0], 1.0)],
    );
    assert_eq!(u.cavities[1].id, big);
    let part = u.cavities[0].id;
    assert!(part != big && part != small);
    assert_eq!(
        u.events,
        vec![CavityEvent::Split {
            from: big,
            into: vec![part]
        }]
    );
    // Far away: the old ones die, a new one is born.
    let u = t.update(3, &[blob(5.0, [50.0, 0.0, 0.0], 1.0)]);
    let new = u.cavities[0].id;
    assert_eq!(
        u.events,
        vec![
            CavityEvent::Birth { id: new },
            CavityEvent::Death { id: part },
            CavityEvent::Death { id: big }
        ]
    );
}
