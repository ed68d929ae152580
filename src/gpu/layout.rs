//! Every binding of the compute shaders, named once: number, WGSL variable name and kind. The
//! kernels build explicit bind-group layouts from these tables ([`super::kernel::Layout`]) and
//! fill bind groups by the same names, so no binding number is written twice on the Rust side;
//! [`check_against_wgsl`] (run by the tests) parses the assembled WGSL with naga and fails when a
//! shader's `@binding` disagrees with its table (number, address space, access) or declares a
//! binding the table does not name. All bindings are in group 0.

/// What a binding holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// `var<uniform>`, bound whole.
    Uniform,
    /// `var<uniform>` of this many bytes at a dynamic offset (one buffer, one slot per slab).
    DynamicUniform(u64),
    /// `var<storage, read>`.
    Read,
    /// `var<storage, read_write>`.
    ReadWrite,
}

/// One binding of group 0.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Slot {
    /// `@binding(n)`.
    pub binding: u32,
    /// The WGSL variable's name.
    pub name: &'static str,
    /// What it holds.
    pub kind: Kind,
}

pub(crate) const fn slot(binding: u32, name: &'static str, kind: Kind) -> Slot {
    Slot {
        binding,
        name,
        kind,
    }
}

use Kind::{DynamicUniform, Read, ReadWrite, Uniform};

/// `shaders/bin.wgsl`.
pub mod bin {
    use super::*;
    /// [`crate::gpu::types::BinUniform`].
    pub const U: Slot = slot(0, "u", Uniform);
    /// Positions.
    pub const POSITIONS: Slot = slot(1, "positions", Read);
    /// Radii.
    pub const RADII: Slot = slot(2, "radii", Read);
    /// Packed colours.
    pub const COLOURS: Slot = slot(3, "colours", Read);
    /// Atom counts per cell (the cell-start buffer before its scan).
    pub const CELL_COUNT: Slot = slot(4, "cell_count", ReadWrite);
    /// First slot per cell.
    pub const CELL_START: Slot = slot(5, "cell_start", Read);
    /// Fill cursors, then one past the last slot per cell.
    pub const CELL_END: Slot = slot(6, "cell_end", ReadWrite);
    /// Sorted atoms.
    pub const SORTED_ATOMS: Slot = slot(7, "sorted_atoms", ReadWrite);
    /// Sorted colours.
    pub const SORTED_COLOURS: Slot = slot(8, "sorted_colours", ReadWrite);
    /// Layout of `count`.
    pub const COUNT: &[Slot] = &[U, POSITIONS, CELL_COUNT];
    /// Layout of `copy_starts`.
    pub const COPY_STARTS: &[Slot] = &[U, CELL_START, CELL_END];
    /// Layout of `scatter`.
    pub const SCATTER: &[Slot] = &[
        U,
        POSITIONS,
        RADII,
        COLOURS,
        CELL_END,
        SORTED_ATOMS,
        SORTED_COLOURS,
    ];
    /// Layout of `sort_cells`.
    pub const SORT_CELLS: &[Slot] = &[U, CELL_START, CELL_END, SORTED_ATOMS, SORTED_COLOURS];
    /// Every binding of the file.
    pub const ALL: &[Slot] = &[
        U,
        POSITIONS,
        RADII,
        COLOURS,
        CELL_COUNT,
        CELL_START,
        CELL_END,
        SORTED_ATOMS,
        SORTED_COLOURS,
    ];
}

/// `shaders/scan.wgsl` (both entry points share one layout).
pub mod scan {
    use super::*;
    /// [`crate::gpu::types::ScanUniform`] of one level.
    pub const U: Slot = slot(0, "su", Uniform);
    /// The level's data, scanned in place.
    pub const DATA: Slot = slot(1, "data", ReadWrite);
    /// Block totals (the next level's data), or the word the grand total goes to.
    pub const SUMS: Slot = slot(2, "sums", ReadWrite);
    /// Every binding (the layout of both entry points).
    pub const ALL: &[Slot] = &[U, DATA, SUMS];
}

/// Size of [`crate::gpu::types::SlabUniform`], bound at a dynamic offset per slab.
const SLAB: Kind = DynamicUniform(size_of::<crate::gpu::types::SlabUniform>() as u64);

/// `shaders/density.wgsl` (every variant shares one layout).
pub mod density {
    use super::*;
    /// The slab uniform.
    pub const U: Slot = slot(0, "u", SLAB);
    /// Sorted atoms.
    pub const SORTED_ATOMS: Slot = slot(1, "sorted_atoms", Read);
    /// Sorted colours.
    pub const SORTED_COLOURS: Slot = slot(2, "sorted_colours", Read);
    /// First slot per cell.
    pub const CELL_START: Slot = slot(3, "cell_start", Read);
    /// One past the last slot per cell.
    pub const CELL_END: Slot = slot(4, "cell_end", Read);
    /// Slab density.
    pub const DENSITY: Slot = slot(5, "density", ReadWrite);
    /// Slab colour volume.
    pub const COLOUR: Slot = slot(6, "colour", ReadWrite);
    /// The list of reached sparse bricks (count first; `shaders/bricks.wgsl`).
    pub const ACTIVE_BRICKS: Slot = slot(7, "active_bricks", Read);
    /// Frame counters (the sparse pass sets an overflow bit when a slab's reached bricks do
    /// not fit the brick slots).
    pub const COUNTERS: Slot = slot(8, "counters", ReadWrite);
    /// Every binding (the layout).
    pub const ALL: &[Slot] = &[
        U,
        SORTED_ATOMS,
        SORTED_COLOURS,
        CELL_START,
        CELL_END,
        DENSITY,
        COLOUR,
        ACTIVE_BRICKS,
        COUNTERS,
    ];
}

/// `shaders/classify.wgsl`.
pub mod classify {
    use super::*;
    /// The slab uniform.
    pub const U: Slot = slot(0, "u", SLAB);
    /// Slab density.
    pub const DENSITY: Slot = slot(1, "density", Read);
    /// Marching Cubes tables.
    pub const MC: Slot = slot(2, "mc", Uniform);
    /// Class words.
    pub const CLASSES: Slot = slot(3, "classes", ReadWrite);
    /// Vertices per block.
    pub const BLOCK_VERTICES: Slot = slot(4, "block_vertices", ReadWrite);
    /// Triangles per block.
    pub const BLOCK_TRIANGLES: Slot = slot(5, "block_triangles", ReadWrite);
    /// Active cells per block.
    pub const BLOCK_ACTIVE: Slot = slot(6, "block_active", ReadWrite);
    /// Per sparse brick: reached by some atom (`shaders/bricks.wgsl`).
    pub const BRICK_FLAGS: Slot = slot(7, "brick_flags", Read);
    /// Frame counters (sparse classes flag a class entry past the buffers).
    pub const COUNTERS: Slot = slot(8, "counters", ReadWrite);
    /// Every binding (the layout).
    pub const ALL: &[Slot] = &[
        U,
        DENSITY,
        MC,
        CLASSES,
        BLOCK_VERTICES,
        BLOCK_TRIANGLES,
        BLOCK_ACTIVE,
        BRICK_FLAGS,
        COUNTERS,
    ];
}

/// `shaders/bricks.wgsl` (sparse bricks).
pub mod bricks {
    use super::*;
    /// [`crate::gpu::types::BrickUniform`].
    pub const U: Slot = slot(0, "u", Uniform);
    /// Sorted atoms.
    pub const SORTED_ATOMS: Slot = slot(1, "sorted_atoms", Read);
    /// First slot per cell.
    pub const CELL_START: Slot = slot(2, "cell_start", Read);
    /// One past the last slot per cell.
    pub const CELL_END: Slot = slot(3, "cell_end", Read);
    /// Per brick: reached by some atom.
    pub const BRICK_FLAGS: Slot = slot(4, "brick_flags", ReadWrite);
    /// Per brick: the flag, scanned in place into list slots.
    pub const BRICK_SCAN: Slot = slot(5, "brick_scan", ReadWrite);
    /// Count, then the reached bricks' ids.
    pub const ACTIVE_BRICKS: Slot = slot(6, "active_bricks", ReadWrite);
    /// Indirect dispatch arguments and the scan total.
    pub const BRICK_ARGS: Slot = slot(7, "brick_args", ReadWrite);
    /// The density buffer, whose first words `compact` fills with the brick slot table.
    pub const DENSITY: Slot = slot(8, "density", ReadWrite);
    /// Layout of `mark`.
    pub const MARK: &[Slot] = &[
        U,
        SORTED_ATOMS,
        CELL_START,
        CELL_END,
        BRICK_FLAGS,
        BRICK_SCAN,
    ];
    /// Layout of `compact`.
    pub const COMPACT: &[Slot] = &[U, BRICK_FLAGS, BRICK_SCAN, ACTIVE_BRICKS, DENSITY];
    /// Layout of `args`.
    pub const ARGS: &[Slot] = &[U, ACTIVE_BRICKS, BRICK_ARGS];
    /// Every binding of the file.
    pub const ALL: &[Slot] = &[
        U,
        SORTED_ATOMS,
        CELL_START,
        CELL_END,
        BRICK_FLAGS,
        BRICK_SCAN,
        ACTIVE_BRICKS,
        BRICK_ARGS,
        DENSITY,
    ];
}

/// `shaders/compact.wgsl`.
pub mod compact {
    use super::*;
    /// The slab uniform.
    pub const U: Slot = slot(0, "u", SLAB);
    /// Class words.
    pub const CLASSES: Slot = slot(1, "classes", Read);
    /// Scanned vertices per block.
    pub const BLOCK_VERTICES: Slot = slot(2, "block_vertices", Read);
    /// Scanned triangles per block.
    pub const BLOCK_TRIANGLES: Slot = slot(3, "block_triangles", Read);
    /// Scanned active cells per block.
    pub const BLOCK_ACTIVE: Slot = slot(4, "block_active", Read);
    /// Frame counters.
    pub const COUNTERS: Slot = slot(5, "counters", ReadWrite);
    /// Vertex base per point.
    pub const VERTEX_BASE: Slot = slot(6, "vertex_base", ReadWrite);
    /// Active cells.
    pub const ACTIVE: Slot = slot(7, "active_cells", ReadWrite);
    /// Slab density (its brick slot table locates sparse class entries).
    pub const DENSITY: Slot = slot(8, "density", Read);
    /// Every binding (the layout).
    pub const ALL: &[Slot] = &[
        U,
        CLASSES,
        BLOCK_VERTICES,
        BLOCK_TRIANGLES,
        BLOCK_ACTIVE,
        COUNTERS,
        VERTEX_BASE,
        ACTIVE,
        DENSITY,
    ];
}

/// `shaders/emit.wgsl` (both variants share one layout).
pub mod emit {
    use super::*;
    /// The slab uniform.
    pub const U: Slot = slot(0, "u", SLAB);
    /// Slab density.
    pub const DENSITY: Slot = slot(1, "density", Read);
    /// Slab colour volume.
    pub const COLOUR: Slot = slot(2, "colour", Read);
    /// Class words.
    pub const CLASSES: Slot = slot(3, "classes", Read);
    /// Vertex base per point.
    pub const VERTEX_BASE: Slot = slot(4, "vertex_base", Read);
    /// Active cells.
    pub const ACTIVE: Slot = slot(5, "active_cells", Read);
    /// Marching Cubes tables.
    pub const MC: Slot = slot(6, "mc", Uniform);
    /// Frame counters.
    pub const COUNTERS: Slot = slot(8, "counters", ReadWrite);
    /// Output vertices.
    pub const VERTICES: Slot = slot(9, "vertices", ReadWrite);
    /// Output indices.
    pub const INDICES: Slot = slot(10, "indices", ReadWrite);
    /// Every binding (the layout).
    pub const ALL: &[Slot] = &[
        U,
        DENSITY,
        COLOUR,
        CLASSES,
        VERTEX_BASE,
        ACTIVE,
        MC,
        COUNTERS,
        VERTICES,
        INDICES,
    ];
}

/// `shaders/refine.wgsl` (issue 13: refined vertices; eight storage buffers, so the cell
/// starts are read as the previous cell's end).
pub mod refine {
    use super::*;
    /// The slab uniform.
    pub const U: Slot = slot(0, "u", SLAB);
    /// Slab density.
    pub const DENSITY: Slot = slot(1, "density", Read);
    /// Class words.
    pub const CLASSES: Slot = slot(2, "classes", Read);
    /// Vertex base per point.
    pub const VERTEX_BASE: Slot = slot(3, "vertex_base", Read);
    /// Active cells.
    pub const ACTIVE: Slot = slot(4, "active_cells", Read);
    /// Sorted atoms.
    pub const SORTED_ATOMS: Slot = slot(5, "sorted_atoms", Read);
    /// One past the last slot per cell.
    pub const CELL_END: Slot = slot(6, "cell_end", Read);
    /// Frame counters (read only here).
    pub const COUNTERS: Slot = slot(7, "counters", Read);
    /// The emitted vertices, refined in place.
    pub const VERTICES: Slot = slot(8, "vertices", ReadWrite);
    /// Every binding (the layout).
    pub const ALL: &[Slot] = &[
        U,
        DENSITY,
        CLASSES,
        VERTEX_BASE,
        ACTIVE,
        SORTED_ATOMS,
        CELL_END,
        COUNTERS,
        VERTICES,
    ];
}

/// `shaders/measure.wgsl`.
pub mod measure {
    use super::*;
    /// [`crate::gpu::types::MeasureUniform`].
    pub const U: Slot = slot(0, "mu", Uniform);
    /// Frame counters.
    pub const COUNTERS: Slot = slot(1, "counters", ReadWrite);
    /// Output vertices.
    pub const VERTICES: Slot = slot(2, "vertices", Read);
    /// Output indices.
    pub const INDICES: Slot = slot(3, "indices", Read);
    /// Area/volume partial sums.
    pub const PARTIALS: Slot = slot(4, "partials", ReadWrite);
    /// Emit dispatch arguments.
    pub const DISPATCH_ARGS: Slot = slot(5, "dispatch_args", ReadWrite);
    /// Indirect draw arguments.
    pub const DRAW_ARGS: Slot = slot(6, "draw_args", ReadWrite);
    /// Atoms sorted by cell (sharp triangles are measured on their Gaussian sum).
    pub const SORTED_ATOMS: Slot = slot(7, "sorted_atoms", Read);
    /// Inclusive cell ends of the binning.
    pub const CELL_END: Slot = slot(8, "cell_end", Read);
    /// Layout of `slab_begin`.
    pub const SLAB_BEGIN: &[Slot] = &[U, COUNTERS, DISPATCH_ARGS];
    /// Layout of `slab_end`.
    pub const SLAB_END: &[Slot] = &[COUNTERS];
    /// Layout of `frame_end`.
    pub const FRAME_END: &[Slot] = &[COUNTERS, DRAW_ARGS];
    /// Layout of `partial_sums`.
    pub const PARTIAL_SUMS: &[Slot] = &[
        U,
        COUNTERS,
        VERTICES,
        INDICES,
        PARTIALS,
        SORTED_ATOMS,
        CELL_END,
    ];
    /// Layout of `final_sum`.
    pub const FINAL_SUM: &[Slot] = &[COUNTERS, PARTIALS];
    /// Every binding of the file.
    pub const ALL: &[Slot] = &[
        U,
        COUNTERS,
        VERTICES,
        INDICES,
        PARTIALS,
        DISPATCH_ARGS,
        DRAW_ARGS,
        SORTED_ATOMS,
        CELL_END,
    ];
}

/// Every compute shader file with all its bindings.
pub const SHADERS: &[(&str, &[Slot])] = &[
    ("bin.wgsl", bin::ALL),
    ("scan.wgsl", scan::ALL),
    ("bricks.wgsl", bricks::ALL),
    ("density.wgsl", density::ALL),
    ("classify.wgsl", classify::ALL),
    ("compact.wgsl", compact::ALL),
    ("emit.wgsl", emit::ALL),
    ("refine.wgsl", refine::ALL),
    ("measure.wgsl", measure::ALL),
    ("exposure.wgsl", crate::gpu::exposure::slots::ALL),
];

/// One disagreement between a binding table and the WGSL; one line naming the shader file.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BindingMismatch {
    /// A shader file with no table in [`SHADERS`].
    #[error("{file}: no binding table in gpu::layout::SHADERS")]
    NoTable {
        /// The shader file.
        file: &'static str,
    },
    /// The assembled WGSL does not parse (naga's report).
    #[error("{file}: {message}")]
    Parse {
        /// The shader file.
        file: &'static str,
        /// What naga said.
        message: String,
    },
    /// A WGSL binding the table does not name.
    #[error("{file}: `{name}` is not named in gpu::layout")]
    NotNamed {
        /// The shader file.
        file: &'static str,
        /// The WGSL variable.
        name: String,
    },
    /// A binding whose group, number or kind differs between WGSL and table.
    #[error(
        "{file}: `{name}` is @group({group}) @binding({binding}) {kind} in WGSL but @group(0) @binding({table_binding}) {want} in gpu::layout"
    )]
    Differs {
        /// The shader file.
        file: &'static str,
        /// The WGSL variable.
        name: String,
        /// Its group in the WGSL.
        group: u32,
        /// Its binding number in the WGSL.
        binding: u32,
        /// Its kind in the WGSL (uniform, read, read_write, other).
        kind: &'static str,
        /// Its binding number in the table.
        table_binding: u32,
        /// Its kind in the table.
        want: &'static str,
    },
    /// A table entry the WGSL does not declare.
    #[error("{file}: `{name}` is not declared in the WGSL")]
    NotDeclared {
        /// The shader file.
        file: &'static str,
        /// The table's variable name.
        name: &'static str,
    },
}

/// Every disagreement found by [`check_against_wgsl`], one per line.
#[derive(Debug, Clone, PartialEq)]
pub struct BindingMismatches(pub Vec<BindingMismatch>);

impl std::fmt::Display for BindingMismatches {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        for (i, m) in self.0.iter().enumerate() {
            if i > 0 {
                writeln!(f)?;
            }
            write!(f, "{m}")?;
        }
        Ok(())
    }
}

impl std::error::Error for BindingMismatches {}

/// Compares every table of [`SHADERS`] with the `@group(0) @binding(n)` declarations of the
/// assembled WGSL ([`super::shaders::ALL`]): same variables, numbers, address spaces and access.
/// Returns every disagreement.
pub fn check_against_wgsl() -> Result<(), BindingMismatches> {
    let mut errors = Vec::new();
    for &(file, source) in super::shaders::ALL {
        let Some((_, slots)) = SHADERS.iter().find(|(f, _)| *f == file) else {
            errors.push(BindingMismatch::NoTable { file });
            continue;
        };
        let module = match naga::front::wgsl::parse_str(source) {
            Ok(m) => m,
            Err(e) => {
                errors.push(BindingMismatch::Parse {
                    file,
                    message: e.emit_to_string(source),
                });
                continue;
            }
        };
        let mut seen = Vec::new();
        for (_, var) in module.global_variables.iter() {
            let Some(rb) = &var.binding else { continue };
            let name = var.name.as_deref().unwrap_or("?");
            let kind = match var.space {
                naga::AddressSpace::Uniform => "uniform",
                naga::AddressSpace::Storage { access } => {
                    if access.contains(naga::StorageAccess::STORE) {
                        "read_write"
                    } else {
                        "read"
                    }
                }
                _ => "other",
            };
            let Some(s) = slots.iter().find(|s| s.name == name) else {
                errors.push(BindingMismatch::NotNamed {
                    file,
                    name: name.to_string(),
                });
                continue;
            };
            seen.push(s.name);
            let want = match s.kind {
                Uniform | DynamicUniform(_) => "uniform",
                Read => "read",
                ReadWrite => "read_write",
            };
            if rb.group != 0 || rb.binding != s.binding || kind != want {
                errors.push(BindingMismatch::Differs {
                    file,
                    name: name.to_string(),
                    group: rb.group,
                    binding: rb.binding,
                    kind,
                    table_binding: s.binding,
                    want,
                });
            }
        }
        for s in slots.iter().filter(|s| !seen.contains(&s.name)) {
            errors.push(BindingMismatch::NotDeclared { file, name: s.name });
        }
    }
    if errors.is_empty() {
        Ok(())
    } else {
        Err(BindingMismatches(errors))
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn tables_match_the_wgsl() {
        if let Err(e) = super::check_against_wgsl() {
            panic!("{e}");
        }
    }
}
