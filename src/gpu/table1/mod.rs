//! The paper's Table 1 on this GPU: synthetic systems of the paper's sizes and spacings, built
//! by tiling a real structure with fresh jitter every frame ([`crate::synthetic`]), run through
//! [`GpuEngine::run_blocking`] a number of times; medians per stage (upload, binning, density,
//! Marching Cubes), whole-frame wall-clock time and fps, GPU memory, and the speed-up over the
//! paper's GTX 580 figures. `mdsurf bench --table1 --backend gpu` prints [`format()`]'s table.
//!
//! [`plan_rows`] sizes the same rows' GPU memory without a device (`mdsurf bench --table1
//! --plan-only`, [`format_plan`]'s table): the same synthetic systems, grids and frame plans,
//! under the limits wgpu reported on an 80 GB NVIDIA H100 ([`DeviceLimits::NVIDIA_80GB`]),
//! with the mesh buffers sized from the CPU engine's surface or at their largest.

#[cfg(feature = "app")]
use std::path::Path;
use std::time::Instant;

use glam::Vec3;

use super::density::DensityGather;
use super::engine::{Changes, EngineOptions, GpuEngine};
use super::plan::{
    BufferPlan, DEFAULT_HEADROOM, DeviceLimits, GpuMemory, MeshCapacity, count_reached_bricks,
    first_mesh_want, largest_brick_slots, plan_frame, settled_brick_slots,
};
use super::{GpuContext, GpuError};
#[cfg(feature = "app")]
use crate::model::{ParticleOptions, Particles};
use crate::surface::{AtomSet, CpuEngine, GridSpec, SurfaceEngine, SurfaceError, SurfaceParams};
use crate::synthetic::{SyntheticError, SyntheticSystem};

mod planned;

pub use planned::*;

/// One row of the paper's Table 1 (GeForce GTX 580 times in seconds).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PaperRow {
    /// Number of atoms.
    pub atoms: usize,
    /// Grid spacing H in Å.
    pub spacing: f32,
    /// Binning time t_sort in s.
    pub t_sort: f64,
    /// Density time t_d in s.
    pub t_d: f64,
    /// Marching Cubes time t_MC in s.
    pub t_mc: f64,
}

impl PaperRow {
    /// t_sort + t_d + t_MC in ms.
    pub fn total_ms(&self) -> f64 {
        (self.t_sort + self.t_d + self.t_mc) * 1e3
    }
}

const fn row(atoms: usize, spacing: f32, t_sort: f64, t_d: f64, t_mc: f64) -> PaperRow {
    PaperRow {
        atoms,
        spacing,
        t_sort,
        t_d,
        t_mc,
    }
}

/// The paper's rows (R = 1, I = 0.5).
pub const PAPER_ROWS: [PaperRow; 6] = [
    row(147_976, 1.0, 0.007, 0.048, 0.009),
    row(754_200, 1.0, 0.01, 0.18, 0.05),
    row(955_226, 1.0, 0.008, 0.189, 0.012),
    row(2_370_000, 2.0, 0.03, 0.17, 0.016),
    row(9_620_000, 2.0, 0.16, 0.023, 0.06),
    row(22_800_000, 4.0, 4.4, 0.68, 0.01),
];

/// How to run the table.
#[derive(Debug, Clone, PartialEq)]
pub struct Table1Options {
    /// Timed frames per row (after one untimed warm-up frame).
    pub repeats: usize,
    /// Skip rows with more atoms than this (small GPUs, quick checks).
    pub max_atoms: Option<usize>,
    /// Compute the colour volume too (the structure's element colours).
    pub colours: bool,
    /// How the sparse density gather reads its atoms.
    pub density_gather: DensityGather,
}

impl Default for Table1Options {
    fn default() -> Self {
        Table1Options {
            repeats: 10,
            max_atoms: None,
            colours: true,
            density_gather: DensityGather::default(),
        }
    }
}

/// Our measurement of one row (times are medians in ms).
#[derive(Debug, Clone, PartialEq)]
pub struct Table1Row {
    /// The paper's row.
    pub paper: PaperRow,
    /// Atoms in our synthetic system.
    pub atoms: usize,
    /// Grid samples along x, y, z.
    pub grid: [u32; 3],
    /// Z-slabs per frame.
    pub slabs: usize,
    /// Triangles of the last frame.
    pub triangles: u32,
    /// Host-side validation and upload of coordinates.
    pub upload_ms: f64,
    /// Binning (t_sort).
    pub bin_ms: f64,
    /// Density and colour (t_d).
    pub density_ms: f64,
    /// Marching Cubes, area, volume (t_MC).
    pub mc_ms: f64,
    /// Whole frame, wall-clock: upload, all stages, counters back on the host.
    pub frame_ms: f64,
    /// Bytes of GPU memory the engine held.
    pub gpu_bytes: u64,
}

impl Table1Row {
    /// Binning + density + Marching Cubes in ms.
    pub fn compute_ms(&self) -> f64 {
        self.bin_ms + self.density_ms + self.mc_ms
    }

    /// Frames per second from the wall-clock frame time.
    pub fn fps(&self) -> f64 {
        1e3 / self.frame_ms.max(1e-9)
    }

    /// Paper total over our binning + density + Marching Cubes.
    pub fn speedup(&self) -> f64 {
        self.paper.total_ms() / self.compute_ms().max(1e-9)
    }
}

/// Why the table could not be produced.
#[derive(Debug, thiserror::Error)]
pub enum Table1Error {
    /// The structure to tile could not be read.
    #[error("{0}")]
    Structure(String),
    /// Tiling failed.
    #[error("tiling the structure: {0}")]
    Synthetic(#[from] SyntheticError),
    /// The engine failed on a row.
    #[error("{atoms} atoms at H = {spacing}: {source}")]
    Surface {
        /// Row size.
        atoms: usize,
        /// Row spacing in Å.
        spacing: f32,
        /// What failed.
        source: SurfaceError,
    },
    /// No GPU.
    #[error(transparent)]
    Gpu(#[from] GpuError),
}

/// A structure to tile: positions and radii in Å, optional linear RGB colours.
#[derive(Debug, Clone, Default)]
pub struct Structure {
    /// Positions in Å.
    pub positions: Vec<Vec3>,
    /// Radii in Å.
    pub radii: Vec<f32>,
    /// Colours per atom.
    pub colours: Option<Vec<[f32; 3]>>,
}

impl Structure {
    /// The first frame of `top` (+ `traj`) with default radii and element colours (the file
    /// readers come with the `app` feature).
    #[cfg(feature = "app")]
    pub fn from_file(top: &Path, traj: Option<&Path>) -> Result<Structure, Table1Error> {
        let err =
            |e: &dyn std::fmt::Display| Table1Error::Structure(format!("{}: {e}", top.display()));
        let t = crate::io::open(top, traj).map_err(|e| err(&e))?;
        let frame = t.read_frame(0).map_err(|e| err(&e))?;
        let particles = Particles::new(t.topology(), &frame, &ParticleOptions::default())
            .map_err(|e| err(&e))?;
        Ok(Structure {
            positions: particles.positions(&frame).map_err(|e| err(&e))?,
            radii: particles.radii().to_vec(),
            colours: Some(particles.colours().to_vec()),
        })
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    let m = v.len() / 2;
    if v.len() % 2 == 1 {
        v[m]
    } else {
        0.5 * (v[m - 1] + v[m])
    }
}

/// The synthetic system of row `index`: `structure` tiled to the row's atom count, with the
/// row's own jitter seed (the same in [`run_rows`] and [`plan_rows`]).
fn row_system(
    structure: &Structure,
    colours: Option<&[[f32; 3]]>,
    index: usize,
    paper: &PaperRow,
) -> Result<SyntheticSystem, Table1Error> {
    Ok(
        SyntheticSystem::tile(&structure.positions, &structure.radii, colours, paper.atoms)?
            .with_seed(0x7461_626c_6531 + index as u64),
    )
}

/// The surface parameters of a row: its spacing, R = 1, I = 0.5 (the defaults).
fn row_params(paper: &PaperRow) -> SurfaceParams {
    SurfaceParams {
        spacing: paper.spacing,
        ..SurfaceParams::default()
    }
}

/// Runs the paper's rows (up to `opts.max_atoms`) on a fresh engine each over `ctx`;
/// `progress` hears a line per row.
pub fn run(
    ctx: &GpuContext,
    structure: &Structure,
    opts: &Table1Options,
    progress: impl FnMut(&str),
) -> Result<Vec<Table1Row>, Table1Error> {
    run_rows(ctx, structure, &PAPER_ROWS, opts, progress)
}

/// Like [`run`] for any list of rows (tests use small ones).
pub fn run_rows(
    ctx: &GpuContext,
    structure: &Structure,
    paper_rows: &[PaperRow],
    opts: &Table1Options,
    mut progress: impl FnMut(&str),
) -> Result<Vec<Table1Row>, Table1Error> {
    let mut rows = Vec::new();
    let colours = if opts.colours {
        structure.colours.as_deref()
    } else {
        None
    };
    for (index, paper) in paper_rows.iter().enumerate() {
        if opts.max_atoms.is_some_and(|m| paper.atoms > m) {
            continue;
        }
        progress(&format!(
            "table 1: {} atoms at H = {} ...",
            paper.atoms, paper.spacing
        ));
        let system = row_system(structure, colours, index, paper)?;
        let params = row_params(paper);
        let fail = |source| Table1Error::Surface {
            atoms: paper.atoms,
            spacing: paper.spacing,
            source,
        };
        let mut engine = GpuEngine::with_context(ctx.clone())?;
        engine.set_options(EngineOptions {
            density_gather: opts.density_gather,
            ..engine.options()
        });
        let mut positions = Vec::new();
        let mut samples: [Vec<f64>; 5] = Default::default();
        let mut last = None;
        for frame in 0..=opts.repeats.max(1) {
            system.frame_into(frame, &mut positions);
            let atoms = AtomSet {
                positions: &positions,
                radii: system.radii(),
                colours: system.colours(),
            };
            let changes = Changes {
                positions: true,
                radii: frame == 0,
                colours: frame == 0,
            };
            let start = Instant::now();
            let stats = engine
                .run_blocking(&atoms, &params, changes)
                .map_err(fail)?;
            let wall = start.elapsed().as_secs_f64() * 1e3;
            if frame > 0 {
                let t = stats.timings;
                for (s, v) in
                    samples
                        .iter_mut()
                        .zip([t.upload_ms, t.bin_ms, t.density_ms, t.mc_ms, wall])
                {
                    s.push(v);
                }
            }
            last = Some(stats);
        }
        let info = engine.last_frame().cloned();
        let [upload_ms, bin_ms, density_ms, mc_ms, frame_ms] = samples.map(median);
        rows.push(Table1Row {
            paper: *paper,
            atoms: system.len(),
            grid: info.as_ref().map(|i| i.grid.dims).unwrap_or_default(),
            slabs: info.map(|i| i.slabs).unwrap_or(0),
            triangles: last.map(|s| s.triangle_count).unwrap_or(0),
            upload_ms,
            bin_ms,
            density_ms,
            mc_ms,
            frame_ms,
            gpu_bytes: engine.gpu_bytes(),
        });
    }
    Ok(rows)
}

/// The table as text: the paper's times beside ours, speed-up and memory per row.
pub fn format(rows: &[Table1Row], device: &str, timestamps: bool) -> String {
    let mut s = format!(
        "Table 1 (Krone et al. 2012, GTX 580) vs mdsurf on {device}; R = 1, I = 0.5, medium quality; \
         stage times from {}; medians in ms\n",
        if timestamps {
            "GPU timestamps"
        } else {
            "wall-clock waits"
        }
    );
    s += &format!(
        "{:>10} {:>4} {:>15} {:>5} {:>9} | {:>7} {:>7} {:>7} {:>8} | {:>7} {:>7} {:>8} {:>7} {:>8} {:>8} {:>7} | {:>8} {:>8}\n",
        "atoms",
        "H",
        "grid",
        "slabs",
        "tris",
        "t_sort",
        "t_d",
        "t_MC",
        "sum",
        "upload",
        "bin",
        "density",
        "MC",
        "sum",
        "frame",
        "fps",
        "speedup",
        "GPU MiB"
    );
    for r in rows {
        let p = &r.paper;
        s += &format!(
            "{:>10} {:>4.1} {:>15} {:>5} {:>9} | {:>7.1} {:>7.1} {:>7.1} {:>8.1} | {:>7.2} {:>7.2} {:>8.2} {:>7.2} {:>8.2} {:>8.2} {:>7.1} | {:>7.0}x {:>8.0}\n",
            r.atoms,
            p.spacing,
            format!("{}x{}x{}", r.grid[0], r.grid[1], r.grid[2]),
            r.slabs,
            r.triangles,
            p.t_sort * 1e3,
            p.t_d * 1e3,
            p.t_mc * 1e3,
            p.total_ms(),
            r.upload_ms,
            r.bin_ms,
            r.density_ms,
            r.mc_ms,
            r.compute_ms(),
            r.frame_ms,
            r.fps(),
            r.speedup(),
            r.gpu_bytes as f64 / (1u64 << 20) as f64,
        );
    }
    s
}

/// Opens the GPU, tiles the first frame of `top` (+ `traj`), runs the table and formats it.
#[cfg(feature = "app")]
pub fn table1(
    top: &Path,
    traj: Option<&Path>,
    opts: &Table1Options,
) -> Result<String, Table1Error> {
    let ctx = GpuContext::new_headless()?;
    let structure = Structure::from_file(top, traj)?;
    let rows = run(&ctx, &structure, opts, |line| eprintln!("{line}"))?;
    let limits = ctx.device_limits();
    Ok(format!(
        "{}: largest storage binding {} bytes, largest buffer {} bytes, volume budget {} bytes\n{}",
        ctx.adapter_name,
        limits.max_binding(),
        limits.max_buffer_size,
        limits.volume_budget(),
        format(&rows, &ctx.adapter_name, ctx.timestamps)
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_totals_and_speedup() {
        assert!((PAPER_ROWS[2].total_ms() - 209.0).abs() < 1e-9);
        let r = Table1Row {
            paper: PAPER_ROWS[0],
            atoms: 147_976,
            grid: [10, 10, 10],
            slabs: 1,
            triangles: 5,
            upload_ms: 1.0,
            bin_ms: 0.1,
            density_ms: 0.5,
            mc_ms: 0.04,
            frame_ms: 2.0,
            gpu_bytes: 1 << 20,
        };
        assert!((r.speedup() - 100.0).abs() < 1e-9);
        assert!((r.fps() - 500.0).abs() < 1e-9);
        let text = format(&[r], "test GPU", true);
        assert!(text.contains("147976") && text.contains("100x"), "{text}");
        assert_eq!(median(vec![3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(vec![4.0, 1.0, 2.0, 3.0]), 2.5);
    }
}
