//! The solvent-excluded surface (SES) a rolling probe leaves around a structure, on a grid, and
//! the area two groups bury against each other on it: what MSMS computes analytically, for the
//! buried area of an interface where a sum of Gaussians swells between the partners and buries
//! too much (docs/measure.md, "Where the small interfaces' excess comes from").
//!
//! The rule, on the grid of spacing `h` (Å) of [`super::probe_cavities`]:
//! 1. Free probe centres (at least `r_i + probe` from every atom) connected to the grid's border
//!    are the probe's outside; the rest of space is the structure's, cavities included (the
//!    outer surface only, as MSMS's external component).
//! 2. Along every grid edge from an outside centre to a blocked one, the exact point where the
//!    probe first touches an atom (the nearest entry into any sphere of radius `r_i + probe`) is
//!    a sample of the solvent-accessible surface (SAS).
//! 3. A point is excluded from the solvent when it is farther than the probe from the SAS; the
//!    SES is the isosurface `d(x) - probe = 0` of the distance `d` to the nearest SAS sample,
//!    made by Marching Cubes on the same grid. The samples lie within `h` of each other, so `d`
//!    is off by a hundredth of an Å at most where it matters.
//! 4. Each triangle's area goes to the atom whose sphere lies nearest its centroid
//!    (`|c - x_i| - r_i` least): contact faces to the atom they lie on, re-entrant faces to the
//!    nearest of the atoms the probe rests on. Per-atom areas sum to the area.
//!
//! For an interface, the complex, A and B are computed on the complex's grid, so that far from
//! the contact the three meshes are the same triangles and cancel exactly.

use glam::{IVec3, Vec3};
use rayon::prelude::*;

use super::MeasureError;
use super::grid_balls::draw_balls;
use super::grid_flood::{OUTSIDE, flood_outside};
use super::interface::{InterfaceResult, union_of};
use super::probe_cavities::{
    ProbeOptions, check_probe_options, free_centres, probe_grid, ses_radii,
};
use crate::model::Topology;
use crate::model::cells::CellList;
use crate::surface::marching_cubes;
use crate::surface::{AtomSet, DensityVolume, GridSpec, Mesh};

/// A probe's solvent-excluded surface.
#[derive(Debug, Clone)]
pub struct ProbeSurface {
    /// The grid it was made on.
    pub grid: GridSpec,
    /// The surface, triangles facing the solvent (positions in Å).
    pub mesh: Mesh,
    /// Its area in Å².
    pub area: f64,
    /// The volume it encloses in Å³.
    pub volume: f64,
    /// Area of each atom in Å² (in the atom set's order), summing to `area`.
    pub atom_areas: Vec<f64>,
}

/// The outer SES of `atoms` (radii: their SES radii, Å) for a probe of `options.probe` Å on a
/// grid of `options.spacing` Å (`min_volume` is not used). Fails on invalid atoms or options,
/// or a grid larger than the memory available.
pub fn probe_surface(
    atoms: &AtomSet<'_>,
    options: &ProbeOptions,
) -> Result<ProbeSurface, MeasureError> {
    check_probe_options(atoms, options)?;
    let grid = probe_grid(atoms, options)?;
    Ok(surface_on(atoms, &grid, options.probe))
}

/// The area `a` and `b` bury against each other on their probe surfaces:
/// `(area(A) + area(B) - area(A and B)) / 2`, the three on the complex's grid, with per-atom
/// areas alone and in the complex. Fails as [`probe_surface`].
pub fn probe_interface(
    a: &AtomSet<'_>,
    b: &AtomSet<'_>,
    options: &ProbeOptions,
) -> Result<InterfaceResult, MeasureError> {
    check_probe_options(a, options)?;
    check_probe_options(b, options)?;
    let (positions, radii) = union_of(a, b);
    let union = AtomSet {
        positions: &positions,
        radii: &radii,
        colours: None,
    };
    let grid = probe_grid(&union, options)?;
    let complex = surface_on(&union, &grid, options.probe);
    let alone_a = surface_on(a, &grid, options.probe);
    let alone_b = surface_on(b, &grid, options.probe);
    let mut atoms_a_complex = complex.atom_areas;
    let atoms_b_complex = atoms_a_complex.split_off(a.len());
    Ok(InterfaceResult {
        grid,
        area_a: alone_a.area,
        area_b: alone_b.area,
        area_complex: complex.area,
        buried: 0.5 * (alone_a.area + alone_b.area - complex.area),
        atoms_a_alone: alone_a.atom_areas,
        atoms_b_alone: alone_b.atom_areas,
        atoms_a_complex,
        atoms_b_complex,
        taken: Default::default(),
    })
}

/// [`probe_interface`] with Bondi's radius of each atom's element ([`super::ses_radius`]; the
/// set's own radius where Bondi gives none): what `mdsurf surface --interface-probe` and
/// Python's `Scene.interface(..., probe_A=...)` compute. `a_indices` and `b_indices` are the
/// topology atoms of the two sets (`None`: all atoms).
pub fn ses_probe_interface(
    topology: &Topology,
    (a_indices, a): (Option<&[u32]>, &AtomSet<'_>),
    (b_indices, b): (Option<&[u32]>, &AtomSet<'_>),
    options: &ProbeOptions,
) -> Result<InterfaceResult, MeasureError> {
    let radii_a = ses_radii(topology, a_indices, a)?;
    let radii_b = ses_radii(topology, b_indices, b)?;
    probe_interface(
        &AtomSet {
            radii: &radii_a,
            ..*a
        },
        &AtomSet {
            radii: &radii_b,
            ..*b
        },
        options,
    )
}

/// The probe surface of `atoms` on `grid` (which holds them with the padding of
/// [`probe_grid`]).
fn surface_on(atoms: &AtomSet<'_>, grid: &GridSpec, probe: f32) -> ProbeSurface {
    let mut marks = free_centres(atoms, grid, probe);
    flood_outside(grid, &mut marks);
    let max_radius = atoms.radii.iter().fold(0.0f32, |m, &r| m.max(r));
    let items: Vec<(u32, Vec3)> = atoms
        .positions
        .iter()
        .enumerate()
        .map(|(i, &p)| (i as u32, p))
        .collect();
    // Every atom within reach of a point lies in the 27 cells around the point's cell.
    let cells = CellList::covering(&items, max_radius + probe + grid.spacing, 1);
    let samples = sas_samples(atoms, grid, &marks, &cells, probe);
    let field = excluded_field(grid, &marks, &samples, probe);
    drop(marks);
    let density = DensityVolume {
        values: field,
        colours: None,
    };
    let mesh = marching_cubes::extract(grid, &density, 0.0);
    let (area, volume) = mesh.area_and_volume();
    let atom_areas = triangle_owners(atoms, &mesh, &cells);
    ProbeSurface {
        grid: *grid,
        mesh,
        area,
        volume,
        atom_areas,
    }
}

/// Calls `visit` with each atom (index, centre, radius in Å) in the 27 cells around `p`
/// (`cells` of `atoms`, at least `max r_i + probe` wide: every atom within that of `p`).
pub(super) fn near_atoms(
    atoms: &AtomSet<'_>,
    cells: &CellList,
    p: Vec3,
    mut visit: impl FnMut(usize, Vec3, f32),
) {
    let at = cells.cell_of(p);
    for dz in -1..=1 {
        for dy in -1..=1 {
            for dx in -1..=1 {
                let (points, ids) = cells.cell(at + IVec3::new(dx, dy, dz));
                for (&q, &id) in points.iter().zip(ids) {
                    visit(id as usize, q, atoms.radii[id as usize]);
                }
            }
        }
    }
}

/// The SAS samples: on each grid edge from an outside centre to a blocked one, the first point
/// where a probe moving along it touches an atom (Å).
fn sas_samples(
    atoms: &AtomSet<'_>,
    grid: &GridSpec,
    marks: &[u32],
    cells: &CellList,
    probe: f32,
) -> Vec<Vec3> {
    let [nx, ny, nz] = grid.dims.map(|d| d as usize);
    let h = grid.spacing;
    let axes = [
        Vec3::X,
        Vec3::NEG_X,
        Vec3::Y,
        Vec3::NEG_Y,
        Vec3::Z,
        Vec3::NEG_Z,
    ];
    // The grid's border and the points next to it are outside (its padding is wider than any
    // atom's reach), so edges to blocked points start inside them and every neighbour exists.
    let row_of = |j: usize, k: usize| &marks[nx * (j + ny * k)..][..nx];
    let per_plane: Vec<Vec<Vec3>> = (1..nz.saturating_sub(1))
        .into_par_iter()
        .map(|k| {
            let mut out = Vec::new();
            for j in 1..ny - 1 {
                let row = row_of(j, k);
                let (below, above) = (row_of(j - 1, k), row_of(j + 1, k));
                let (back, front) = (row_of(j, k - 1), row_of(j, k + 1));
                for i in 1..nx - 1 {
                    if row[i] != OUTSIDE {
                        continue;
                    }
                    // The neighbour along each of `axes`.
                    let next = [
                        row[i + 1],
                        row[i - 1],
                        above[i],
                        below[i],
                        front[i],
                        back[i],
                    ];
                    if next.iter().all(|&m| m == OUTSIDE) {
                        continue;
                    }
                    let start = grid.point(i as u32, j as u32, k as u32);
                    for (axis, &mark) in axes.iter().zip(&next) {
                        if mark == OUTSIDE {
                            continue;
                        }
                        let dir = h * *axis;
                        let t = first_contact(atoms, cells, start, dir, probe);
                        out.push(start + t * dir);
                    }
                }
            }
            out
        })
        .collect();
    per_plane.concat()
}

/// The least `t` in 0..=1 at which `start + t dir` (Å) comes within `r_i + probe` of an atom
/// (1 when none does: the edge's far end is blocked, so one does up to rounding).
fn first_contact(atoms: &AtomSet<'_>, cells: &CellList, start: Vec3, dir: Vec3, probe: f32) -> f32 {
    let mut t_min = 1.0f32;
    let dd = dir.length_squared();
    near_atoms(atoms, cells, start, |_, centre, radius| {
        // |start - centre + t dir|^2 = (r + probe)^2; `start` is outside every such sphere.
        let f = start - centre;
        let reach = radius + probe;
        let half_b = f.dot(dir);
        let c = f.length_squared() - reach * reach;
        let disc = half_b * half_b - dd * c;
        if disc < 0.0 || half_b >= 0.0 {
            return;
        }
        let t = (c / (-half_b + disc.sqrt())).max(0.0);
        t_min = t_min.min(t);
    });
    t_min
}

/// The field whose zero isosurface is the SES, positive inside: `d(x) - probe` at the points
/// that are not the probe's outside (`d` the distance to the nearest SAS sample, capped at
/// `probe + h`: `d` changes by at most `h` along a grid edge, so every edge the isosurface
/// crosses has its true values), `-probe` at the outside's.
fn excluded_field(grid: &GridSpec, marks: &[u32], samples: &[Vec3], probe: f32) -> Vec<f32> {
    let reach = probe + grid.spacing;
    // Squared distances while drawing: the square root is taken once per point after.
    let mut field = vec![reach * reach; grid.voxel_count() as usize];
    draw_balls(
        grid,
        &mut field,
        samples,
        |_| reach,
        |nearest, at| {
            // A compare and select (not `f32::min`, which orders NaN) stored every time (not
            // only when smaller, which compiles to a branch per lane) vectorises.
            let d2 = at.dx * at.dx + at.yz2;
            *nearest = if d2 < *nearest { d2 } else { *nearest };
        },
    );
    field.par_iter_mut().zip(marks).for_each(|(value, &mark)| {
        *value = if mark == OUTSIDE {
            -probe
        } else {
            value.sqrt() - probe
        };
    });
    field
}

/// Each triangle's area given to the atom nearest its centroid (by distance to the atom's
/// sphere); Å² per atom.
fn triangle_owners(atoms: &AtomSet<'_>, mesh: &Mesh, cells: &CellList) -> Vec<f64> {
    let mut areas = vec![0.0f64; atoms.len()];
    for [a, b, c] in mesh.triangles() {
        let area = 0.5 * f64::from((b - a).cross(c - a).length());
        let centroid = (a + b + c) / 3.0;
        let mut best = (f32::INFINITY, usize::MAX);
        near_atoms(atoms, cells, centroid, |id, centre, radius| {
            let gap = centroid.distance(centre) - radius;
            if gap < best.0 {
                best = (gap, id);
            }
        });
        if best.1 == usize::MAX {
            // Not expected (every SES point is within the probe of an atom); look at all.
            for (id, (p, r)) in atoms.positions.iter().zip(atoms.radii).enumerate() {
                let gap = centroid.distance(*p) - r;
                if gap < best.0 {
                    best = (gap, id);
                }
            }
        }
        areas[best.1] += area;
    }
    areas
}

#[cfg(test)]
mod tests {
    use super::*;

    fn set<'a>(positions: &'a [Vec3], radii: &'a [f32]) -> AtomSet<'a> {
        AtomSet {
            positions,
            radii,
            colours: None,
        }
    }

    /// One atom: its SES is its own sphere.
    #[test]
    fn a_lone_atom_has_its_sphere_as_surface() {
        let (positions, radii) = ([Vec3::new(0.3, -0.2, 0.1)], [1.7f32]);
        let s = probe_surface(&set(&positions, &radii), &ProbeOptions::default()).unwrap();
        let sphere = 4.0 * std::f64::consts::PI * 1.7f64.powi(2);
        assert!(
            (s.area / sphere - 1.0).abs() < 0.02,
            "{} against {sphere}",
            s.area
        );
        let ball = 4.0 / 3.0 * std::f64::consts::PI * 1.7f64.powi(3);
        assert!(
            (s.volume / ball - 1.0).abs() < 0.02,
            "{} against {ball}",
            s.volume
        );
        assert!((s.atom_areas[0] - s.area).abs() < 1e-6 * s.area);
    }

    /// Two touching atoms: the probe cannot reach their waist, so the SES fills it with a
    /// re-entrant belt; the area is less than the two spheres' and the volume more than the
    /// two balls'. Per-atom areas split it evenly and sum to it.
    #[test]
    fn two_touching_atoms_fill_their_waist() {
        let positions = [Vec3::new(-1.6, 0.0, 0.0), Vec3::new(1.6, 0.0, 0.0)];
        let radii = [1.6f32, 1.6];
        let s = probe_surface(&set(&positions, &radii), &ProbeOptions::default()).unwrap();
        let sphere = 4.0 * std::f64::consts::PI * 1.6f64.powi(2);
        let ball = 4.0 / 3.0 * std::f64::consts::PI * 1.6f64.powi(3);
        assert!(s.area < 2.0 * sphere * 0.98, "{}", s.area);
        assert!(s.volume > 2.0 * ball * 1.01, "{}", s.volume);
        let sum: f64 = s.atom_areas.iter().sum();
        assert!((sum - s.area).abs() < 1e-6 * s.area);
        assert!((s.atom_areas[0] / s.atom_areas[1] - 1.0).abs() < 0.02);
    }

    /// Groups far apart bury nothing: the complex's mesh is the two sides' meshes.
    #[test]
    fn groups_apart_bury_nothing_and_touching_groups_bury_area() {
        let a = [Vec3::new(0.0, 0.0, 0.0), Vec3::new(3.0, 0.0, 0.0)];
        let radii = [1.7f32, 1.7];
        let far = [Vec3::new(0.0, 12.0, 0.0), Vec3::new(3.0, 12.0, 0.0)];
        let near = [Vec3::new(0.0, 3.0, 0.0), Vec3::new(3.0, 3.0, 0.0)];
        let options = ProbeOptions::default();
        let apart = probe_interface(&set(&a, &radii), &set(&far, &radii), &options).unwrap();
        assert!(apart.buried.abs() < 1e-6, "{}", apart.buried);
        let touching = probe_interface(&set(&a, &radii), &set(&near, &radii), &options).unwrap();
        assert!(touching.buried > 4.0, "{}", touching.buried);
        let sum = |areas: &[f64]| areas.iter().sum::<f64>();
        assert!((sum(&touching.atoms_a_alone) - touching.area_a).abs() < 1e-6);
        let lost = sum(&touching.atoms_a_alone) - sum(&touching.atoms_a_complex)
            + sum(&touching.atoms_b_alone)
            - sum(&touching.atoms_b_complex);
        assert!((lost - 2.0 * touching.buried).abs() < 1e-6, "{lost}");
    }
}
