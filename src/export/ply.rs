//! Stanford PLY writer: binary little-endian, per vertex `x y z nx ny nz` (float, Å and unit
//! normal) and `red green blue` (uchar sRGB), faces as `list uchar int vertex_indices`.
//!
//! Written by hand: the format is a short text header plus packed records, and the PLY crates on
//! crates.io are either unmaintained or add a generic property model we do not need.

use std::io::{self, Write};

use glam::Vec3;

use super::{linear_to_srgb8, too_large};
use crate::surface::Mesh;

/// Bytes per vertex record: six f32 and three u8.
pub const VERTEX_BYTES: usize = 6 * 4 + 3;
/// Bytes per face record: a u8 count (3) and three i32 indices.
pub const FACE_BYTES: usize = 1 + 3 * 4;

/// The PLY header for `vertices` vertices and `faces` triangles.
pub fn ply_header(vertices: usize, faces: usize) -> String {
    format!(
        "ply\n\
         format binary_little_endian 1.0\n\
         comment mdsurf Gaussian density surface, positions in angstrom\n\
         element vertex {vertices}\n\
         property float x\n\
         property float y\n\
         property float z\n\
         property float nx\n\
         property float ny\n\
         property float nz\n\
         property uchar red\n\
         property uchar green\n\
         property uchar blue\n\
         element face {faces}\n\
         property list uchar int vertex_indices\n\
         end_header\n"
    )
}

/// Writes `mesh` as binary little-endian PLY. Missing normals or colours are written as zero
/// normals and white.
pub fn write_ply(w: &mut dyn Write, mesh: &Mesh) -> io::Result<()> {
    if mesh.vertex_count() > i32::MAX as usize {
        return Err(too_large("PLY's int vertex indices"));
    }
    w.write_all(ply_header(mesh.vertex_count(), mesh.triangle_count()).as_bytes())?;

    const CHUNK: usize = 1 << 14;
    let mut buf = Vec::with_capacity(CHUNK * VERTEX_BYTES);
    for (start, chunk) in mesh.positions.chunks(CHUNK).enumerate() {
        buf.clear();
        for (k, p) in chunk.iter().enumerate() {
            let i = start * CHUNK + k;
            let n = mesh.normals.get(i).copied().unwrap_or(Vec3::ZERO);
            let c = mesh.colours.get(i).copied().unwrap_or([1.0; 3]);
            for v in [p.x, p.y, p.z, n.x, n.y, n.z] {
                buf.extend_from_slice(&v.to_le_bytes());
            }
            buf.extend(c.map(linear_to_srgb8));
        }
        w.write_all(&buf)?;
    }

    let mut buf = Vec::with_capacity(CHUNK * FACE_BYTES);
    for chunk in mesh.indices.chunks(3 * CHUNK) {
        buf.clear();
        for t in chunk.chunks_exact(3) {
            buf.push(3u8);
            for &i in t {
                buf.extend_from_slice(&(i as i32).to_le_bytes());
            }
        }
        w.write_all(&buf)?;
    }
    Ok(())
}
