//! Recording one frame's compute work (DESIGN section 3, steps 2 to 5): the exposure radii of
//! the SES preset when the engine has a model ([`super::exposure`]), binning and, on sparse
//! bricks, the list of reached bricks ([`super::bricks`]), then per z-slab the density pass (over
//! the reached bricks into their brick slots, or over every voxel) and the Marching Cubes
//! pass (classify, three scans, compaction, emission and, with refined vertices, refinement),
//! then the end-of-frame bookkeeping, area/volume reduction and indirect draw arguments. Which
//! stages run depends on what changed ([`Work`]). Called by [`super::engine::GpuEngine`].

use std::time::Instant;

use super::GpuError;
use super::bin::Binner;
use super::bricks::BrickStage;
use super::context::GpuContext;
use super::density::{DensityGather, DensityMode, DensityStage};
use super::exposure::ExposureStage;
use super::mc::{Classify, Compact, Emit, Refine};
use super::measure::Measure;
use super::plan::{FramePlan, Slab};
use super::resources::Buffers;
use super::scan::{ScanPlan, Scanner};
use super::timing::{Stage, Timer};
use super::types::{C_SCAN_ACTIVE, C_SCAN_TRIANGLES, C_SCAN_VERTICES, MeasureUniform, SlabUniform};
use crate::surface::analytic::REFINE_REACH;
use crate::surface::{StageTimings, SurfaceParams};

/// Which stages a frame re-runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Work {
    /// Binning, density (and colour), Marching Cubes: positions, radii, H, R or quality changed.
    Full,
    /// Binning (for the sorted colours), the colour pass and Marching Cubes: colours changed.
    Colour,
    /// Marching Cubes only: the isovalue changed, or a rerun after a mesh overflow.
    Mc,
}

/// The compiled stages of one device with their persistent uniforms, scan scratch and cached
/// bind groups ([`Stages::prepare`] refreshes them, [`Stages::record`] only records).
#[derive(Debug)]
pub struct Stages {
    scanner: Scanner,
    binner: Binner,
    /// The SES preset's exposure radii, before binning (when the engine has a model).
    pub(crate) exposure: ExposureStage,
    bricks: BrickStage,
    density: DensityStage,
    classify: Classify,
    compact: Compact,
    emit: Emit,
    refine: Refine,
    measure: Measure,
    /// Scans of the block sums of vertices, triangles, active cells.
    block_scans: [ScanPlan; 3],
    slab_values: Vec<SlabUniform>,
    max_groups: u32,
    /// The prepared frame runs on sparse bricks.
    sparse: bool,
}

/// Encoder plus optional wall-clock timing: without timestamp queries a blocking frame submits
/// and waits after each stage and charges the elapsed time to it.
pub struct Recorder<'a> {
    ctx: &'a GpuContext,
    encoder: wgpu::CommandEncoder,
    wall: Option<(StageTimings, Instant)>,
}

impl<'a> Recorder<'a> {
    /// A recorder; `wall_clock` times stages by waiting after each.
    pub fn new(ctx: &'a GpuContext, wall_clock: bool) -> Recorder<'a> {
        Recorder {
            ctx,
            encoder: ctx.device.create_command_encoder(&Default::default()),
            wall: wall_clock.then(|| (StageTimings::default(), Instant::now())),
        }
    }

    /// The current encoder.
    pub fn encoder(&mut self) -> &mut wgpu::CommandEncoder {
        &mut self.encoder
    }

    /// Ends a stage: in wall-clock mode submits, waits and charges the time to `stage`.
    pub fn end_stage(&mut self, stage: Stage) -> Result<(), GpuError> {
        let Some((t, start)) = &mut self.wall else {
            return Ok(());
        };
        let enc = std::mem::replace(
            &mut self.encoder,
            self.ctx.device.create_command_encoder(&Default::default()),
        );
        self.ctx.queue.submit([enc.finish()]);
        self.ctx.wait()?;
        let ms = start.elapsed().as_secs_f64() * 1e3;
        match stage {
            Stage::Exposure => t.exposure_ms += ms,
            Stage::Bin => t.bin_ms += ms,
            Stage::Density => t.density_ms += ms,
            Stage::Mc => t.mc_ms += ms,
        }
        *start = Instant::now();
        Ok(())
    }

    /// Finishes: the last command buffer and the wall-clock timings (None in timestamp mode).
    pub fn finish(self) -> (wgpu::CommandBuffer, Option<StageTimings>) {
        (self.encoder.finish(), self.wall.map(|w| w.0))
    }
}

/// The uniform of one slab (`sparse`: the frame runs on sparse bricks; `sparse_classes`: its
/// class entries are held per brick slot, [`super::plan::ClassEntries`]).
pub fn slab_uniform(
    plan: &FramePlan,
    params: &SurfaceParams,
    slab: &Slab,
    atoms: u64,
    sparse: bool,
    sparse_classes: bool,
) -> SlabUniform {
    let g = &plan.grid;
    SlabUniform {
        origin: g.origin.to_array(),
        spacing: g.spacing,
        dims: g.dims,
        isovalue: params.isovalue,
        cell_origin: g.origin.to_array(),
        cell_size: plan.cell_size,
        cell_dims: plan.cell_dims,
        cutoff: params.cutoff(),
        dens_z0: slab.dens_z0,
        dens_layers: slab.dens_layers,
        own_z0: slab.own_z0,
        own_z1: slab.own_z1,
        class_points: plan.class_points() as u32,
        class_layers: plan.class_layers,
        max_cut: plan.max_cut,
        has_extra_layer: u32::from(slab.own_z1 < g.dims[2]),
        centre: grid_centre(plan).to_array(),
        atom_count: atoms as u32,
        brick_dims: plan.brick_dims,
        sparse: u32::from(sparse) | (u32::from(sparse && sparse_classes) << 1),
    }
}

fn grid_centre(plan: &FramePlan) -> glam::Vec3 {
    let g = &plan.grid;
    let d = glam::Vec3::new(g.dims[0] as f32, g.dims[1] as f32, g.dims[2] as f32) - 1.0;
    g.origin + 0.5 * g.spacing * d
}

impl Stages {
    /// Compiles every stage.
    pub fn new(ctx: &GpuContext, max_groups: u32) -> Stages {
        Stages {
            scanner: Scanner::new(ctx, max_groups),
            binner: Binner::new(ctx, max_groups),
            exposure: ExposureStage::new(ctx, max_groups),
            bricks: BrickStage::new(ctx, max_groups),
            density: DensityStage::new(ctx),
            classify: Classify::new(ctx),
            compact: Compact::new(ctx),
            emit: Emit::new(ctx),
            refine: Refine::new(ctx),
            measure: Measure::new(ctx),
            block_scans: Default::default(),
            slab_values: Vec::new(),
            max_groups,
            sparse: false,
        }
    }

    /// Prepares a frame after the buffers were sized: writes every uniform in place (the slab
    /// uniforms into one buffer at dynamic offsets) and rebuilds only the bind groups whose
    /// buffers were replaced, those of every output set together (so the first frame builds
    /// both). Creates no GPU object in steady state. `sparse`: density and classification run
    /// on the sparse bricks the atoms reach; `sparse_classes`: the class entries are held per
    /// brick slot (as the buffers were sized, [`super::plan::BufferPlan::class_entries`]);
    /// `gather`: which sparse density gather runs ([`DensityGather::resolve`]d for the grid).
    #[allow(clippy::too_many_arguments)]
    pub fn prepare(
        &mut self,
        ctx: &GpuContext,
        b: &mut Buffers,
        plan: &FramePlan,
        params: &SurfaceParams,
        atoms: u64,
        work: Work,
        sparse: bool,
        sparse_classes: bool,
        gather: DensityGather,
    ) {
        self.sparse = sparse;
        self.density.gather = gather.resolve(plan.grid.spacing, plan.cell_size);
        self.slab_values.clear();
        self.slab_values.extend(
            plan.slabs
                .iter()
                .map(|s| slab_uniform(plan, params, s, atoms, sparse, sparse_classes)),
        );
        b.slab_uniforms.write(ctx, &self.slab_values);
        let b = &*b;
        if work != Work::Mc {
            self.exposure.prepare(ctx, &self.scanner, b, plan, atoms);
            self.binner
                .prepare(ctx, &self.scanner, b, plan, atoms, params.radius_scale);
            if sparse {
                self.bricks
                    .prepare(ctx, &self.scanner, b, plan, params.cutoff());
            }
        }
        let blocks = plan.class_blocks();
        for (i, slot) in [C_SCAN_VERTICES, C_SCAN_TRIANGLES, C_SCAN_ACTIVE]
            .into_iter()
            .enumerate()
        {
            self.scanner.prepare(
                ctx,
                &mut self.block_scans[i],
                &b.block_sums[i].buffer,
                blocks,
                (&b.counters, slot),
            );
        }
        self.measure.prepare(
            ctx,
            b,
            &MeasureUniform {
                centre: grid_centre(plan).to_array(),
                max_groups_x: self.max_groups,
                cell_origin: plan.grid.origin.to_array(),
                cell_size: plan.cell_size,
                cell_dims: plan.cell_dims,
                // As refine.wgsl's field_cells: the largest alpha is max_cut / cutoff.
                reach: REFINE_REACH * plan.max_cut / params.cutoff() * 1.0001 + 1e-4,
                isovalue: params.isovalue,
                pad: [0; 3],
            },
        );
        self.density.prepare(ctx, b);
        self.classify.prepare(ctx, b);
        self.compact.prepare(ctx, b);
        self.emit.prepare(ctx, b);
        self.refine.prepare(ctx, b);
    }

    /// Records binning and the sparse-brick pass alone (prepared by [`Stages::prepare`] with
    /// [`Work::Full`] on sparse bricks): the engine counts a first frame's reached bricks from
    /// the slot table it writes before sizing the brick slots.
    pub fn record_bricks(&self, rec: &mut Recorder<'_>, b: &Buffers) {
        self.exposure.record(rec.encoder(), &self.scanner, None);
        self.binner.record(rec.encoder(), &self.scanner, b, None);
        self.bricks.record(rec.encoder(), &self.scanner);
    }

    /// Records the frame prepared by [`Stages::prepare`] into `rec` (after the caller reset the
    /// counters), writing the mesh and draw arguments into output set `set`; `refined`:
    /// vertices refined on the exact Gaussian sum and area and volume curvature-corrected
    /// ([`crate::surface::VertexMode::Refined`]).
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        rec: &mut Recorder<'_>,
        timer: &mut Timer,
        b: &Buffers,
        plan: &FramePlan,
        work: Work,
        set: usize,
        colour: bool,
        refined: bool,
    ) -> Result<(), GpuError> {
        if work != Work::Mc && self.exposure.active() {
            let ts = timer.pass(Stage::Exposure);
            self.exposure.record(rec.encoder(), &self.scanner, ts);
            rec.end_stage(Stage::Exposure)?;
        }
        if work != Work::Mc {
            let ts = timer.pass(Stage::Bin);
            self.binner.record(rec.encoder(), &self.scanner, b, ts);
            if self.sparse {
                self.bricks.record(rec.encoder(), &self.scanner);
            }
            rec.end_stage(Stage::Bin)?;
        }
        if self.sparse {
            BrickStage::record_count(rec.encoder(), b);
        }
        let mode = match (work, colour) {
            (Work::Mc, _) => None,
            (Work::Colour, _) => Some(DensityMode::ColourOnly),
            (Work::Full, true) => Some(DensityMode::WithColour),
            (Work::Full, false) => Some(DensityMode::Plain),
        };
        let blocks = plan.class_blocks();
        for (i, slab) in plan.slabs.iter().enumerate() {
            let offset = b.slab_uniforms.offset(i);
            if let Some(mode) = mode {
                let ts = timer.pass(Stage::Density);
                let mut pass = rec
                    .encoder()
                    .begin_compute_pass(&wgpu::ComputePassDescriptor {
                        label: Some("density"),
                        timestamp_writes: ts,
                    });
                if self.sparse {
                    self.density
                        .record_sparse(&mut pass, offset, &b.brick_args, mode);
                } else {
                    self.density
                        .record(&mut pass, offset, plan.grid.dims, slab.dens_layers, mode);
                }
                drop(pass);
                rec.end_stage(Stage::Density)?;
            }
            let ts = timer.pass(Stage::Mc);
            let mut pass = rec
                .encoder()
                .begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("marching cubes"),
                    timestamp_writes: ts,
                });
            self.classify
                .record(&mut pass, offset, blocks, self.max_groups);
            for s in &self.block_scans {
                self.scanner.record(&mut pass, s);
            }
            self.measure.slab_begin(&mut pass);
            self.compact
                .record(&mut pass, offset, blocks, self.max_groups);
            self.emit.record(&mut pass, offset, b, set, colour);
            if refined {
                self.refine.record(&mut pass, offset, b, set);
            }
            self.measure.slab_end(&mut pass);
            drop(pass);
            rec.end_stage(Stage::Mc)?;
        }
        let ts = timer.pass(Stage::Mc);
        let mut pass = rec
            .encoder()
            .begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("measure"),
                timestamp_writes: ts,
            });
        self.measure.frame_end(&mut pass, set, refined);
        drop(pass);
        rec.end_stage(Stage::Mc)
    }
}
