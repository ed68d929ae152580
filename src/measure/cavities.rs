//! Cavities: the connected components of a mesh whose triangles wind towards an enclosed void
//! (negative signed volume) and that lie inside an outer component (ray parity).

use glam::{DVec3, Vec3};

use super::MeasureError;
use super::cells::{Batch, CellList, nearest};
use crate::surface::periodic::TriclinicCell;
use crate::surface::{AtomSet, Mesh, SurfaceOutput, SurfaceParams};

/// One connected component of a mesh (triangles sharing vertices).
#[derive(Debug, Clone, PartialEq)]
pub struct Component {
    /// Its triangles (indices into the mesh's triangles).
    pub triangles: Vec<u32>,
    /// Its vertices (indices into the mesh's vertices), ascending.
    pub vertices: Vec<u32>,
    /// Area in Å².
    pub area: f64,
    /// Signed enclosed volume in Å³ (divergence theorem): positive for an outer surface,
    /// negative for the wall of a void.
    pub volume: f64,
    /// Centroid of the enclosed region (Å).
    pub centroid: DVec3,
}

/// Union-find root of `i`, with path halving.
fn root(parent: &mut [u32], mut i: u32) -> u32 {
    while parent[i as usize] != i {
        let up = parent[parent[i as usize] as usize];
        parent[i as usize] = up;
        i = up;
    }
    i
}

/// The connected components of `mesh` (vertices shared by index: the Marching Cubes mesh has one
/// vertex per crossed grid edge), largest area first. Fails on an index past the vertices.
pub fn components(mesh: &Mesh) -> Result<Vec<Component>, MeasureError> {
    let n = mesh.positions.len();
    if let Some(&bad) = mesh.indices.iter().find(|&&i| i as usize >= n) {
        return Err(MeasureError::IndexOutOfRange {
            what: "mesh vertex",
            index: bad as usize,
            len: n,
        });
    }
    let mut parent: Vec<u32> = (0..n as u32).collect();
    for t in mesh.indices.chunks_exact(3) {
        let r0 = root(&mut parent, t[0]);
        for &v in &t[1..] {
            let r = root(&mut parent, v);
            if r != r0 {
                let (lo, hi) = (r.min(r0), r.max(r0));
                parent[hi as usize] = lo;
            }
        }
    }
    // Component number of each root, in order of first triangle.
    let mut number = vec![u32::MAX; n];
    let mut out: Vec<Component> = Vec::new();
    for (k, t) in mesh.indices.chunks_exact(3).enumerate() {
        let r = root(&mut parent, t[0]) as usize;
        if number[r] == u32::MAX {
            number[r] = out.len() as u32;
            out.push(Component {
                triangles: Vec::new(),
                vertices: Vec::new(),
                area: 0.0,
                volume: 0.0,
                centroid: DVec3::ZERO,
            });
        }
        out[number[r] as usize].triangles.push(k as u32);
    }
    for v in 0..n as u32 {
        let r = root(&mut parent, v) as usize;
        if number[r] != u32::MAX {
            out[number[r] as usize].vertices.push(v);
        }
    }
    for c in &mut out {
        measure(mesh, c);
    }
    out.sort_by(|a, b| b.area.total_cmp(&a.area));
    Ok(out)
}

/// Fills the area, signed volume and centroid of `c`, relative to its first vertex for
/// precision.
fn measure(mesh: &Mesh, c: &mut Component) {
    let p = |i: u32| mesh.positions[i as usize].as_dvec3();
    let origin = c.vertices.first().map_or(DVec3::ZERO, |&v| p(v));
    let (mut area, mut volume, mut moment) = (0.0, 0.0, DVec3::ZERO);
    for &t in &c.triangles {
        let t = 3 * t as usize;
        let [a, b, d] = [0, 1, 2].map(|k| p(mesh.indices[t + k]) - origin);
        area += 0.5 * (b - a).cross(d - a).length();
        let v = a.dot(b.cross(d)) / 6.0;
        volume += v;
        moment += v * (a + b + d) / 4.0;
    }
    c.area = area;
    c.volume = volume;
    c.centroid = origin
        + if volume != 0.0 {
            moment / volume
        } else {
            DVec3::ZERO
        };
}

/// For each of `points`, true when it is inside the closed component `c` of `mesh`: a ray
/// along +x from it crosses the component's triangles an odd number of times. The ray starts a
/// few thousandths of an Å off the point in y and z, off the grid planes that hold the mesh's
/// vertices, so it practically never meets an edge. One pass over the triangles for all points.
pub fn contains(mesh: &Mesh, c: &Component, points: &[DVec3]) -> Vec<bool> {
    let offset = DVec3::new(0.0, 1.372_9e-3, 2.913_7e-3);
    let starts: Vec<DVec3> = points.iter().map(|p| *p + offset).collect();
    let mut inside = vec![false; points.len()];
    let p = |i: u32| mesh.positions[i as usize].as_dvec3();
    for &t in &c.triangles {
        let t = 3 * t as usize;
        let [a, b, d] = [0, 1, 2].map(|k| p(mesh.indices[t + k]));
        let (ylo, yhi) = (a.y.min(b.y).min(d.y), a.y.max(b.y).max(d.y));
        let (zlo, zhi) = (a.z.min(b.z).min(d.z), a.z.max(b.z).max(d.z));
        let det = (b.y - a.y) * (d.z - a.z) - (d.y - a.y) * (b.z - a.z);
        if det == 0.0 {
            continue;
        }
        for (q, flag) in starts.iter().zip(inside.iter_mut()) {
            if q.y < ylo || q.y > yhi || q.z < zlo || q.z > zhi {
                continue;
            }
            // Barycentric coordinates of q in the triangle's projection on the yz plane.
            let u = ((q.y - a.y) * (d.z - a.z) - (d.y - a.y) * (q.z - a.z)) / det;
            let v = ((b.y - a.y) * (q.z - a.z) - (q.y - a.y) * (b.z - a.z)) / det;
            if u < 0.0 || v < 0.0 || u + v > 1.0 {
                continue;
            }
            if a.x + u * (b.x - a.x) + v * (d.x - a.x) > q.x {
                *flag = !*flag;
            }
        }
    }
    inside
}

/// Options of [`cavities()`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CavityOptions {
    /// Cavities smaller than this (Å³) are left out (0: none).
    pub min_volume: f64,
    /// An atom lines a cavity when, at one of the cavity's vertices, its Gaussian is at least
    /// this fraction of the largest Gaussian there (the atoms the wall's area is mostly split
    /// among, see [`super::atom_areas`]). Between 0 and 1; default 0.5 (for equal widths: within
    /// `sqrt(2 ln 2) alpha^2 / d` further than the nearest atom, about 0.9 Å at 3.5 Å).
    pub lining_fraction: f32,
}

impl Default for CavityOptions {
    fn default() -> Self {
        CavityOptions {
            min_volume: 0.0,
            lining_fraction: 0.5,
        }
    }
}

/// An enclosed void of a surface.
#[derive(Debug, Clone, PartialEq)]
pub struct Cavity {
    /// Volume of the void in Å³ (positive).
    pub volume: f64,
    /// Area of its wall in Å².
    pub area: f64,
    /// Centroid of the void (Å).
    pub centroid: DVec3,
    /// Largest distance from the centroid to a vertex of the wall (Å).
    pub radius: f64,
    /// Vertices of its wall.
    pub vertex_count: usize,
    /// Atoms (indices into the atom set) lining it, ascending.
    pub lining_atoms: Vec<u32>,
    /// The periodic cell it lies in, for a periodic surface's cavity (its centroid is in the
    /// cell, and tracking compares centroids by their nearest images); `None` in open space.
    pub cell: Option<TriclinicCell>,
}

impl Cavity {
    /// Distance (Å) between this cavity's centroid and `other`'s, by their nearest images when
    /// either lies in a periodic cell.
    pub fn centroid_distance(&self, other: &Cavity) -> f64 {
        let d = other.centroid - self.centroid;
        match self.cell.or(other.cell) {
            None => d.length(),
            Some(cell) => {
                let m = cell.matrix();
                let f = m.inverse() * d;
                (m * (f - f.round())).length()
            }
        }
    }
}

/// The cavities of `mesh` (computed from `atoms` under `params`, the parameters the engine
/// used), largest first: components with negative signed volume inside a component with
/// positive volume, at least `options.min_volume` Å³.
///
/// Fails on invalid atoms, parameters or options, or an index past the vertices.
pub fn cavities(
    mesh: &Mesh,
    atoms: &AtomSet<'_>,
    params: &SurfaceParams,
    options: &CavityOptions,
) -> Result<Vec<Cavity>, MeasureError> {
    params.validate()?;
    atoms.validate()?;
    options.validate()?;
    let parts = components(mesh)?;
    let cells = CellList::new(atoms, params);
    // Candidate voids and a point on each; they count when inside an outer component.
    let voids: Vec<&Component> = parts
        .iter()
        .filter(|c| c.volume < -options.min_volume && !c.vertices.is_empty())
        .collect();
    let probes: Vec<DVec3> = voids
        .iter()
        .map(|c| mesh.positions[c.vertices[0] as usize].as_dvec3())
        .collect();
    let mut enclosed = vec![false; voids.len()];
    if !voids.is_empty() {
        for outer in parts.iter().filter(|o| o.volume > 0.0) {
            for (e, inside) in enclosed.iter_mut().zip(contains(mesh, outer, &probes)) {
                *e |= inside;
            }
        }
    }
    let mut out = Vec::new();
    for (c, _) in voids.iter().zip(&enclosed).filter(|(_, e)| **e) {
        let wall = c.vertices.iter().map(|&v| mesh.positions[v as usize]);
        out.push(Cavity {
            volume: -c.volume,
            area: c.area,
            centroid: c.centroid,
            radius: bounding_radius(wall.clone(), c.centroid),
            vertex_count: c.vertices.len(),
            lining_atoms: lining_atoms(wall, atoms, &cells, options.lining_fraction),
            cell: None,
        });
    }
    out.sort_by(|a, b| b.volume.total_cmp(&a.volume));
    Ok(out)
}

/// [`cavities()`] of a computed surface: of its mesh, or of one cell's periodic surface
/// ([`super::periodic_cavities`]). Fails as they do, or when the engine did not keep the mesh.
pub fn cavities_of(
    output: &SurfaceOutput,
    atoms: &AtomSet<'_>,
    params: &SurfaceParams,
    options: &CavityOptions,
) -> Result<Vec<Cavity>, MeasureError> {
    if output.counts_without_mesh.is_some() {
        return Err(MeasureError::NoMesh);
    }
    match &output.periodic {
        Some(seams) => super::periodic_cavities(&output.mesh, seams, atoms, params, options),
        None => cavities(&output.mesh, atoms, params, options),
    }
}

impl CavityOptions {
    /// Checks the minimum volume (finite, at least 0) and the lining fraction (0 to 1).
    pub(crate) fn validate(&self) -> Result<(), MeasureError> {
        for (name, value) in [
            ("minimum cavity volume", self.min_volume),
            ("lining fraction", f64::from(self.lining_fraction)),
        ] {
            if !(value.is_finite() && value >= 0.0) || (name == "lining fraction" && value > 1.0) {
                return Err(MeasureError::InvalidOption { name, value });
            }
        }
        Ok(())
    }
}

/// The largest distance (Å) from `centroid` to a point of `wall`.
pub(crate) fn bounding_radius(wall: impl Iterator<Item = Vec3>, centroid: DVec3) -> f64 {
    wall.map(|p| p.as_dvec3().distance(centroid))
        .fold(0.0, f64::max)
}

/// The atoms (indices into `atoms`, which `cells` bins) lining a cavity whose wall has the
/// vertices `wall`: at some vertex, the atom's Gaussian is at least `fraction` of the largest
/// Gaussian there (the nearest atom where none reaches). Ascending, without repeats.
pub(crate) fn lining_atoms(
    wall: impl Iterator<Item = Vec3>,
    atoms: &AtomSet<'_>,
    cells: &CellList,
    fraction: f32,
) -> Vec<u32> {
    let mut batch = Batch::default();
    let mut lining = Vec::new();
    let mut here: Vec<(u32, f32)> = Vec::new();
    for p in wall {
        here.clear();
        cells.gather(p, p, &mut batch);
        batch.for_each_gaussian(p, |a, w| here.push((a, w)));
        let largest = here.iter().fold(0.0f32, |m, &(_, w)| m.max(w));
        if largest > 0.0 {
            let floor = fraction * largest;
            lining.extend(here.iter().filter(|&&(_, w)| w >= floor).map(|&(a, _)| a));
        } else {
            lining.push(nearest(atoms.positions, p));
        }
    }
    lining.sort_unstable();
    lining.dedup();
    lining
}
