// The frame counters' word indices and overflow bits, written once. Prepended by
// src/gpu/shaders.rs to every stage that touches the counters (density, classify, compact, emit,
// refine, measure); the unit test `prelude_constants_match_their_rust_twins` there checks each
// value against the Rust side.

// Twin of crate::gpu::types::GpuCounters (64 bytes), viewed as u32 words: the word of each field.
const C_VERTEX_COUNT: u32 = 0u;
const C_TRIANGLE_COUNT: u32 = 1u;
const C_OVERFLOW: u32 = 2u;
const C_SLAB_VERTEX_BASE: u32 = 3u;
const C_SLAB_TRIANGLE_BASE: u32 = 4u;
const C_SLAB_OWNED_VERTICES: u32 = 5u;
const C_SCAN_ACTIVE: u32 = 6u;
const C_SCAN_VERTICES: u32 = 7u;
const C_SCAN_TRIANGLES: u32 = 8u;
const C_AREA: u32 = 9u;
const C_VOLUME: u32 = 10u;
const C_VERTEX_CAPACITY: u32 = 11u;
const C_TRIANGLE_CAPACITY: u32 = 12u;
const C_ACTIVE_TOTAL: u32 = 13u;
const C_REACHED_BRICKS: u32 = 14u;
const C_BRICK_SLOTS: u32 = 15u;

// Bits of the word C_OVERFLOW (crate::gpu::types::{OVERFLOW_VERTICES, OVERFLOW_TRIANGLES,
// OVERFLOW_BRICKS}): vertex buffer too small, index buffer too small, a slab's reached bricks
// did not fit the brick slots (or its class entries the class buffers).
const OVERFLOW_VERTICES: u32 = 1u;
const OVERFLOW_TRIANGLES: u32 = 2u;
const OVERFLOW_BRICKS: u32 = 4u;
