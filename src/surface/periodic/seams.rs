//! Where a periodic mesh continues across the cell faces: the vertices on the upper faces
//! (`x = L_x`, and y, z; in a triclinic cell the faces at index `N_a`, `N_b`, `N_c`) are copies of
//! vertices on the lower faces moved by a lattice vector ([`super::mc`] makes them so). The
//! measurements that need the surface as one closed sheet (cavities in a periodic cell, per-atom
//! areas of the one-cell part of a replicated mesh) read [`PeriodicMesh`] from the surface's
//! output.
//!
//! Data flow: the one-cell mesh in local coordinates (Å from the cell origin, or index space for
//! a triclinic cell), before it is moved or mapped -> [`face_twins`] -> [`PeriodicMesh`] in
//! [`crate::surface::SurfaceOutput::periodic`].

use std::collections::HashMap;

use glam::Vec3;

use super::{Replicate, TriclinicCell};

/// A vertex on an upper face and the vertex on the lower faces it copies:
/// `position(vertex) = position(twin) + shift[0] a + shift[1] b + shift[2] c`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FaceTwin {
    /// The vertex on an upper face (index into the mesh's vertices).
    pub vertex: u32,
    /// The vertex it copies, on the lower faces.
    pub twin: u32,
    /// Lattice vector between them, in cell edges (each 0 or 1).
    pub shift: [i8; 3],
}

/// What a periodic surface's mesh is: one cell's mesh (its first vertices and triangles; the
/// rest, with `--replicate`, are copies moved by lattice vectors), open at the faces, whose
/// upper-face vertices copy lower-face ones.
#[derive(Debug, Clone, PartialEq)]
pub struct PeriodicMesh {
    /// The cell (origin and edge vectors a, b, c in Å; a rectangular box has them along x, y, z).
    pub cell: TriclinicCell,
    /// Images of the cell the mesh shows.
    pub replicate: Replicate,
    /// Vertices of one cell's mesh: the mesh's first ones.
    pub cell_vertices: u32,
    /// Triangles of one cell's mesh: the mesh's first ones.
    pub cell_triangles: u32,
    /// Every vertex of one cell's mesh on an upper face with its twin, by vertex.
    pub face_twins: Vec<FaceTwin>,
    /// Vertices on an upper face without a twin (none from the periodic Marching Cubes): the
    /// sheet is open there.
    pub unmatched: Vec<u32>,
}

/// The upper-face vertices of a one-cell mesh whose local coordinates (`local`, before the cell
/// origin is added or the index space mapped) run from 0 to `top` along each axis, with the
/// lower-face vertices they copy. A copy has exactly the coordinate `top[k]` where its twin has
/// exactly 0 and the same bits elsewhere (the periodic Marching Cubes computes both from the
/// same samples). Also returns the upper-face vertices without a twin (which that rule does
/// not make), whose sheets the measurements treat as open.
pub fn face_twins(local: &[Vec3], top: Vec3) -> (Vec<FaceTwin>, Vec<u32>) {
    let key = |p: Vec3| p.to_array().map(f32::to_bits);
    let lower: HashMap<[u32; 3], u32> = local
        .iter()
        .enumerate()
        .filter(|(_, p)| p.to_array().contains(&0.0))
        .map(|(i, &p)| (key(p), i as u32))
        .collect();
    let (mut out, mut unmatched) = (Vec::new(), Vec::new());
    for (i, &p) in local.iter().enumerate() {
        let mut shift = [0i8; 3];
        let mut wrapped = p;
        for k in 0..3 {
            if p[k] == top[k] {
                shift[k] = 1;
                wrapped[k] = 0.0;
            }
        }
        if shift == [0; 3] {
            continue;
        }
        match lower.get(&key(wrapped)) {
            Some(&twin) => out.push(FaceTwin {
                vertex: i as u32,
                twin,
                shift,
            }),
            None => unmatched.push(i as u32),
        }
    }
    (out, unmatched)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn upper_face_vertices_find_their_lower_copies() {
        let top = Vec3::new(3.0, 4.0, 5.0);
        let local = [
            Vec3::new(0.0, 1.5, 2.0), // 0: lower x face
            Vec3::new(3.0, 1.5, 2.0), // 1: its copy
            Vec3::new(0.0, 0.0, 2.5), // 2: lower x and y edge
            Vec3::new(3.0, 4.0, 2.5), // 3: its copy across both
            Vec3::new(1.0, 2.0, 5.0), // 4: upper z face, no twin
            Vec3::new(1.0, 2.0, 2.0), // 5: inside
            Vec3::new(3.0, 0.0, 2.5), // 6: copy of 2 across x only
        ];
        let (twins, unmatched) = face_twins(&local, top);
        assert_eq!(unmatched, vec![4]);
        assert_eq!(
            twins,
            vec![
                FaceTwin {
                    vertex: 1,
                    twin: 0,
                    shift: [1, 0, 0]
                },
                FaceTwin {
                    vertex: 3,
                    twin: 2,
                    shift: [1, 1, 0]
                },
                FaceTwin {
                    vertex: 6,
                    twin: 2,
                    shift: [1, 0, 0]
                },
            ]
        );
    }
}
