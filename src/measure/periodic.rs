//! Measurements on a periodic surface (`--periodic`): the mesh of one cell, open at its faces,
//! whose density counts every periodic image of every atom ([`crate::surface::periodic`]).
//!
//! - **Area per atom**: the rule of [`super::atom_areas`] over the atoms' images that reach the
//!   cell (a vertex near a face takes its share from the atoms across it), each image's area
//!   added to its atom. Only one cell's mesh is weighed (the first copy when `--replicate`
//!   shows several), so an atom's area is per cell, as the surface's area is.
//! - **Cavities**: the cell's mesh is welded across the faces (each upper-face vertex to the
//!   lower-face vertex it copies, [`crate::surface::periodic::PeriodicMesh`]) and each connected
//!   sheet unwrapped by walking its triangles (a vertex reached over a face is moved by that
//!   lattice vector). A sheet that meets itself moved by a lattice vector runs through the
//!   periodic system (a membrane, the bulk solvent) and encloses nothing; a finite sheet is
//!   closed, and one of negative signed volume (triangles winding towards a void) is a cavity.
//!   With no outer surface in a periodic system, no enclosing component is asked for. Its
//!   volume, area and centroid are those of the unwrapped sheet, the centroid moved into the
//!   cell, and its lining atoms are found among the images as [`super::cavities()`] finds them.
//!
//! - **Buried area** ([`periodic_interface`]): the three surfaces of A, B and both, each
//!   periodic in the frame's cell (whose grid they share), their areas per cell.
//!
//! Data flow: a periodic surface's mesh and its [`PeriodicMesh`] + the atoms and parameters it
//! was computed from -> images of the atoms -> per-atom areas, or welded and unwrapped sheets
//! -> [`Cavity`] rows, as the non-periodic measurements give them. Lengths in Å.

use std::borrow::Cow;
use std::collections::VecDeque;

use glam::{DMat3, DVec3, IVec3, Vec3};
use rayon::prelude::*;

use super::cavities::{
    Cavity, CavityOptions, Component, bounding_radius, components, lining_atoms,
};
use super::cells::CellList;
use super::{InterfaceResult, MeasureError, atom_areas};
use crate::surface::periodic::cell::images_reaching_cell;
use crate::surface::periodic::{
    PeriodicCell, PeriodicEngine, PeriodicMesh, Replicate, TriclinicCell,
};
use crate::surface::{AtomSet, Mesh, SurfaceParams};

/// Periodic images of a set of atoms, each with the atom it copies.
struct Images {
    /// Positions in Å.
    positions: Vec<Vec3>,
    /// Radii in Å (the atom's).
    radii: Vec<f32>,
    /// The atom each image copies (index into the atom set).
    atom: Vec<u32>,
}

impl Images {
    /// Every image of `atoms` whose cutoff sphere under `params`, widened by `margin` Å,
    /// reaches `cell` (tested against the slabs between opposite faces, so a few images
    /// that just miss a corner are kept too).
    fn reaching(
        atoms: &AtomSet<'_>,
        params: &SurfaceParams,
        cell: &TriclinicCell,
        margin: f64,
    ) -> Images {
        let m = cell.matrix();
        let inv = m.inverse();
        let widths = cell.widths();
        let q = f64::from(params.cutoff()) * f64::from(params.radius_scale);
        // Each atom's images in parallel, kept in the atoms' order.
        let (positions, (radii, atom)) = atoms
            .positions
            .par_iter()
            .zip(atoms.radii.par_iter())
            .enumerate()
            .flat_map_iter(|(i, (&p, &r))| {
                let s = inv * (p - cell.origin).as_dvec3();
                // Reach in fractions of the cell along each axis.
                let reach = ((q * f64::from(r) + margin) * DVec3::ONE / widths).to_array();
                images_reaching_cell(s, reach)
                    .map(move |f| ((m * f).as_vec3() + cell.origin, (r, i as u32)))
            })
            .unzip();
        Images {
            positions,
            radii,
            atom,
        }
    }

    fn set(&self) -> AtomSet<'_> {
        AtomSet {
            positions: &self.positions,
            radii: &self.radii,
            colours: None,
        }
    }
}

/// The one-cell part of a periodic surface's mesh: its first vertices and triangles.
fn cell_mesh<'a>(mesh: &'a Mesh, seams: &PeriodicMesh) -> Result<Cow<'a, Mesh>, MeasureError> {
    let (vertices, triangles) = (seams.cell_vertices as usize, seams.cell_triangles as usize);
    if vertices > mesh.positions.len() || 3 * triangles > mesh.indices.len() {
        return Err(MeasureError::IndexOutOfRange {
            what: "periodic cell's mesh vertex",
            index: vertices.max(triangles),
            len: mesh.positions.len(),
        });
    }
    if vertices == mesh.positions.len() && 3 * triangles == mesh.indices.len() {
        return Ok(Cow::Borrowed(mesh));
    }
    let first = |n: usize, len: usize| n.min(len);
    Ok(Cow::Owned(Mesh {
        positions: mesh.positions[..vertices].to_vec(),
        normals: mesh.normals[..first(vertices, mesh.normals.len())].to_vec(),
        indices: mesh.indices[..3 * triangles].to_vec(),
        ..Mesh::default()
    }))
}

/// Area in Å² of one cell's periodic surface (`mesh` with its `seams`, from `atoms` under
/// `params`) per atom
/// of `atoms`, by the rule of [`super::atom_areas`] over the atoms' periodic images. The
/// entries sum to one cell's triangle area to rounding.
pub fn periodic_atom_areas(
    mesh: &Mesh,
    seams: &PeriodicMesh,
    atoms: &AtomSet<'_>,
    params: &SurfaceParams,
) -> Result<Vec<f64>, MeasureError> {
    params.validate()?;
    atoms.validate()?;
    let mesh = cell_mesh(mesh, seams)?;
    let images = Images::reaching(atoms, params, &seams.cell, 0.0);
    let per_image = atom_areas(&mesh, &images.set(), params)?;
    let mut areas = vec![0.0f64; atoms.len()];
    for (&atom, area) in images.atom.iter().zip(per_image) {
        areas[atom as usize] += area;
    }
    Ok(areas)
}

/// A cell's mesh welded across the faces and unwrapped sheet by sheet.
struct Unwrapped {
    /// The mesh: positions of the lower-face (kept) vertices moved by their sheet's lattice
    /// vectors, triangles on kept vertices only.
    mesh: Mesh,
    /// Per vertex, true when its sheet meets itself moved by a lattice vector, or is open (an
    /// upper-face vertex without a twin).
    endless: Vec<bool>,
}

/// Welds `mesh` (one cell, open at the faces) by `seams` and unwraps each sheet.
fn unwrap(mesh: &Mesh, seams: &PeriodicMesh) -> Unwrapped {
    let n = mesh.positions.len();
    let mut kept: Vec<u32> = (0..n as u32).collect();
    let mut shift = vec![IVec3::ZERO; n];
    let mut open = vec![false; n];
    for t in &seams.face_twins {
        kept[t.vertex as usize] = t.twin;
        shift[t.vertex as usize] = IVec3::from_array(t.shift.map(i32::from));
    }
    for &v in &seams.unmatched {
        open[v as usize] = true;
    }
    let triangles: Vec<[u32; 3]> = mesh
        .indices
        .chunks_exact(3)
        .map(|t| [t[0], t[1], t[2]])
        .collect();
    // Triangles by kept vertex (compressed rows).
    let mut starts = vec![0u32; n + 1];
    for t in &triangles {
        for &v in t {
            starts[kept[v as usize] as usize + 1] += 1;
        }
    }
    for i in 0..n {
        starts[i + 1] += starts[i];
    }
    let mut fill = starts.clone();
    let mut by_vertex = vec![0u32; 3 * triangles.len()];
    for (k, t) in triangles.iter().enumerate() {
        for &v in t {
            let w = kept[v as usize] as usize;
            by_vertex[fill[w] as usize] = k as u32;
            fill[w] += 1;
        }
    }
    // Each sheet from its first kept vertex: lattice offset of every kept vertex such that a
    // triangle's corners (each the kept vertex moved by its corner's shift) move together.
    let mut offset: Vec<Option<IVec3>> = vec![None; n];
    let mut sheet = vec![u32::MAX; n];
    let mut endless_sheet: Vec<bool> = Vec::new();
    let mut queue = VecDeque::new();
    for seed in 0..n {
        if kept[seed] != seed as u32 || offset[seed].is_some() || starts[seed] == starts[seed + 1] {
            continue;
        }
        let id = endless_sheet.len() as u32;
        endless_sheet.push(false);
        offset[seed] = Some(IVec3::ZERO);
        sheet[seed] = id;
        queue.push_back(seed as u32);
        while let Some(w) = queue.pop_front() {
            let here = offset[w as usize].unwrap_or(IVec3::ZERO);
            for &k in &by_vertex[starts[w as usize] as usize..starts[w as usize + 1] as usize] {
                let corners = triangles[k as usize];
                let Some(&via) = corners.iter().find(|&&v| kept[v as usize] == w) else {
                    continue;
                };
                let moved = here - shift[via as usize];
                for &v in &corners {
                    endless_sheet[id as usize] |= open[v as usize];
                    let (u, want) = (kept[v as usize] as usize, moved + shift[v as usize]);
                    match offset[u] {
                        None => {
                            offset[u] = Some(want);
                            sheet[u] = id;
                            queue.push_back(u as u32);
                        }
                        Some(o) if o != want => endless_sheet[id as usize] = true,
                        Some(_) => {}
                    }
                }
            }
        }
    }
    let m = seams.cell.matrix();
    let positions = (0..n)
        .map(|v| {
            let o = offset[v].unwrap_or(IVec3::ZERO).as_dvec3();
            (mesh.positions[v].as_dvec3() + m * o).as_vec3()
        })
        .collect();
    let indices = triangles
        .iter()
        .flat_map(|t| t.map(|v| kept[v as usize]))
        .collect();
    let endless = (0..n)
        .map(|v| sheet[v] != u32::MAX && endless_sheet[sheet[v] as usize])
        .collect();
    Unwrapped {
        mesh: Mesh {
            positions,
            indices,
            ..Mesh::default()
        },
        endless,
    }
}

/// The cell translation (in cell edges) that moves `p` into `cell`.
fn into_cell(cell: &TriclinicCell, inv: &DMat3, p: DVec3) -> DVec3 {
    -(*inv * (p - cell.origin.as_dvec3())).floor()
}

/// The cavities of one cell's periodic surface (`mesh` with its `seams`, from `atoms` under
/// `params`), largest first: the finite sheets of negative signed volume, at least
/// `options.min_volume` Å³, with their centroids in the cell and lining atoms indexed into
/// `atoms`.
pub fn periodic_cavities(
    mesh: &Mesh,
    seams: &PeriodicMesh,
    atoms: &AtomSet<'_>,
    params: &SurfaceParams,
    options: &CavityOptions,
) -> Result<Vec<Cavity>, MeasureError> {
    let found = periodic_cavity_walls(mesh, seams, atoms, params, options)?;
    Ok(found.into_iter().map(|(cavity, _)| cavity).collect())
}

/// [`periodic_cavities`] with each cavity's wall: its sheet unwrapped and moved into the cell
/// by the lattice vector that takes its centroid there (so it may reach a little past a face),
/// positions, normals and triangles as the surface has them (winding towards the void).
pub fn periodic_cavity_walls(
    mesh: &Mesh,
    seams: &PeriodicMesh,
    atoms: &AtomSet<'_>,
    params: &SurfaceParams,
    options: &CavityOptions,
) -> Result<Vec<(Cavity, Mesh)>, MeasureError> {
    params.validate()?;
    atoms.validate()?;
    options.validate()?;
    let mesh = cell_mesh(mesh, seams)?;
    let unwrapped = unwrap(&mesh, seams);
    let sheets: Vec<Component> = components(&unwrapped.mesh)?
        .into_iter()
        .filter(|c| c.volume < -options.min_volume)
        .filter(|c| !c.vertices.iter().any(|&v| unwrapped.endless[v as usize]))
        .collect();
    if sheets.is_empty() {
        return Ok(Vec::new());
    }
    let cell = &seams.cell;
    let (m, inv) = (cell.matrix(), cell.matrix().inverse());
    let positions = &unwrapped.mesh.positions;
    let wall = |c: &Component, by: Vec3| -> Vec<Vec3> {
        c.vertices
            .iter()
            .map(|&v| positions[v as usize] + by)
            .collect()
    };
    let radii: Vec<f64> = sheets
        .iter()
        .map(|c| bounding_radius(wall(c, Vec3::ZERO).into_iter(), c.centroid))
        .collect();
    // Images reaching the cell widened by the largest wall, moved into the cell by its centroid.
    let margin = radii.iter().fold(0.0f64, |a, &b| a.max(b)) + 1.0;
    let images = Images::reaching(atoms, params, cell, margin);
    let image_set = images.set();
    let cells = CellList::new(&image_set, params);
    let mut out: Vec<(Cavity, Mesh)> = sheets
        .iter()
        .zip(radii)
        .map(|(c, radius)| {
            let by = into_cell(cell, &inv, c.centroid);
            let moved = wall(c, (m * by).as_vec3());
            let mut lining: Vec<u32> = lining_atoms(
                moved.iter().copied(),
                &image_set,
                &cells,
                options.lining_fraction,
            )
            .into_iter()
            .map(|i| images.atom[i as usize])
            .collect();
            lining.sort_unstable();
            lining.dedup();
            let cavity = Cavity {
                volume: -c.volume,
                area: c.area,
                centroid: c.centroid + m * by,
                radius,
                vertex_count: c.vertices.len(),
                lining_atoms: lining,
                cell: Some(*cell),
            };
            (cavity, sheet_mesh(&mesh, &unwrapped.mesh, c, moved))
        })
        .collect();
    out.sort_by(|a, b| b.0.volume.total_cmp(&a.0.volume));
    Ok(out)
}

/// The mesh of sheet `c` of `welded` with its vertices at `positions` (in `c.vertices`'
/// order), normals from the cell's mesh `cell`.
fn sheet_mesh(cell: &Mesh, welded: &Mesh, c: &Component, positions: Vec<Vec3>) -> Mesh {
    let mut local = std::collections::HashMap::with_capacity(c.vertices.len());
    for (k, &v) in c.vertices.iter().enumerate() {
        local.insert(v, k as u32);
    }
    let indices = c
        .triangles
        .iter()
        .flat_map(|&t| {
            let t = 3 * t as usize;
            [0, 1, 2].map(|j| local[&welded.indices[t + j]])
        })
        .collect();
    Mesh {
        normals: c
            .vertices
            .iter()
            .map(|&v| cell.normals.get(v as usize).copied().unwrap_or_default())
            .collect(),
        colours: vec![[1.0; 3]; positions.len()],
        positions,
        indices,
    }
}

/// The buried area between `a` and `b` on periodic surfaces in `cell` (each of the three
/// surfaces from the periodic engine, on the cell's grid, which the three share by
/// construction), per cell: as [`super::interface_with`] defines it, with the complex's radii
/// `complex_radii` (Å, `a`'s atoms then `b`'s; `None`: each side's own) and the per-atom
/// areas over the atoms' images ([`periodic_atom_areas`]) when `per_atom`.
///
/// Fails on invalid atoms or parameters, radii of another length, or a grid the memory cannot
/// hold.
pub fn periodic_interface(
    engine: &mut PeriodicEngine,
    [a, b]: [&AtomSet<'_>; 2],
    cell: &PeriodicCell,
    complex_radii: Option<&[f32]>,
    params: &SurfaceParams,
    per_atom: bool,
) -> Result<InterfaceResult, MeasureError> {
    let [a, b] = [a, b].map(|s| AtomSet {
        colours: None,
        ..*s
    });
    a.validate()?;
    b.validate()?;
    params.validate()?;
    let (positions, radii) = super::interface::complex_of(&a, &b, complex_radii)?;
    let union = AtomSet {
        positions: &positions,
        radii: &radii,
        colours: None,
    };
    let one = Replicate::default();
    let mut surface = |atoms: &AtomSet<'_>| engine.compute_cell(atoms, params, cell, one);
    let [out_a, out_b, out_ab] = [surface(&a)?, surface(&b)?, surface(&union)?];
    let mut per_atom_areas: [Vec<f64>; 4] = Default::default();
    if per_atom {
        let together = super::atom_areas_of(&out_ab, &union, params)?;
        per_atom_areas = [
            super::atom_areas_of(&out_a, &a, params)?,
            super::atom_areas_of(&out_b, &b, params)?,
            together[..a.len()].to_vec(),
            together[a.len()..].to_vec(),
        ];
    }
    Ok(InterfaceResult::of(
        [&out_a, &out_b, &out_ab],
        per_atom_areas,
        Default::default(),
    ))
}
