//! Area per atom: each triangle's area goes one third to each vertex, each vertex's share to the
//! atoms in proportion to their Gaussians there (see [`super`] for the rule).

use glam::Vec3;
use rayon::prelude::*;

use super::MeasureError;
use super::cells::{Batch, CellGrid, CellList, nearest};
use crate::model::cells::sort_by_cell;
use crate::surface::analytic::exp_fast;
use crate::surface::periodic::PeriodicMesh;
use crate::surface::{AtomSet, Mesh, SurfaceOutput, SurfaceParams};

/// Area in Å² of each triangle-vertex share: `vertex_areas[v]` is a third of the area of every
/// triangle using vertex `v` (f64). Fails on an index past the vertices.
pub fn vertex_areas(mesh: &Mesh) -> Result<Vec<f64>, MeasureError> {
    let n = mesh.positions.len();
    if let Some(&bad) = mesh.indices.iter().find(|&&i| i as usize >= n) {
        return Err(MeasureError::IndexOutOfRange {
            what: "mesh vertex",
            index: bad as usize,
            len: n,
        });
    }
    // Runs of triangles in parallel, each adding its thirds to the vertices it uses in a local
    // array over the run's range of vertex indices (narrow on a mesh written cell by cell),
    // then the runs added in order: runs of a fixed length, so the sums do not depend on the
    // thread count. A run whose vertices lie further apart keeps its thirds instead, added
    // vertex by vertex in the merge (memory stays within 3 f64 per triangle).
    let third = |t: &[u32]| {
        let [a, b, c] = [t[0], t[1], t[2]].map(|i| mesh.positions[i as usize]);
        0.5 * (b - a).as_dvec3().cross((c - a).as_dvec3()).length() / 3.0
    };
    let runs: Vec<RunShares> = mesh
        .indices
        .par_chunks(3 * TRIANGLES_PER_RUN)
        .map(|run| {
            let (lo, hi) = run
                .iter()
                .fold((u32::MAX, 0), |(lo, hi), &i| (lo.min(i), hi.max(i)));
            let range = (hi - lo) as usize + 1;
            if range > run.len() {
                return RunShares::Thirds(run.chunks_exact(3).map(third).collect());
            }
            let mut local = vec![0.0f64; range];
            for t in run.chunks_exact(3) {
                let third = third(t);
                for &i in t {
                    local[(i - lo) as usize] += third;
                }
            }
            RunShares::Local {
                lo: lo as usize,
                shares: local,
            }
        })
        .collect();
    let mut shares = vec![0.0f64; n];
    for (run, run_shares) in mesh.indices.chunks(3 * TRIANGLES_PER_RUN).zip(runs) {
        match run_shares {
            RunShares::Local { lo, shares: local } => {
                for (share, add) in shares[lo..lo + local.len()].iter_mut().zip(local) {
                    *share += add;
                }
            }
            RunShares::Thirds(thirds) => {
                for (t, third) in run.chunks_exact(3).zip(thirds) {
                    for &i in t {
                        shares[i as usize] += third;
                    }
                }
            }
        }
    }
    Ok(shares)
}

/// Triangles per run of [`vertex_areas`].
const TRIANGLES_PER_RUN: usize = 8192;

/// What one run of triangles of [`vertex_areas`] adds to the vertices' shares (Å²).
enum RunShares {
    /// The sums over the run's vertex indices `lo..lo + shares.len()`.
    Local { lo: usize, shares: Vec<f64> },
    /// Each triangle's third, in triangle order (the run's vertices lie far apart).
    Thirds(Vec<f64>),
}

/// The smallest box (Å, lower and upper corner) holding `points` (not empty).
fn bounds(points: impl Iterator<Item = Vec3>) -> (Vec3, Vec3) {
    points.fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(p), hi.max(p)),
    )
}

/// The vertices of one cell of [`atom_areas`] (indices into `mesh`, with their area shares),
/// and the atoms and cell list they are weighed against.
struct CellWork<'a> {
    order: &'a [u32],
    mesh: &'a Mesh,
    shares: &'a [f64],
    cells: &'a CellList,
    atoms: &'a AtomSet<'a>,
}

/// What [`weigh_cell`] reuses from cell to cell: the gathered atoms; for the cell's vertices
/// one after the other, the gathered atoms reaching each, their Gaussians, and where each
/// vertex's run of them ends; the area (Å²) each gathered atom has from the cell so far.
#[derive(Default)]
struct Scratch {
    batch: Batch,
    picked: Vec<u32>,
    gaussians: Vec<f32>,
    ends: Vec<usize>,
    gathered_area: Vec<f64>,
}

/// Appends to `out` the (atom, area) pairs of the vertices of one cell: each vertex's share
/// split in proportion to the Gaussians reaching it (the nearest atom's when none does), summed
/// per atom over the cell's vertices in vertex order.
fn weigh_cell(work: &CellWork<'_>, scratch: &mut Scratch, out: &mut Vec<(u32, f64)>) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2 (checked just above).
        unsafe { weigh_cell_avx2(work, scratch, out) };
        return;
    }
    weigh_cell_body(work, scratch, out);
}

/// [`weigh_cell`] compiled for AVX2; the same operations in the same order (Rust never fuses
/// a multiply and an add), so the same bits as the portable build.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn weigh_cell_avx2(work: &CellWork<'_>, scratch: &mut Scratch, out: &mut Vec<(u32, f64)>) {
    weigh_cell_body(work, scratch, out);
}

/// The body of [`weigh_cell`], inlined into each instruction-set variant.
#[inline(always)]
fn weigh_cell_body(work: &CellWork<'_>, scratch: &mut Scratch, out: &mut Vec<(u32, f64)>) {
    let Scratch {
        batch,
        picked,
        gaussians,
        ends,
        gathered_area,
    } = scratch;
    let position = |v: u32| work.mesh.positions[v as usize];
    let (lo, hi) = bounds(work.order.iter().map(|&v| position(v)));
    work.cells.gather(lo, hi, batch);
    // The reaching atoms of every vertex of the cell, then all their Gaussians in one loop
    // (the polynomial exponential, relative error below 1e-6, which the compiler vectorises),
    // then each vertex's share split among its atoms.
    picked.clear();
    gaussians.clear();
    ends.clear();
    for &v in work.order {
        batch.reaching(position(v), picked, gaussians);
        ends.push(picked.len());
    }
    for g in gaussians.iter_mut() {
        *g = exp_fast(*g);
    }
    gathered_area.clear();
    gathered_area.resize(batch.len(), 0.0);
    let mut start = 0;
    for (&v, &end) in work.order.iter().zip(ends.iter()) {
        let (atoms, weights) = (&picked[start..end], &gaussians[start..end]);
        start = end;
        let share = work.shares[v as usize];
        let total: f64 = weights.iter().map(|&w| f64::from(w)).sum();
        if total > 0.0 {
            let scale = share / total;
            for (&k, &w) in atoms.iter().zip(weights) {
                gathered_area[k as usize] += f64::from(w) * scale;
            }
        } else {
            out.push((nearest(work.atoms.positions, position(v)), share));
        }
    }
    for (k, &area) in gathered_area.iter().enumerate() {
        if area != 0.0 {
            out.push((batch.atom(k), area));
        }
    }
}

/// The vertices of a mesh grouped by the cells of a [`CellGrid`]: each group gathers its
/// candidate atoms once.
struct VertexGroups {
    /// Start of each group cell's run in `order` (one more entry than group cells).
    starts: Vec<u32>,
    /// Vertices on the grid, sorted by group cell (ascending within a cell).
    order: Vec<u32>,
    /// The group cells with vertices, ascending.
    occupied: Vec<u32>,
    /// Vertices off the grid (no atom reaches them), ascending.
    off_grid: Vec<u32>,
}

impl VertexGroups {
    fn new(grid: &CellGrid, mesh: &Mesh) -> VertexGroups {
        let keys: Vec<usize> = mesh
            .positions
            .par_iter()
            .map(|p| grid.key(*p).map_or(usize::MAX, |key| key as usize))
            .collect();
        let (starts, order) = sort_by_cell(&keys, grid.len());
        let occupied: Vec<u32> = (0..grid.len() as u32)
            .filter(|&c| starts[c as usize] < starts[c as usize + 1])
            .collect();
        let off_grid: Vec<u32> = (0..keys.len() as u32)
            .filter(|&v| keys[v as usize] == usize::MAX)
            .collect();
        VertexGroups {
            starts,
            order,
            occupied,
            off_grid,
        }
    }
}

/// Cells of vertices handed to one task of [`atom_areas`]: a fixed number, so that the order
/// of the per-atom sums, and so the result, does not depend on the thread count.
const CELLS_PER_TASK: usize = 64;

/// Area in Å² of `mesh` that belongs to each atom of `atoms` (one entry per atom, f64), by the
/// rule of [`super`]: `params` must be the ones the surface was computed with (with refined
/// vertices, `engine.vertices().effective(&params)`). The entries sum to the mesh's triangle
/// area to rounding. An empty mesh gives zeros.
///
/// Fails on invalid atoms or parameters, or a triangle index past the vertices.
pub fn atom_areas(
    mesh: &Mesh,
    atoms: &AtomSet<'_>,
    params: &SurfaceParams,
) -> Result<Vec<f64>, MeasureError> {
    params.validate()?;
    atoms.validate()?;
    // The vertices' shares beside the atoms binned and then the vertices grouped by cell (a
    // vertex without a share, in no triangle, adds nothing).
    let grid = CellGrid::plan(atoms, params);
    let (shares, (cells, groups)) = rayon::join(
        || vertex_areas(mesh),
        || (grid.bin(atoms, params), VertexGroups::new(&grid, mesh)),
    );
    let shares = shares?;
    let VertexGroups {
        starts,
        order,
        occupied,
        off_grid,
    } = groups;
    // Per task the (atom, area) pairs of its vertices, summed in task order at the end.
    let pairs: Vec<Vec<(u32, f64)>> = occupied
        .par_chunks(CELLS_PER_TASK)
        .map_init(Scratch::default, |scratch, task| {
            let vertices: u32 = task
                .iter()
                .map(|&c| starts[c as usize + 1] - starts[c as usize])
                .sum();
            let mut out = Vec::with_capacity(vertices as usize * 2);
            for &cell in task {
                let (s, e) = (starts[cell as usize], starts[cell as usize + 1]);
                let work = CellWork {
                    order: &order[s as usize..e as usize],
                    mesh,
                    shares: &shares,
                    cells: &cells,
                    atoms,
                };
                weigh_cell(&work, scratch, &mut out);
            }
            out
        })
        .collect();
    let mut areas = vec![0.0f64; atoms.len()];
    for (atom, area) in pairs.iter().flatten() {
        areas[*atom as usize] += area;
    }
    for v in off_grid.into_iter().filter(|&v| shares[v as usize] != 0.0) {
        let p = mesh.positions[v as usize];
        areas[nearest(atoms.positions, p) as usize] += shares[v as usize];
    }
    Ok(areas)
}

/// [`atom_areas`] of a computed surface, rescaled so that they sum to
/// [`SurfaceOutput::measured_area`]: its area (the same, to rounding, with interpolated
/// vertices; the curved area with refined ones), one cell's for a periodic surface, whose
/// areas are [`super::periodic_atom_areas`]. Fails as [`atom_areas`] does, or when the engine
/// did not keep the mesh.
pub fn atom_areas_of(
    output: &SurfaceOutput,
    atoms: &AtomSet<'_>,
    params: &SurfaceParams,
) -> Result<Vec<f64>, MeasureError> {
    if output.counts_without_mesh.is_some() {
        return Err(MeasureError::NoMesh);
    }
    let seams = output.periodic.as_deref();
    scaled_atom_areas(&output.mesh, seams, output.measured_area(), atoms, params)
}

/// The per-atom areas of `mesh` (with a periodic surface's `seams`: per cell, over the atoms'
/// images), scaled so that they sum to `area` (Å²), the area the engine measured: the rule of
/// [`atom_areas_of`] for a mesh held apart from its `SurfaceOutput` (one read back from the
/// GPU).
pub fn scaled_atom_areas(
    mesh: &Mesh,
    seams: Option<&PeriodicMesh>,
    area: f64,
    atoms: &AtomSet<'_>,
    params: &SurfaceParams,
) -> Result<Vec<f64>, MeasureError> {
    let mut areas = match seams {
        Some(seams) => super::periodic_atom_areas(mesh, seams, atoms, params)?,
        None => atom_areas(mesh, atoms, params)?,
    };
    let sum: f64 = areas.iter().sum();
    if sum > 0.0 && area.is_finite() {
        let scale = area / sum;
        areas.iter_mut().for_each(|a| *a *= scale);
    }
    Ok(areas)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each vertex's share is a third of the area of every triangle using it, with triangles
    /// spread over several runs of [`TRIANGLES_PER_RUN`], and a run whose vertices are too far
    /// apart for a local array (the last, with a triangle of the first and last vertex).
    #[test]
    fn vertex_shares_are_thirds_of_their_triangles_across_runs() {
        let side = 160u32; // a jittered sheet of 160 x 160 vertices: 50,563 triangles
        let positions: Vec<Vec3> = (0..side * side)
            .map(|i| {
                let (x, y) = ((i % side) as f32, (i / side) as f32);
                Vec3::new(x, y, (x * 0.3).sin() + (y * 0.7).cos())
            })
            .collect();
        let mut indices = Vec::new();
        for y in 0..side - 1 {
            for x in 0..side - 1 {
                let v = y * side + x;
                indices.extend([v, v + 1, v + side, v + 1, v + side + 1, v + side]);
            }
        }
        let last = side * side - 1;
        indices.extend([0, last, side - 1]);
        assert!(indices.len() / 3 > 6 * TRIANGLES_PER_RUN);
        assert!(
            side * side > 3 * TRIANGLES_PER_RUN as u32,
            "the last run keeps thirds"
        );
        let mesh = Mesh {
            positions,
            indices,
            ..Mesh::default()
        };
        let mut want = vec![0.0f64; mesh.positions.len()];
        for t in mesh.indices.chunks_exact(3) {
            // Edges in f32, the cross product in f64, as the function computes them.
            let [a, b, c] = [t[0], t[1], t[2]].map(|i| mesh.positions[i as usize]);
            let area = (b - a).as_dvec3().cross((c - a).as_dvec3()).length() / 2.0;
            for &i in t {
                want[i as usize] += area / 3.0;
            }
        }
        let got = vertex_areas(&mesh).expect("vertex areas");
        assert_eq!(got.len(), want.len());
        for (v, (g, w)) in got.iter().zip(&want).enumerate() {
            assert!(
                (g - w).abs() <= 1e-12 * w.abs().max(1.0),
                "vertex {v}: {g} vs {w}"
            );
        }
        let bad = Mesh {
            indices: vec![0, 1, u32::MAX],
            ..mesh
        };
        assert!(vertex_areas(&bad).is_err());
    }
}
