//! Structs that cross to the GPU, defined once here (`#[repr(C)]` + bytemuck) and mirrored in the
//! WGSL files named on each (the WGSL side names its twin); sizes are asserted at compile time.

use bytemuck::{Pod, Zeroable};

/// Binning parameters. Twin: `BinUniform` in `shaders/bin.wgsl`.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct BinUniform {
    /// Corner of cell (0, 0, 0) in Å (the density grid origin).
    pub cell_origin: [f32; 3],
    /// Edge of one cubic cell in Å (at least the largest cutoff distance).
    pub cell_size: f32,
    /// Cells along x, y, z.
    pub cell_dims: [u32; 3],
    /// Number of atoms.
    pub atom_count: u32,
    /// Radius scale R (alpha = r * R).
    pub radius_scale: f32,
    /// Total number of cells.
    pub cell_count: u32,
    /// Padding to 16 bytes.
    pub _pad: [u32; 2],
}
const _: () = assert!(std::mem::size_of::<BinUniform>() == 48);

/// Exposure counting parameters ([`super::exposure`]). Twin: `ExposureUniform` in
/// `shaders/exposure.wgsl`.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, Pod, Zeroable)]
pub struct ExposureUniform {
    /// Corner of cell (0, 0, 0) in Å.
    pub cell_origin: [f32; 3],
    /// Edge of one cubic cell in Å.
    pub cell_size: f32,
    /// Cells along x, y, z.
    pub cell_dims: [u32; 3],
    /// Number of atoms.
    pub atom_count: u32,
    /// Number of heavy atoms.
    pub heavy_count: u32,
    /// Cell offsets in the offsets buffer.
    pub offset_count: u32,
    /// Count at which an atom stops counting (the model's saturation).
    pub cap: u32,
    /// Square of the counting radius in Å² (rounded as the host rounds it).
    pub radius_sq: f32,
    /// Always 0: keeps the squares of distances from being fused into multiply-adds.
    pub zero_bits: u32,
    /// Total number of cells.
    pub cell_count: u32,
    /// Padding to 16 bytes.
    pub _pad: [u32; 2],
}
const _: () = assert!(std::mem::size_of::<ExposureUniform>() == 64);

/// Exclusive-scan level parameters. Twin: `ScanUniform` in `shaders/scan.wgsl`.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct ScanUniform {
    /// Number of u32 elements scanned at this level.
    pub count: u32,
    /// Index in the `sums` binding where block 0's total goes.
    pub sum_index: u32,
    /// Padding to 16 bytes.
    pub _pad: [u32; 2],
}
const _: () = assert!(std::mem::size_of::<ScanUniform>() == 16);

/// Per-slab parameters of density, classification, compaction and emission.
/// Twin: `SlabUniform` in `shaders/slab_uniform.wgsl` (prepended to the four slab stages).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct SlabUniform {
    /// Grid origin in Å.
    pub origin: [f32; 3],
    /// Grid spacing H in Å.
    pub spacing: f32,
    /// Whole-grid samples along x, y, z.
    pub dims: [u32; 3],
    /// Isovalue I.
    pub isovalue: f32,
    /// Bin cell origin in Å.
    pub cell_origin: [f32; 3],
    /// Bin cell edge in Å.
    pub cell_size: f32,
    /// Bin cells along x, y, z.
    pub cell_dims: [u32; 3],
    /// Cutoff q in units of alpha.
    pub cutoff: f32,
    /// First z layer held in the slab's density buffer.
    pub dens_z0: u32,
    /// Number of z layers held in the density buffer (computed by this slab's density pass).
    pub dens_layers: u32,
    /// First z layer whose points/cells this slab owns.
    pub own_z0: u32,
    /// One past the last owned z layer.
    pub own_z1: u32,
    /// Points classified per slab (nx * ny * class_layers; the same for every slab).
    pub class_points: u32,
    /// Layers classified per slab (largest owned layer count + 1).
    pub class_layers: u32,
    /// Largest cutoff distance q * R * max(r) in Å.
    pub max_cut: f32,
    /// 1 when a layer above the owned ones exists (own_z1 < nz).
    pub has_extra_layer: u32,
    /// Centre of the grid in Å (volume reference point).
    pub centre: [f32; 3],
    /// Number of atoms.
    pub atom_count: u32,
    /// Bricks of [`crate::gpu::plan::BRICK`]^3 samples along x, y, z (covering the whole grid).
    pub brick_dims: [u32; 3],
    /// 1 when the frame runs on sparse bricks: the density pass covers only the bricks some
    /// atom reaches (the rest stays zeroed) and classification skips points far from them.
    pub sparse: u32,
}
const _: () = assert!(std::mem::size_of::<SlabUniform>() == 128);

/// Parameters of the sparse-brick pass. Twin: `BrickUniform` in `shaders/bricks.wgsl`.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct BrickUniform {
    /// Grid origin in Å.
    pub origin: [f32; 3],
    /// Grid spacing H in Å.
    pub spacing: f32,
    /// Whole-grid samples along x, y, z.
    pub dims: [u32; 3],
    /// Bricks covering the grid.
    pub brick_count: u32,
    /// Bricks along x, y, z.
    pub brick_dims: [u32; 3],
    /// Device limit on workgroups per dispatch dimension.
    pub max_groups: u32,
    /// Bin cell origin in Å.
    pub cell_origin: [f32; 3],
    /// Bin cell edge in Å.
    pub cell_size: f32,
    /// Bin cells along x, y, z.
    pub cell_dims: [u32; 3],
    /// Cutoff q in units of alpha.
    pub cutoff: f32,
    /// Largest cutoff distance q * R * max(r) in Å.
    pub max_cut: f32,
    /// Padding to 16 bytes.
    pub _pad: [u32; 3],
}
const _: () = assert!(std::mem::size_of::<BrickUniform>() == 96);

/// Reduction and bookkeeping parameters. Twin: `MeasureUniform` in `shaders/measure.wgsl`.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct MeasureUniform {
    /// Reference point for the volume sum in Å (the grid centre).
    pub centre: [f32; 3],
    /// Device limit on workgroups per dispatch dimension.
    pub max_groups_x: u32,
    /// Corner of the binning's first cell in Å (sharp triangles are measured on the Gaussian
    /// sum of the binned atoms).
    pub cell_origin: [f32; 3],
    /// Edge of a binning cell in Å.
    pub cell_size: f32,
    /// Binning cells per axis.
    pub cell_dims: [u32; 3],
    /// How far the farthest-reaching atom counts in the Gaussian sum, Å.
    pub reach: f32,
    /// Isovalue I (dimensionless).
    pub isovalue: f32,
    /// Padding to 16 bytes.
    pub pad: [u32; 3],
}
const _: () = assert!(std::mem::size_of::<MeasureUniform>() == 64);

/// Frame counters on the GPU, read back asynchronously. Twin: the `C_*` word indices in
/// `shaders/counters.wgsl` (one per field, checked against the field offsets by the tests of
/// [`super::shaders`]).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, Pod, Zeroable, PartialEq)]
pub struct GpuCounters {
    /// Vertices of the surface (may exceed `vertex_capacity`: then `overflow` is set).
    pub vertex_count: u32,
    /// Triangles of the surface (may exceed `triangle_capacity`).
    pub triangle_count: u32,
    /// Bit 0 ([`OVERFLOW_VERTICES`]): vertex buffer too small; bit 1 ([`OVERFLOW_TRIANGLES`]):
    /// index buffer too small; bit 2 ([`OVERFLOW_BRICKS`]): the reached bricks did not fit the
    /// brick slots.
    pub overflow: u32,
    /// Internal: first vertex id of the current slab.
    pub slab_vertex_base: u32,
    /// Internal: first triangle id of the current slab.
    pub slab_triangle_base: u32,
    /// Internal: vertices owned by the current slab.
    pub slab_owned_vertices: u32,
    /// Internal: active cells of the current slab (scan total).
    pub scan_active: u32,
    /// Internal: vertices classified in the current slab (scan total).
    pub scan_vertices: u32,
    /// Internal: triangles of the current slab (scan total).
    pub scan_triangles: u32,
    /// Surface area in Å² (f32).
    pub area: f32,
    /// Enclosed volume in Å³ (f32).
    pub volume: f32,
    /// Vertices the vertex buffer holds.
    pub vertex_capacity: u32,
    /// Triangles the index buffer holds.
    pub triangle_capacity: u32,
    /// Active cells over all slabs.
    pub active_total: u32,
    /// Bricks some atom reaches (sparse bricks; 0 on the dense path). Copied in each frame
    /// from the sparse-brick pass's count ([`crate::gpu::bricks`]).
    pub reached_bricks: u32,
    /// Sparse bricks: the most brick slots one slab used (its reached bricks), written by the
    /// density pass (0 on frames that do not run it, and on the dense path).
    pub brick_slots: u32,
}
const _: () = assert!(std::mem::size_of::<GpuCounters>() == 64);

/// Word index of a field of [`GpuCounters`].
macro_rules! counter_word {
    ($field:ident) => {
        (std::mem::offset_of!(GpuCounters, $field) / 4) as u32
    };
}
/// Word index of the scan totals in [`GpuCounters`] (where the scans write their grand totals;
/// `C_SCAN_*` in `shaders/counters.wgsl`).
pub(crate) const C_SCAN_ACTIVE: u32 = counter_word!(scan_active);
pub(crate) const C_SCAN_VERTICES: u32 = counter_word!(scan_vertices);
pub(crate) const C_SCAN_TRIANGLES: u32 = counter_word!(scan_triangles);
/// Word index of [`GpuCounters::reached_bricks`] (`C_REACHED_BRICKS` in `shaders/counters.wgsl`).
pub(crate) const C_REACHED_BRICKS: u32 = counter_word!(reached_bricks);
/// Bit of [`GpuCounters::overflow`]: the vertex buffer was too small (`OVERFLOW_VERTICES` in
/// `shaders/counters.wgsl`).
pub const OVERFLOW_VERTICES: u32 = 1;
/// Bit of [`GpuCounters::overflow`]: the index buffer was too small (`OVERFLOW_TRIANGLES` in
/// `shaders/counters.wgsl`).
pub const OVERFLOW_TRIANGLES: u32 = 2;
/// Bit of [`GpuCounters::overflow`]: the reached bricks of a slab did not fit the brick slots
/// (`OVERFLOW_BRICKS` in `shaders/counters.wgsl`).
pub const OVERFLOW_BRICKS: u32 = 4;

/// One output vertex. Twin: the 9-float records written by `write_vertex` in `shaders/emit.wgsl`.
/// Vertex buffer layout for the renderer: stride 36 bytes; position `Float32x3` at offset 0 (Å),
/// normal `Float32x3` at 12 (unit, outward), colour `Float32x3` at 24 (linear RGB 0..1).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, Pod, Zeroable, PartialEq)]
pub struct GpuVertex {
    /// Position in Å.
    pub position: [f32; 3],
    /// Unit outward normal.
    pub normal: [f32; 3],
    /// Linear RGB colour.
    pub colour: [f32; 3],
}
const _: () = assert!(std::mem::size_of::<GpuVertex>() == 36);

/// Indirect draw arguments as `measure.wgsl`'s `frame_end` writes them (wgpu's
/// `DrawIndexedIndirectArgs` layout: index_count, instance_count, first_index, base_vertex,
/// first_instance).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, Pod, Zeroable, PartialEq)]
pub struct DrawIndexedArgs {
    /// 3 * triangles (0 when the frame overflowed).
    pub index_count: u32,
    /// Always 1.
    pub instance_count: u32,
    /// Always 0.
    pub first_index: u32,
    /// Always 0.
    pub base_vertex: i32,
    /// Always 0.
    pub first_instance: u32,
}
const _: () = assert!(std::mem::size_of::<DrawIndexedArgs>() == 20);

/// Packs a linear RGB colour (clamped to 0..1) as two u32 of 16-bit unorm channels, the format
/// `shaders/bin.wgsl` reads with `unpack2x16unorm`.
pub fn pack_colour(c: [f32; 3]) -> [u32; 2] {
    let q = |v: f32| (v.clamp(0.0, 1.0) * 65535.0).round() as u32;
    [q(c[0]) | (q(c[1]) << 16), q(c[2])]
}

/// Word where the triangle edges start in [`McTablesUniform`] (`MC_TRI_BASE` in
/// `shaders/mc_tables.wgsl`).
pub const MC_TRI_BASE: usize = 260;
/// 16-byte rows of [`McTablesUniform`] (`MC_TABLE_ROWS` in `shaders/mc_tables.wgsl`).
pub const MC_TABLE_ROWS: usize = 1025;

/// The Marching Cubes tables as one uniform buffer. Twin: `McTablesUniform` in
/// `shaders/mc_tables.wgsl` (prepended to `shaders/classify.wgsl` and `shaders/emit.wgsl`).
/// Words `0..257`: case starts; from word [`MC_TRI_BASE`]: triangle edges, three per triangle.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct McTablesUniform {
    /// The words, four per 16-byte row.
    pub words: [[u32; 4]; MC_TABLE_ROWS],
}
const _: () = assert!(std::mem::size_of::<McTablesUniform>() == 16 * MC_TABLE_ROWS);

impl McTablesUniform {
    /// Packs `tables`; None when they do not fit (they always do for Marching Cubes: at most
    /// 5 triangles per case).
    pub fn new(tables: &crate::surface::McTables) -> Option<Box<McTablesUniform>> {
        let edges = tables.triangles_flat_u32();
        if tables.case_start.len() > MC_TRI_BASE || MC_TRI_BASE + edges.len() > 4 * MC_TABLE_ROWS {
            return None;
        }
        let mut u: Box<McTablesUniform> = bytemuck::zeroed_box();
        let flat: &mut [u32] = bytemuck::cast_slice_mut(&mut u.words);
        flat[..tables.case_start.len()].copy_from_slice(&tables.case_start);
        flat[MC_TRI_BASE..MC_TRI_BASE + edges.len()].copy_from_slice(&edges);
        Some(u)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mc_tables_fit_the_uniform() {
        let t = crate::surface::McTables::get();
        let u = McTablesUniform::new(t).expect("tables fit");
        let flat: &[u32] = bytemuck::cast_slice(&u.words);
        assert_eq!(&flat[..257], &t.case_start[..]);
        let edges = t.triangles_flat_u32();
        assert_eq!(&flat[MC_TRI_BASE..MC_TRI_BASE + edges.len()], &edges[..]);
    }
}
