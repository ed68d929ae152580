// Shared by the slab stages (density, classify, compact, emit): the per-slab uniform. The Rust
// side prepends this file to each of those shaders (src/gpu/shaders.rs), so it is written once.

// Twin of crate::gpu::types::SlabUniform (128 bytes).
struct SlabUniform {
    origin: vec3<f32>,
    spacing: f32,
    dims: vec3<u32>,
    isovalue: f32,
    cell_origin: vec3<f32>,
    cell_size: f32,
    cell_dims: vec3<u32>,
    cutoff: f32,
    dens_z0: u32,
    dens_layers: u32,
    own_z0: u32,
    own_z1: u32,
    class_points: u32,
    class_layers: u32,
    max_cut: f32,
    has_extra_layer: u32,
    centre: vec3<f32>,
    atom_count: u32,
    brick_dims: vec3<u32>,
    sparse: u32,
}
