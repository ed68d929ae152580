//! Which parser reads a file, decided from its name before any parser touches it (so an unknown
//! or missing file gives a clean error instead of reaching the C++ library).

use std::path::Path;

use super::IoError;

/// What a file name says about its content.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FileFormat {
    /// The chemfiles format string, with a compression suffix when compressed (`GRO / GZ`).
    pub chemfiles: String,
    /// The format without compression (`GRO`).
    pub base: &'static str,
    /// True when the format carries atom names (so it can be its own topology).
    pub has_names: bool,
    /// Which wwPDB flavour this is, for the pdbtbx reader (uncompressed PDB and mmCIF only).
    pub wwpdb: Option<WwFormat>,
}

/// The two wwPDB file flavours pdbtbx reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WwFormat {
    /// Fixed-column PDB.
    Pdb,
    /// PDBx/mmCIF.
    Mmcif,
}

impl WwFormat {
    /// The pdbtbx name of this format.
    pub(crate) fn pdbtbx(self) -> pdbtbx::Format {
        match self {
            WwFormat::Pdb => pdbtbx::Format::Pdb,
            WwFormat::Mmcif => pdbtbx::Format::Mmcif,
        }
    }
}

/// The compression suffixes chemfiles reads itself, with its names for them.
const COMPRESSIONS: [(&str, &str); 3] = [("gz", "GZ"), ("bz2", "BZ2"), ("xz", "XZ")];

/// Extension (lower case) -> (chemfiles format, has atom names).
const FORMATS: [(&str, &str, bool); 16] = [
    ("pdb", "PDB", true),
    ("ent", "PDB", true),
    ("cif", "mmCIF", true),
    ("mmcif", "mmCIF", true),
    ("gro", "GRO", true),
    ("xtc", "XTC", false),
    ("trr", "TRR", false),
    ("dcd", "DCD", false),
    ("lammpstrj", "LAMMPS", true),
    ("lammpsdump", "LAMMPS", true),
    ("dump", "LAMMPS", true),
    ("xyz", "XYZ", true),
    ("tng", "TNG", true),
    ("nc", "Amber NetCDF", false),
    ("ncdf", "Amber NetCDF", false),
    ("mol2", "MOL2", true),
];

/// The format named `base` (`GRO`, `Amber NetCDF`) as the static name [`FileFormat::base`]
/// holds, or `None` when no format has that name.
#[cfg(feature = "chemfiles")]
pub(crate) fn base_named(base: &str) -> Option<&'static str> {
    FORMATS.iter().map(|f| f.1).find(|b| *b == base)
}

/// Checks that `path` is a readable regular file and names a known format.
pub fn detect(path: &Path) -> Result<FileFormat, IoError> {
    check_readable(path)?;
    detect_name(path)
}

/// The format `path`'s name says, without looking at the file (for a URL: its last path
/// segment, a query string or fragment left out, as in `traj.xtc?token=...`).
pub(crate) fn detect_name(path: &Path) -> Result<FileFormat, IoError> {
    let text = path.to_string_lossy();
    let end = text.find(['?', '#']).unwrap_or(text.len());
    let name = text[..end].rsplit('/').next().unwrap_or("").to_lowercase();
    let mut parts: Vec<&str> = name.split('.').skip(1).collect();
    let compression = match parts.last() {
        Some(last) => COMPRESSIONS
            .iter()
            .find(|(ext, _)| ext == last)
            .map(|(_, c)| *c),
        None => None,
    };
    if compression.is_some() {
        parts.pop();
    }
    let ext = parts.last().copied().unwrap_or("");
    let Some(&(_, base, has_names)) = FORMATS.iter().find(|(e, _, _)| *e == ext) else {
        let written = path
            .extension()
            .map(|e| e.to_string_lossy().into_owned())
            .unwrap_or_default();
        return Err(IoError::UnknownFormat {
            path: path.to_path_buf(),
            ext: written,
        });
    };
    let chemfiles = match compression {
        Some(c) => format!("{base} / {c}"),
        None => base.to_string(),
    };
    let wwpdb = match (base, compression) {
        ("PDB", None) => Some(WwFormat::Pdb),
        ("mmCIF", None) => Some(WwFormat::Mmcif),
        _ => None,
    };
    Ok(FileFormat {
        chemfiles,
        base,
        has_names,
        wwpdb,
    })
}

/// Fails with [`IoError::NotFound`] unless `path` exists and we may open it, with
/// [`IoError::NotAFile`] when it is not a regular file, with [`IoError::Empty`] when it is empty.
fn check_readable(path: &Path) -> Result<(), IoError> {
    let not_found = |reason: String| IoError::NotFound {
        path: path.to_path_buf(),
        reason,
    };
    let meta = std::fs::metadata(path).map_err(|e| not_found(e.to_string()))?;
    if !meta.is_file() {
        use std::os::unix::fs::FileTypeExt;
        let kind = meta.file_type();
        let what = if kind.is_dir() {
            "a folder"
        } else if kind.is_fifo() {
            "a pipe (such as `<(zcat FILE)`; mdsurf reads .gz, .bz2 and .xz files itself)"
        } else {
            "a device or socket"
        };
        return Err(IoError::NotAFile {
            path: path.to_path_buf(),
            what,
        });
    }
    std::fs::File::open(path).map_err(|e| not_found(e.to_string()))?;
    if meta.len() == 0 {
        return Err(IoError::Empty {
            path: path.to_path_buf(),
            what: "the file is empty",
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp_file(name: &str) -> (tempfile::TempDir, std::path::PathBuf) {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join(name);
        std::fs::write(&path, "x").expect("write");
        (dir, path)
    }

    #[test]
    fn compressed_names_get_a_compression_suffix() {
        let (_d, p) = temp_file("a.lammpstrj.bz2");
        let f = detect(&p).expect("known");
        assert_eq!(f.chemfiles, "LAMMPS / BZ2");
        assert!(f.wwpdb.is_none());
        let (_d, p) = temp_file("A.GRO.gz");
        assert_eq!(detect(&p).expect("known").chemfiles, "GRO / GZ");
    }

    #[test]
    fn wwpdb_only_for_plain_pdb_and_cif() {
        let (_d, p) = temp_file("x.cif");
        let f = detect(&p).expect("known");
        assert_eq!(f.base, "mmCIF");
        assert_eq!(f.wwpdb, Some(WwFormat::Mmcif));
    }

    #[test]
    fn unknown_extension_names_it() {
        let (_d, p) = temp_file("x.docx");
        let e = detect(&p).expect_err("unknown");
        assert!(e.to_string().contains("'docx'"), "{e}");
    }
}
