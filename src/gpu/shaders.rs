//! The WGSL source of every compute stage, as the device compiles it. The four slab stages share
//! one uniform struct (`shaders/slab_uniform.wgsl`, twin of [`super::types::SlabUniform`]),
//! which is prepended here so it is written once; the naga validation test checks these very
//! strings.

/// Binning: count, scatter and per-cell sort (`shaders/bin.wgsl`).
pub const BIN: &str = include_str!("../../shaders/bin.wgsl");
/// Multi-level exclusive prefix sums (`shaders/scan.wgsl`).
pub const SCAN: &str = include_str!("../../shaders/scan.wgsl");
/// Sparse bricks: mark, compact, indirect arguments (`shaders/bricks.wgsl`).
pub const BRICKS: &str = include_str!("../../shaders/bricks.wgsl");
/// Density and colour gather (`shaders/density.wgsl` after the slab uniform).
pub const DENSITY: &str = concat!(
    include_str!("../../shaders/slab_uniform.wgsl"),
    include_str!("../../shaders/density.wgsl")
);
/// Marching Cubes cell classification (`shaders/classify.wgsl` after the slab uniform and the
/// shared sample reads, `shaders/brick_samples.wgsl`).
pub const CLASSIFY: &str = concat!(
    include_str!("../../shaders/slab_uniform.wgsl"),
    include_str!("../../shaders/brick_samples.wgsl"),
    include_str!("../../shaders/class_entries.wgsl"),
    include_str!("../../shaders/classify.wgsl")
);
/// Marching Cubes compaction of active cells (`shaders/compact.wgsl` after the slab uniform).
pub const COMPACT: &str = concat!(
    include_str!("../../shaders/slab_uniform.wgsl"),
    include_str!("../../shaders/brick_samples.wgsl"),
    include_str!("../../shaders/class_entries.wgsl"),
    include_str!("../../shaders/compact.wgsl")
);
/// Marching Cubes vertex and triangle emission (`shaders/emit.wgsl` after the slab uniform and
/// `shaders/brick_samples.wgsl`).
pub const EMIT: &str = concat!(
    include_str!("../../shaders/slab_uniform.wgsl"),
    include_str!("../../shaders/brick_samples.wgsl"),
    include_str!("../../shaders/class_entries.wgsl"),
    include_str!("../../shaders/emit.wgsl")
);
/// Refined vertices on the exact Gaussian sum (`shaders/refine.wgsl` after the slab uniform,
/// `shaders/brick_samples.wgsl` and the sum itself, `shaders/field.wgsl`).
pub const REFINE: &str = concat!(
    include_str!("../../shaders/slab_uniform.wgsl"),
    include_str!("../../shaders/brick_samples.wgsl"),
    include_str!("../../shaders/class_entries.wgsl"),
    include_str!("../../shaders/field.wgsl"),
    include_str!("../../shaders/refine.wgsl")
);
/// Area, volume and indirect draw arguments (`shaders/measure.wgsl` after the exact Gaussian
/// sum, `shaders/field.wgsl`, which its sharp triangles are measured on).
pub const MEASURE: &str = concat!(
    include_str!("../../shaders/field.wgsl"),
    include_str!("../../shaders/measure.wgsl")
);

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
];
