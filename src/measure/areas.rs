//! Area per atom: each triangle's area goes one third to each vertex, each vertex's share to the
//! atoms in proportion to their Gaussians there (see [`super`] for the rule).

use rayon::prelude::*;

use super::MeasureError;
use super::cells::{Batch, CellList, nearest};
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
    let mut shares = vec![0.0f64; n];
    for t in mesh.indices.chunks_exact(3) {
        let [a, b, c] = [t[0], t[1], t[2]].map(|i| mesh.positions[i as usize]);
        let third = 0.5 * (b - a).as_dvec3().cross((c - a).as_dvec3()).length() / 3.0;
        for &i in t {
            shares[i as usize] += third;
        }
    }
    Ok(shares)
}

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
    let shares = vertex_areas(mesh)?;
    let cells = CellList::new(atoms, params);
    // Vertices grouped by cell (in cell order, then vertex order), so that each group gathers
    // its candidate atoms once; per group the (atom, area) pairs, summed in group order at the
    // end, so the result does not depend on the thread count.
    let keys: Vec<u32> = mesh
        .positions
        .par_iter()
        .map(|p| cells.key(*p).unwrap_or(u32::MAX))
        .collect();
    let mut order: Vec<u32> = (0..mesh.positions.len() as u32)
        .filter(|&v| shares[v as usize] != 0.0)
        .collect();
    order.par_sort_unstable_by_key(|&v| (keys[v as usize], v));
    let groups: Vec<&[u32]> = order
        .chunk_by(|&a, &b| keys[a as usize] == keys[b as usize])
        .collect();
    let pairs: Vec<Vec<(u32, f64)>> = groups
        .par_iter()
        .map_init(
            || (Batch::default(), Vec::<(u32, f32)>::with_capacity(32)),
            |(batch, here), group| {
                let mut out = Vec::with_capacity(group.len() * 8);
                let key = keys[group[0] as usize];
                if key != u32::MAX {
                    cells.gather(key, batch);
                }
                for &v in *group {
                    let (p, share) = (mesh.positions[v as usize], shares[v as usize]);
                    here.clear();
                    let mut total = 0.0f64;
                    if key != u32::MAX {
                        batch.for_each_gaussian(p, |atom, w| {
                            here.push((atom, w));
                            total += f64::from(w);
                        });
                    }
                    if total > 0.0 {
                        let scale = share / total;
                        out.extend(here.iter().map(|&(a, w)| (a, f64::from(w) * scale)));
                    } else {
                        out.push((nearest(atoms.positions, p), share));
                    }
                }
                out
            },
        )
        .collect();
    let mut areas = vec![0.0f64; atoms.len()];
    for (atom, area) in pairs.iter().flatten() {
        areas[*atom as usize] += area;
    }
    Ok(areas)
}

/// [`atom_areas`] of a computed surface, rescaled so that they sum to [`SurfaceOutput::area`]
/// (the same, to rounding, with interpolated vertices; the curved area with refined ones).
/// Fails as [`atom_areas`] does, or when the engine did not keep the mesh.
pub fn atom_areas_of(
    output: &SurfaceOutput,
    atoms: &AtomSet<'_>,
    params: &SurfaceParams,
) -> Result<Vec<f64>, MeasureError> {
    if output.counts_without_mesh.is_some() {
        return Err(MeasureError::NoMesh);
    }
    let mut areas = atom_areas(&output.mesh, atoms, params)?;
    let sum: f64 = areas.iter().sum();
    if sum > 0.0 && output.area.is_finite() {
        let scale = output.area / sum;
        areas.iter_mut().for_each(|a| *a *= scale);
    }
    Ok(areas)
}
