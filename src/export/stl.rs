//! Binary STL writer: an 80-byte header, a u32 triangle count, then per triangle its unit face
//! normal, three vertices (f32, Å) and a zero attribute word. STL has no colours or shared
//! vertices; it is here for 3D printing and CAD tools.

use std::io::{self, Write};

use super::too_large;
use crate::surface::Mesh;

/// Bytes per triangle record.
pub const TRIANGLE_BYTES: usize = 50;

/// Writes `mesh` as binary STL.
pub fn write_stl(w: &mut dyn Write, mesh: &Mesh) -> io::Result<()> {
    let count = u32::try_from(mesh.triangle_count()).map_err(|_| too_large("STL"))?;
    // The header must not start with "solid", or readers take the file for ASCII STL.
    let mut header = [b' '; 80];
    let text = b"mdsurf binary STL, Gaussian density surface, units: angstrom";
    header[..text.len()].copy_from_slice(text);
    w.write_all(&header)?;
    w.write_all(&count.to_le_bytes())?;

    const CHUNK: usize = 1 << 14;
    let mut buf = Vec::with_capacity(CHUNK * TRIANGLE_BYTES);
    let mut n = 0;
    for [a, b, c] in mesh.triangles() {
        let normal = (b - a).cross(c - a).normalize_or_zero();
        for v in [normal, a, b, c] {
            for x in v.to_array() {
                buf.extend_from_slice(&x.to_le_bytes());
            }
        }
        buf.extend_from_slice(&0u16.to_le_bytes());
        n += 1;
        if n == CHUNK {
            w.write_all(&buf)?;
            buf.clear();
            n = 0;
        }
    }
    w.write_all(&buf)
}
