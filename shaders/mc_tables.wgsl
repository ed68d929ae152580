// The Marching Cubes tables' uniform layout, written once. Prepended by src/gpu/shaders.rs to
// the stages that read the tables (classify, emit), which bind it as `mc`; the unit test
// `prelude_constants_match_their_rust_twins` there checks the constants against the Rust side.

// Twin of crate::gpu::types::McTablesUniform: case starts in words 0..257
// (crate::surface::McTables::case_start), triangle edges, three per triangle, from word
// MC_TRI_BASE (crate::surface::McTables::triangles_flat_u32), in MC_TABLE_ROWS 16-byte rows.
// A uniform, as uniforms do not count against the device's 8 storage buffers per stage.
const MC_TRI_BASE: u32 = 260u;
const MC_TABLE_ROWS: u32 = 1025u;
struct McTablesUniform {
    words: array<vec4<u32>, MC_TABLE_ROWS>,
}
