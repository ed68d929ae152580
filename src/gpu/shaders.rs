//! The WGSL source of every compute stage, as the device compiles it. What several stages share
//! is written once and prepended here:
//!
//! - the preludes of constants: `shaders/counters.wgsl` (the word of each
//!   [`super::types::GpuCounters`] field, `C_*`, and the overflow bits, `OVERFLOW_*`),
//!   `shaders/brick_const.wgsl` (the sparse-brick size [`super::plan::BRICK`], class apron, slot
//!   table bit and the "none" sentinels) and `shaders/mc_tables.wgsl` (the layout of
//!   [`super::types::McTablesUniform`]), each prepended once to every stage that uses it
//!   ([`PRELUDES`]; a unit test checks every constant in them against its Rust twin);
//! - the slab uniform struct (`shaders/slab_uniform.wgsl`, twin of
//!   [`super::types::SlabUniform`]) of the slab stages;
//! - shared functions: the density sample reads (`shaders/brick_samples.wgsl`), the class entry
//!   lookup (`shaders/class_entries.wgsl`) and the exact Gaussian sum (`shaders/field.wgsl`).
//!
//! The naga validation test checks these very strings.

/// The concatenation of the named files of `shaders/`, in order.
macro_rules! wgsl {
    ($($file:literal),+ $(,)?) => {
        concat!($(include_str!(concat!("../../shaders/", $file))),+)
    };
}

/// The preludes of constants as `(file name, source)`; each holds only `const` declarations
/// (and, in `mc_tables.wgsl`, the struct they size), so it parses on its own.
pub const PRELUDES: &[(&str, &str)] = &[
    ("counters.wgsl", wgsl!("counters.wgsl")),
    ("brick_const.wgsl", wgsl!("brick_const.wgsl")),
    ("mc_tables.wgsl", wgsl!("mc_tables.wgsl")),
];

/// Binning: count, scatter and per-cell sort (`shaders/bin.wgsl`).
pub const BIN: &str = wgsl!("bin.wgsl");
/// Multi-level exclusive prefix sums (`shaders/scan.wgsl`).
pub const SCAN: &str = wgsl!("scan.wgsl");
/// Sparse bricks: mark, compact, indirect arguments (`shaders/bricks.wgsl` after the brick
/// constants).
pub const BRICKS: &str = wgsl!("brick_const.wgsl", "bricks.wgsl");
/// Density and colour gather (`shaders/density.wgsl` after the counter and brick constants and
/// the slab uniform).
pub const DENSITY: &str = wgsl!(
    "counters.wgsl",
    "brick_const.wgsl",
    "slab_uniform.wgsl",
    "density.wgsl"
);
/// Marching Cubes cell classification (`shaders/classify.wgsl` after the counter, brick and table
/// constants, the slab uniform, the shared sample reads, `shaders/brick_samples.wgsl`, and class
/// entries, `shaders/class_entries.wgsl`).
pub const CLASSIFY: &str = wgsl!(
    "counters.wgsl",
    "brick_const.wgsl",
    "mc_tables.wgsl",
    "slab_uniform.wgsl",
    "brick_samples.wgsl",
    "class_entries.wgsl",
    "classify.wgsl"
);
/// Marching Cubes compaction of active cells (`shaders/compact.wgsl` after the counter and brick
/// constants, the slab uniform, `shaders/brick_samples.wgsl` and `shaders/class_entries.wgsl`).
pub const COMPACT: &str = wgsl!(
    "counters.wgsl",
    "brick_const.wgsl",
    "slab_uniform.wgsl",
    "brick_samples.wgsl",
    "class_entries.wgsl",
    "compact.wgsl"
);
/// Marching Cubes vertex and triangle emission (`shaders/emit.wgsl` after the counter, brick and
/// table constants, the slab uniform, `shaders/brick_samples.wgsl` and
/// `shaders/class_entries.wgsl`).
pub const EMIT: &str = wgsl!(
    "counters.wgsl",
    "brick_const.wgsl",
    "mc_tables.wgsl",
    "slab_uniform.wgsl",
    "brick_samples.wgsl",
    "class_entries.wgsl",
    "emit.wgsl"
);
/// Refined vertices on the exact Gaussian sum (`shaders/refine.wgsl` after the counter and brick
/// constants, the slab uniform, `shaders/brick_samples.wgsl`, `shaders/class_entries.wgsl` and
/// the sum itself, `shaders/field.wgsl`).
pub const REFINE: &str = wgsl!(
    "counters.wgsl",
    "brick_const.wgsl",
    "slab_uniform.wgsl",
    "brick_samples.wgsl",
    "class_entries.wgsl",
    "field.wgsl",
    "refine.wgsl"
);
/// Area, volume and indirect draw arguments (`shaders/measure.wgsl` after the counter constants
/// and the exact Gaussian sum, `shaders/field.wgsl`, which its sharp triangles are measured on).
pub const MEASURE: &str = wgsl!("counters.wgsl", "field.wgsl", "measure.wgsl");

/// Exposure counts and radii of the SES preset (`shaders/exposure.wgsl`).
pub const EXPOSURE: &str = wgsl!("exposure.wgsl");

/// Every compute stage as `(file name, full source)`, for validation.
pub const ALL: &[(&str, &str)] = &[
    ("bin.wgsl", BIN),
    ("scan.wgsl", SCAN),
    ("bricks.wgsl", BRICKS),
    ("density.wgsl", DENSITY),
    ("classify.wgsl", CLASSIFY),
    ("compact.wgsl", COMPACT),
    ("emit.wgsl", EMIT),
    ("refine.wgsl", REFINE),
    ("measure.wgsl", MEASURE),
    ("exposure.wgsl", EXPOSURE),
];

#[cfg(test)]
mod tests {
    use std::collections::BTreeMap;
    use std::mem::{offset_of, size_of};

    use super::super::plan::{BRICK, CLASS_ENTRIES_PER_SLOT, SlotTable};
    use super::super::types::{self, GpuCounters};

    /// Every `const` of the preludes, by name, as naga evaluates it (u32 constants only: any
    /// other type, or a name declared twice, fails).
    fn prelude_constants() -> BTreeMap<String, u64> {
        let mut constants = BTreeMap::new();
        for &(file, source) in super::PRELUDES {
            let module = naga::front::wgsl::parse_str(source)
                .unwrap_or_else(|e| panic!("{file}: {}", e.emit_to_string(source)));
            for (_, c) in module.constants.iter() {
                let name = c.name.clone().expect("named constant");
                let value = match module.global_expressions[c.init] {
                    naga::Expression::Literal(naga::Literal::U32(v)) => u64::from(v),
                    ref other => panic!("{file}: `{name}` is not a u32 literal: {other:?}"),
                };
                assert!(
                    constants.insert(name.clone(), value).is_none(),
                    "{file}: `{name}` is declared in two preludes"
                );
            }
        }
        constants
    }

    /// The Rust value each prelude constant mirrors.
    fn rust_twins() -> BTreeMap<String, u64> {
        macro_rules! word {
            ($field:ident) => {
                (offset_of!(GpuCounters, $field) / 4) as u64
            };
        }
        let words = [
            ("C_VERTEX_COUNT", word!(vertex_count)),
            ("C_TRIANGLE_COUNT", word!(triangle_count)),
            ("C_OVERFLOW", word!(overflow)),
            ("C_SLAB_VERTEX_BASE", word!(slab_vertex_base)),
            ("C_SLAB_TRIANGLE_BASE", word!(slab_triangle_base)),
            ("C_SLAB_OWNED_VERTICES", word!(slab_owned_vertices)),
            ("C_SCAN_ACTIVE", word!(scan_active)),
            ("C_SCAN_VERTICES", word!(scan_vertices)),
            ("C_SCAN_TRIANGLES", word!(scan_triangles)),
            ("C_AREA", word!(area)),
            ("C_VOLUME", word!(volume)),
            ("C_VERTEX_CAPACITY", word!(vertex_capacity)),
            ("C_TRIANGLE_CAPACITY", word!(triangle_capacity)),
            ("C_ACTIVE_TOTAL", word!(active_total)),
            ("C_REACHED_BRICKS", word!(reached_bricks)),
            ("C_BRICK_SLOTS", word!(brick_slots)),
        ];
        // Every word of the counters is named (a new field needs its `C_*`).
        assert_eq!(words.len() * 4, size_of::<GpuCounters>());
        // The word indices the Rust side uses itself.
        assert_eq!(u64::from(types::C_SCAN_ACTIVE), word!(scan_active));
        assert_eq!(u64::from(types::C_SCAN_VERTICES), word!(scan_vertices));
        assert_eq!(u64::from(types::C_SCAN_TRIANGLES), word!(scan_triangles));
        assert_eq!(u64::from(types::C_REACHED_BRICKS), word!(reached_bricks));
        let apron = (BRICK + 1) as u64;
        assert_eq!(apron * apron * apron, CLASS_ENTRIES_PER_SLOT);
        let others = [
            ("OVERFLOW_VERTICES", u64::from(types::OVERFLOW_VERTICES)),
            ("OVERFLOW_TRIANGLES", u64::from(types::OVERFLOW_TRIANGLES)),
            ("OVERFLOW_BRICKS", u64::from(types::OVERFLOW_BRICKS)),
            ("BRICK", u64::from(BRICK)),
            ("CLASS_APRON", apron),
            ("SLOT_UNREACHED", u64::from(SlotTable::UNREACHED)),
            // Sentinels outside every index; no Rust constant.
            ("NO_SAMPLE", u64::from(u32::MAX)),
            ("NO_ENTRY", u64::from(u32::MAX)),
            ("MC_TRI_BASE", types::MC_TRI_BASE as u64),
            ("MC_TABLE_ROWS", types::MC_TABLE_ROWS as u64),
        ];
        words
            .into_iter()
            .chain(others)
            .map(|(n, v)| (n.to_string(), v))
            .collect()
    }

    #[test]
    fn prelude_constants_match_their_rust_twins() {
        let (wgsl, rust) = (prelude_constants(), rust_twins());
        let names: std::collections::BTreeSet<&String> = wgsl.keys().chain(rust.keys()).collect();
        let differ: Vec<String> = names
            .into_iter()
            .filter(|n| wgsl.get(*n) != rust.get(*n))
            .map(|n| format!("{n}: WGSL {:?}, Rust {:?}", wgsl.get(n), rust.get(n)))
            .collect();
        assert!(
            differ.is_empty(),
            "preludes and Rust disagree:\n{}",
            differ.join("\n")
        );
    }

    /// The overflow bits are distinct single bits.
    #[test]
    fn overflow_bits_are_distinct() {
        let bits = [
            types::OVERFLOW_VERTICES,
            types::OVERFLOW_TRIANGLES,
            types::OVERFLOW_BRICKS,
        ];
        assert!(bits.iter().all(|b| b.is_power_of_two()));
        assert_eq!(bits.iter().fold(0, |a, b| a | b).count_ones(), 3);
    }
}
