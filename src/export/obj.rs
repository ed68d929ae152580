//! Wavefront OBJ writer (text): `v x y z r g b` with sRGB colours in 0..1 as the common
//! vertex-colour extension (MeshLab, Blender), `vn` normals, and `f a//a b//b c//c` faces
//! (1-based, each vertex's normal has its index).

use std::io::{self, Write};

use glam::Vec3;

use super::linear_to_srgb8;
use crate::surface::Mesh;

/// Writes `mesh` as OBJ. Missing normals or colours are written as zero normals and white.
pub fn write_obj(w: &mut dyn Write, mesh: &Mesh) -> io::Result<()> {
    writeln!(
        w,
        "# mdsurf Gaussian density surface, positions in angstrom"
    )?;
    writeln!(
        w,
        "# {} vertices, {} triangles",
        mesh.vertex_count(),
        mesh.triangle_count()
    )?;
    for (i, p) in mesh.positions.iter().enumerate() {
        let c = mesh.colours.get(i).copied().unwrap_or([1.0; 3]);
        let [r, g, b] = c.map(|x| f32::from(linear_to_srgb8(x)) / 255.0);
        writeln!(w, "v {} {} {} {:.4} {:.4} {:.4}", p.x, p.y, p.z, r, g, b)?;
    }
    for i in 0..mesh.vertex_count() {
        let n = mesh.normals.get(i).copied().unwrap_or(Vec3::ZERO);
        writeln!(w, "vn {} {} {}", n.x, n.y, n.z)?;
    }
    for t in mesh.indices.chunks_exact(3) {
        let [a, b, c] = [t[0] as u64 + 1, t[1] as u64 + 1, t[2] as u64 + 1];
        writeln!(w, "f {a}//{a} {b}//{b} {c}//{c}")?;
    }
    Ok(())
}
