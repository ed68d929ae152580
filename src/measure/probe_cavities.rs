//! Cavities as the solvent-excluded surface (SES) sees them: voids inside a structure where a
//! probe sphere (1.4 Å for water) fits but which it cannot reach from outside. These are the
//! inner components of an SES program such as MSMS (`-all_components`), and unlike the
//! Gaussian surface's enclosed components ([`super::cavities()`]) they include pockets whose
//! mouth is too narrow for the probe, such as an empty ligand pocket.
//!
//! The rule, on a grid of spacing `h` (Å):
//! 1. A grid point is a free probe centre when it is at least `r_i + probe` from every atom `i`
//!    (`r_i` the atom's radius; Bondi's radii from [`ses_radius`] for SES).
//! 2. Free points connected (26 neighbours) to the grid's border are outside; every other
//!    connected set of free points is one cavity.
//! 3. The cavity's void is the union of probe balls at its free points: its wall is the
//!    isosurface `probe - d(x) = 0` of the distance `d` to the nearest free point, made by
//!    Marching Cubes on the same grid. Volume (Å³), area (Å²) and centroid come from that mesh
//!    as for [`super::Component`]s.
//! 4. An atom lines the cavity when a probe at one of its free points touches it (distance at
//!    most `r_i + probe + h`).
//!
//! A void whose free centres all fit between grid points (a probe that fits only just, about
//! 11.5 Å³ of void) is found by a finer search around the grid's near-free points
//! ([`super::probe_small_voids`]). A pocket that opens to the outside only through a gap
//! narrower than `h` is reported as a cavity.

use glam::{DVec3, Vec3};

use super::MeasureError;
use super::cavities::{Cavity, components};
use super::grid_balls::draw_balls;
use super::grid_flood::{BLOCKED, UNSEEN, flood_outside, label_cavities, neighbours};
use super::probe_small_voids::voids_between_grid_points;
use crate::model::Topology;
use crate::surface::marching_cubes;
use crate::surface::{
    AtomSet, DensityVolume, GridSpec, Mesh, SurfaceError, available_memory_bytes,
};

/// Bondi's van der Waals radius of `element` in Å (the radii SES areas are usually computed
/// with, and MSMS was run with in `tests/data`), for the elements of biomolecules.
pub fn ses_radius(element: &str) -> Option<f32> {
    Some(match element {
        "H" => 1.20,
        "C" => 1.70,
        "N" => 1.55,
        "O" => 1.52,
        "S" => 1.80,
        "P" => 1.80,
        "F" => 1.47,
        "Cl" => 1.75,
        "Se" => 1.90,
        _ => return None,
    })
}

/// The probe cavities of the atoms `atoms` (`atom_indices` into `topology`, or every atom when
/// `None`) with Bondi's radius of each atom's element ([`ses_radius`]), the atom's own radius
/// in `atoms` where Bondi gives none: what `mdsurf surface --cavity-probe` and Python's
/// `Scene.cavities(probe_A=...)` compute.
pub fn ses_probe_cavities(
    topology: &Topology,
    atom_indices: Option<&[u32]>,
    atoms: &AtomSet<'_>,
    options: &ProbeOptions,
) -> Result<Vec<Cavity>, MeasureError> {
    let walls = ses_probe_cavity_walls(topology, atom_indices, atoms, options)?;
    Ok(walls.into_iter().map(|(cavity, _)| cavity).collect())
}

/// [`ses_probe_cavities`] with each cavity's wall: a closed mesh around the void, triangles
/// facing out of it (positions in Å), what the window draws.
pub fn ses_probe_cavity_walls(
    topology: &Topology,
    atom_indices: Option<&[u32]>,
    atoms: &AtomSet<'_>,
    options: &ProbeOptions,
) -> Result<Vec<(Cavity, Mesh)>, MeasureError> {
    let radii = ses_radii(topology, atom_indices, atoms)?;
    let ses_atoms = AtomSet {
        radii: &radii,
        ..*atoms
    };
    probe_cavity_walls(&ses_atoms, options)
}

/// Bondi's radius of each atom of `atoms` (`atom_indices` into `topology`, or every atom when
/// `None`), the set's own radius where Bondi gives none (Å).
pub(super) fn ses_radii(
    topology: &Topology,
    atom_indices: Option<&[u32]>,
    atoms: &AtomSet<'_>,
) -> Result<Vec<f32>, MeasureError> {
    let mut radii = Vec::with_capacity(atoms.len());
    for k in 0..atoms.len() {
        let atom = atom_indices.map_or(Some(k), |ix| ix.get(k).map(|&a| a as usize));
        let element = atom.and_then(|a| topology.elements.get(a));
        let Some(element) = element else {
            return Err(MeasureError::IndexOutOfRange {
                what: "topology atom",
                index: atom.unwrap_or(k),
                len: topology.len(),
            });
        };
        radii.push(ses_radius(element).unwrap_or(atoms.radii[k]));
    }
    Ok(radii)
}

/// Options of [`probe_cavities`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProbeOptions {
    /// Probe radius in Å (1.4 for water).
    pub probe: f32,
    /// Grid spacing in Å (0.25 finds voids down to about one probe's volume).
    pub spacing: f32,
    /// Cavities smaller than this (Å³) are left out.
    pub min_volume: f64,
}

impl Default for ProbeOptions {
    fn default() -> Self {
        ProbeOptions {
            probe: 1.4,
            spacing: 0.25,
            min_volume: 0.0,
        }
    }
}

/// How far (Å) beyond the probe a free centre's ball may grow towards the atoms (see
/// [`void_of`]).
const CLEARANCE_CAP: f32 = 1.0;

/// The probe-accessible cavities of `atoms` (radii: the SES radii of the atoms, Å), largest
/// first, at least `options.min_volume` Å³ each. Fails on invalid atoms or options, or a grid
/// larger than the memory available.
pub fn probe_cavities(
    atoms: &AtomSet<'_>,
    options: &ProbeOptions,
) -> Result<Vec<Cavity>, MeasureError> {
    let walls = probe_cavity_walls(atoms, options)?;
    Ok(walls.into_iter().map(|(cavity, _)| cavity).collect())
}

/// [`probe_cavities`] with each cavity's wall (see [`ses_probe_cavity_walls`]).
pub fn probe_cavity_walls(
    atoms: &AtomSet<'_>,
    options: &ProbeOptions,
) -> Result<Vec<(Cavity, Mesh)>, MeasureError> {
    check_probe_options(atoms, options)?;
    let grid = probe_grid(atoms, options)?;
    let mut marks = free_centres(atoms, &grid, options.probe);
    flood_outside(&grid, &mut marks);
    let count = label_cavities(&grid, &mut marks);
    let mut centres: Vec<Vec<Vec3>> = vec![Vec::new(); count as usize];
    for (at, &mark) in marks.iter().enumerate() {
        if (1..=count).contains(&mark) {
            centres[mark as usize - 1].push(grid.point_at(at));
        }
    }
    centres.extend(voids_between_grid_points(
        atoms,
        &grid,
        &marks,
        options.probe,
    ));
    drop(marks);
    let mut out = Vec::new();
    for free in &centres {
        let (cavity, wall) = void_of(atoms, grid.spacing, free, options.probe)?;
        if cavity.volume >= options.min_volume {
            out.push((cavity, wall));
        }
    }
    out.sort_by(|a, b| b.0.volume.total_cmp(&a.0.volume));
    Ok(out)
}

/// Checks the atoms and the options' ranges (probe 0.1 to 10 Å, spacing 0.05 to 10 Å, minimum
/// volume not negative); an empty set is an error.
pub(super) fn check_probe_options(
    atoms: &AtomSet<'_>,
    options: &ProbeOptions,
) -> Result<(), MeasureError> {
    atoms.validate()?;
    for (name, value, low, high) in [
        ("probe radius (Å)", options.probe, 0.1, 10.0),
        ("probe grid spacing (Å)", options.spacing, 0.05, 10.0),
    ] {
        let value = f64::from(value);
        if !(value.is_finite() && (low..=high).contains(&value)) {
            return Err(MeasureError::OptionOutOfRange {
                name,
                value,
                low,
                high,
            });
        }
    }
    if !(options.min_volume.is_finite() && options.min_volume >= 0.0) {
        return Err(MeasureError::InvalidOption {
            name: "minimum cavity volume",
            value: options.min_volume,
        });
    }
    if atoms.is_empty() {
        return Err(SurfaceError::EmptySystem.into());
    }
    Ok(())
}

/// The grid over the atoms with a border of free points all round.
pub(super) fn probe_grid(
    atoms: &AtomSet<'_>,
    options: &ProbeOptions,
) -> Result<GridSpec, MeasureError> {
    let far = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    let (lo, hi) = atoms
        .positions
        .iter()
        .fold(far, |(lo, hi), p| (lo.min(*p), hi.max(*p)));
    let max_radius = atoms.radii.iter().fold(0.0f32, |m, &r| m.max(r));
    let h = options.spacing;
    let pad = max_radius + 2.0 * options.probe + 2.0 * h;
    let origin = lo - Vec3::splat(pad);
    let extent = hi + Vec3::splat(pad) - origin;
    let dims64 = extent.to_array().map(|e| (e / h).ceil() as u64 + 1);
    // 4 bytes of marks, 4 of distance field and 1 of depth (the search between grid points)
    // per point, and a little for the meshes.
    let points: u64 = dims64.iter().product();
    let bytes_needed = points.saturating_mul(10);
    let bytes_available = available_memory_bytes();
    if dims64.iter().any(|&d| d > u32::MAX as u64 / 4) || bytes_needed > bytes_available {
        return Err(MeasureError::ProbeGridTooLarge {
            dims: dims64,
            spacing: h,
            bytes_needed,
            bytes_available,
        });
    }
    Ok(GridSpec {
        origin,
        spacing: h,
        dims: dims64.map(|d| d as u32),
    })
}

/// Marks every grid point: [`BLOCKED`] when a probe there overlaps an atom, else [`UNSEEN`].
pub(super) fn free_centres(atoms: &AtomSet<'_>, grid: &GridSpec, probe: f32) -> Vec<u32> {
    let mut marks = vec![UNSEEN; grid.voxel_count() as usize];
    draw_balls(
        grid,
        &mut marks,
        atoms.positions,
        |a| atoms.radii[a] + probe,
        |mark, at| {
            // Strictly inside the reach: a probe touching an atom is free. Stored every time,
            // so that the row's loop vectorises without a branch per point.
            *mark = if at.dx * at.dx < at.left {
                BLOCKED
            } else {
                *mark
            };
        },
    );
    marks
}

/// The void of one cavity, the union of probe balls at its free points `centres` (Å, points of
/// a grid of spacing `h`): its measures and lining atoms, and its wall as a mesh.
fn void_of(
    atoms: &AtomSet<'_>,
    h: f32,
    centres: &[Vec3],
    probe: f32,
) -> Result<(Cavity, Mesh), MeasureError> {
    let far = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    let (lo, hi) = centres
        .iter()
        .fold(far, |(lo, hi), p| (lo.min(*p), hi.max(*p)));
    // The void's own grid: the same lattice, around its balls.
    let pad = probe + CLEARANCE_CAP + 2.0 * h;
    let grid = GridSpec {
        origin: lo - Vec3::splat(pad),
        spacing: h,
        dims: ((hi - lo + Vec3::splat(2.0 * pad)) / h)
            .round()
            .to_array()
            .map(|n| n as u32 + 1),
    };
    // Each free centre x stands for the ball of its clearance s(x) (distance to the nearest
    // atom's surface, at least the probe): every point of that ball is within the probe of a
    // free centre on the way to it, so the ball lies in the void, and it reaches the atoms the
    // probe touches. s is capped (the cap only shrinks balls), which bounds the atoms to look at.
    let cap = probe + CLEARANCE_CAP;
    let max_radius = atoms.radii.iter().fold(0.0f32, |m, &r| m.max(r));
    let near: Vec<(Vec3, f32)> = atoms
        .positions
        .iter()
        .zip(atoms.radii)
        .filter(|(p, _)| {
            !(p.cmplt(lo - (cap + max_radius)) | p.cmpgt(hi + (cap + max_radius))).any()
        })
        .map(|(p, r)| (*p, *r))
        .collect();
    let clearance_at = |x: Vec3| near.iter().fold(cap, |m, (p, r)| m.min(p.distance(x) - r));
    // The balls: each free centre with its clearance, and, from each centre near the edge of
    // the free set, the last free point towards each blocked neighbour (bisected to within
    // h/256), so the void does not stop up to a grid step short of the atoms.
    let mut balls: Vec<(Vec3, f32)> = Vec::with_capacity(centres.len());
    let edge = probe + h * 3f32.sqrt();
    for &c in centres {
        let clearance = clearance_at(c).max(probe);
        balls.push((c, clearance));
        if clearance >= edge {
            continue;
        }
        for step in neighbours() {
            let y = c + h * Vec3::new(step[0] as f32, step[1] as f32, step[2] as f32);
            if clearance_at(y) >= probe {
                continue;
            }
            let (mut free, mut blocked) = (0.0f32, 1.0f32);
            for _ in 0..8 {
                let mid = 0.5 * (free + blocked);
                if clearance_at(c.lerp(y, mid)) >= probe {
                    free = mid;
                } else {
                    blocked = mid;
                }
            }
            if free > 0.0 {
                balls.push((c.lerp(y, free), probe));
            }
        }
    }
    // max over balls of (radius - |y - centre|), where a ball reaches within 2h.
    let mut field = vec![-2.0 * h; grid.voxel_count() as usize];
    let centres_of_balls: Vec<Vec3> = balls.iter().map(|&(c, _)| c).collect();
    draw_balls(
        &grid,
        &mut field,
        &centres_of_balls,
        |b| balls[b].1 + 2.0 * h,
        |value, at| {
            let inside = balls[at.ball].1 - (at.dx * at.dx + at.yz2).sqrt();
            // Stored every time (a compare and select), so that the row's loop vectorises.
            *value = if inside > *value { inside } else { *value };
        },
    );
    let density = DensityVolume {
        values: field,
        colours: None,
    };
    let mesh = marching_cubes::extract(&grid, &density, 0.0);
    let parts = components(&mesh)?;
    let volume: f64 = parts.iter().map(|p| p.volume).sum();
    let centroid = if volume > 0.0 {
        parts.iter().map(|p| p.centroid * p.volume).sum::<DVec3>() / volume
    } else {
        centres.iter().map(|c| c.as_dvec3()).sum::<DVec3>() / centres.len() as f64
    };
    let radius = mesh
        .positions
        .iter()
        .map(|p| p.as_dvec3().distance(centroid))
        .fold(0.0, f64::max);
    let mut lining: Vec<u32> = Vec::new();
    for (a, (p, r)) in atoms.positions.iter().zip(atoms.radii).enumerate() {
        let touch = r + probe + h;
        if (p.cmplt(lo - touch) | p.cmpgt(hi + touch)).any() {
            continue;
        }
        if centres
            .iter()
            .any(|c| c.distance_squared(*p) <= touch * touch)
        {
            lining.push(a as u32);
        }
    }
    let cavity = Cavity {
        volume,
        area: mesh.area(),
        centroid,
        radius,
        vertex_count: mesh.positions.len(),
        lining_atoms: lining,
        cell: None,
    };
    Ok((cavity, mesh))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_options_and_no_atoms_are_errors() {
        let positions = [Vec3::ZERO];
        let radii = [1.5];
        let atoms = AtomSet {
            positions: &positions,
            radii: &radii,
            colours: None,
        };
        for (options, message) in [
            (
                ProbeOptions {
                    probe: 0.0,
                    ..ProbeOptions::default()
                },
                "probe radius (Å) must be a number from 0.1 to 10, got 0",
            ),
            (
                ProbeOptions {
                    spacing: f32::NAN,
                    ..ProbeOptions::default()
                },
                "probe grid spacing (Å) must be a number from 0.05 to 10, got NaN",
            ),
            (
                ProbeOptions {
                    spacing: 20.0,
                    ..ProbeOptions::default()
                },
                "probe grid spacing (Å) must be a number from 0.05 to 10, got 20",
            ),
            (
                ProbeOptions {
                    min_volume: -1.0,
                    ..ProbeOptions::default()
                },
                "minimum cavity volume must be a finite non-negative number, got -1",
            ),
        ] {
            let error = probe_cavities(&atoms, &options).unwrap_err();
            assert_eq!(error.to_string(), message);
        }
        assert!(
            probe_cavities(&atoms, &ProbeOptions::default())
                .unwrap()
                .is_empty()
        );
        let none = AtomSet {
            positions: &[],
            radii: &[],
            colours: None,
        };
        assert!(probe_cavities(&none, &ProbeOptions::default()).is_err());
    }

    #[test]
    fn a_grid_larger_than_memory_is_an_error_naming_the_grid() {
        let positions = [Vec3::ZERO, Vec3::splat(5_000.0)];
        let radii = [1.5, 1.5];
        let atoms = AtomSet {
            positions: &positions,
            radii: &radii,
            colours: None,
        };
        let error = probe_cavities(&atoms, &ProbeOptions::default()).unwrap_err();
        assert!(
            matches!(error, MeasureError::ProbeGridTooLarge { .. }),
            "{error:?}"
        );
        let text = error.to_string();
        assert!(
            text.contains("grid at 0.25 Å needs") && text.contains("select fewer atoms"),
            "{text}"
        );
    }

    #[test]
    fn bondi_radii_for_the_elements_of_proteins() {
        assert_eq!(ses_radius("C"), Some(1.70));
        assert_eq!(ses_radius("O"), Some(1.52));
        assert_eq!(ses_radius("Xx"), None);
    }
}
