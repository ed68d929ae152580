// Sparse-brick constants, written once. Prepended by src/gpu/shaders.rs to every stage that
// works on bricks (bricks, density, classify, compact, emit, refine); the unit test
// `prelude_constants_match_their_rust_twins` there checks each value against the Rust side.

// Samples per sparse-brick edge (crate::gpu::plan::BRICK); a brick holds BRICK^3 samples.
const BRICK: u32 = 8u;
// Class entries per brick slot edge on sparse classes, BRICK + 1 (shaders/class_entries.wgsl;
// crate::gpu::plan::CLASS_ENTRIES_PER_SLOT is its cube).
const CLASS_APRON: u32 = BRICK + 1u;
// The bit set on an unreached brick's word of the brick slot table (shaders/bricks.wgsl writes
// the table; crate::gpu::plan::SlotTable::UNREACHED); the other bits are the slot.
const SLOT_UNREACHED: u32 = 0x80000000u;
// "None" sentinels: the sample index of a point whose brick no atom reaches
// (shaders/brick_samples.wgsl) and the class entry of a point that has none
// (shaders/class_entries.wgsl). No Rust twin: u32::MAX, never a valid index.
const NO_SAMPLE: u32 = 0xffffffffu;
const NO_ENTRY: u32 = 0xffffffffu;
