//! Export: the end of the headless data flow. Writes surface meshes (PLY, OBJ, STL, glTF binary)
//! and per-frame statistics (CSV), always atomically (see [`atomic`]).
//!
//! Positions are written in Å as they are; colours go to PLY/OBJ as sRGB (what viewers expect)
//! and to glTF as linear RGB (what its spec requires).

pub(crate) mod atomic;
#[cfg(feature = "app")]
pub mod gif_movie;
pub mod glb;
#[cfg(feature = "app")]
pub mod movie;
#[cfg(feature = "app")]
pub mod movie_merge;
pub(crate) mod obj;
mod part_rows;
pub(crate) mod ply;
pub(crate) mod stats;
pub mod stats_merge;
pub(crate) mod stl;
pub mod table_merge;
#[cfg(feature = "app")]
pub mod video;

use std::fmt;
use std::io::{self, Write};
use std::path::{Path, PathBuf};

use crate::surface::Mesh;

pub use atomic::{AtomicFile, resolve_links, write_atomic};

/// A number written with a fixed count of decimals for a CSV field: `Fixed(x, 4)` writes as
/// `{:.4}` does, but a value that rounds to zero has no sign (`0.0000`, not the `-0.0000` of
/// an empty sum, which is -0.0 in Rust, or of a rounding error below zero).
#[derive(Debug, Clone, Copy)]
pub struct Fixed(pub f64, pub usize);

impl fmt::Display for Fixed {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let Fixed(value, decimals) = *self;
        // Only a value in (-1, 0] can print as a signed zero; the rest is written directly
        // (these fields fill per-atom tables, one per atom and frame).
        if !(value > -1.0 && value <= 0.0) {
            return write!(f, "{value:.decimals$}");
        }
        let text = format!("{value:.decimals$}");
        match text.strip_prefix('-') {
            Some(unsigned) if unsigned.bytes().all(|b| b == b'0' || b == b'.') => {
                f.write_str(unsigned)
            }
            _ => f.write_str(&text),
        }
    }
}
pub use stats::{STATS_COLUMNS, StatsRow, StatsWriter};

/// Why an output file could not be written.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// Creating, writing or renaming the file failed.
    #[error("cannot write {}: {source}", path.display())]
    Io {
        /// The output path.
        path: PathBuf,
        /// What went wrong.
        source: io::Error,
    },
    /// The file name does not say which mesh format to write.
    #[error("cannot tell the mesh format of {}: use a .ply, .obj, .stl or .glb file name", path.display())]
    UnknownFormat {
        /// The output path.
        path: PathBuf,
    },
}

impl ExportError {
    /// An I/O error on `path`.
    pub fn io(path: &Path, source: io::Error) -> ExportError {
        ExportError::Io {
            path: path.to_path_buf(),
            source,
        }
    }
}

/// A mesh file format.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MeshFormat {
    /// Stanford PLY, binary little-endian, with normals and 8-bit sRGB colours.
    Ply,
    /// Wavefront OBJ (text) with normals and sRGB vertex colours as extra `v` components.
    Obj,
    /// Binary STL (positions and face normals only).
    Stl,
    /// glTF 2.0 binary container with positions, normals, linear colours and indices.
    Glb,
}

impl MeshFormat {
    /// All formats.
    pub const ALL: [MeshFormat; 4] = [
        MeshFormat::Ply,
        MeshFormat::Obj,
        MeshFormat::Stl,
        MeshFormat::Glb,
    ];

    /// The usual file extension, lower case, without the dot.
    pub fn extension(self) -> &'static str {
        match self {
            MeshFormat::Ply => "ply",
            MeshFormat::Obj => "obj",
            MeshFormat::Stl => "stl",
            MeshFormat::Glb => "glb",
        }
    }

    /// The format named by `path`'s extension (case-insensitive).
    pub fn from_path(path: &Path) -> Result<MeshFormat, ExportError> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        MeshFormat::ALL
            .into_iter()
            .find(|f| Some(f.extension()) == ext.as_deref())
            .ok_or_else(|| ExportError::UnknownFormat {
                path: path.to_path_buf(),
            })
    }

    /// Writes `mesh` in this format to `w`.
    pub fn write(self, w: &mut dyn Write, mesh: &Mesh) -> io::Result<()> {
        match self {
            MeshFormat::Ply => ply::write_ply(w, mesh),
            MeshFormat::Obj => obj::write_obj(w, mesh),
            MeshFormat::Stl => stl::write_stl(w, mesh),
            MeshFormat::Glb => glb::write_glb(w, mesh),
        }
    }
}

impl fmt::Display for MeshFormat {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.extension())
    }
}

/// Writes `mesh` to `path` atomically, in the format its extension names.
pub fn write_mesh(path: &Path, mesh: &Mesh) -> Result<(), ExportError> {
    let format = MeshFormat::from_path(path)?;
    write_atomic(path, |w| format.write(w, mesh))
}

/// Encodes a linear RGB component in 0..1 as an 8-bit sRGB value.
pub fn linear_to_srgb8(c: f32) -> u8 {
    let c = if c.is_finite() {
        c.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let s = if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0).round().clamp(0.0, 255.0) as u8
}

/// The error for a mesh too large for a format's index or count fields.
pub(crate) fn too_large(what: &str) -> io::Error {
    io::Error::new(
        io::ErrorKind::InvalidInput,
        format!("the mesh is too large for {what}"),
    )
}

#[cfg(test)]
mod tests {
    use super::Fixed;

    #[test]
    fn fixed_decimals_drop_the_sign_of_zero_only() {
        let empty_sum: f64 = std::iter::empty::<f64>().sum();
        assert_eq!(
            format!("{empty_sum:.4}"),
            "-0.0000",
            "Rust's empty sum is -0.0"
        );
        assert_eq!(Fixed(empty_sum, 4).to_string(), "0.0000");
        assert_eq!(Fixed(-2e-9, 3).to_string(), "0.000");
        assert_eq!(Fixed(-0.0006, 3).to_string(), "-0.001");
        assert_eq!(Fixed(-12.5, 1).to_string(), "-12.5");
        assert_eq!(
            Fixed(1234.56789, 4).to_string(),
            format!("{:.4}", 1234.56789)
        );
        assert_eq!(Fixed(f64::NAN, 3).to_string(), "NaN");
    }
}
