//! The CPU reference engine: validates the input, then runs binning ([`super::bin`]), density
//! ([`super::density`]) and Marching Cubes ([`super::marching_cubes`]) with rayon, timing each
//! stage. It is the oracle the GPU engine is tested against and the engine on machines without
//! a GPU.

use std::sync::Arc;
use std::time::Instant;

use glam::Vec3;

use super::analytic::{AnalyticField, RefinedReuse};
use super::bin::{PreparedAtom, bin_atoms, bin_atoms_overlapping};
use super::brick_mc::march_bricks;
use super::bricks::{self, BrickScratch, BrickStats, BrickVolume};
use super::kept_density::{KeptSamples, dense_difference_into};
use super::marching_cubes::{McScratch, VertexData, march_dense};
use super::{
    AtomSet, DensityVolume, GridSpec, KeptDensity, Mesh, MeshCounts, StageTimings, SurfaceEngine,
    SurfaceError, SurfaceOutput, SurfaceParams, VertexMode, curved, density, memory,
};

/// Grid samples up to which the default engine computes dense (a 64³ grid; 1hpv at H = 1 Å has
/// 0.2 million): measured on 1hpv, the dense path takes 0.95 ms of density per frame against
/// 1.17 ms in bricks, for the same bits; at 0.9 million samples (solvated adk) the two are even
/// and bricks use less memory.
pub const DENSE_MAX_SAMPLES: u64 = 1 << 18;

/// The multi-threaded CPU surface engine (uses rayon's global thread pool).
///
/// By default it is sparse: the density lives in the 8³-sample bricks that some atom reaches
/// ([`super::bricks`]), Marching Cubes visits only the bricks the surface crosses
/// ([`super::brick_mc`]) and colours are computed per vertex, not per sample; the mesh, area
/// and volume are bitwise those of the dense path ([`CpuEngine::dense`]), which samples a full
/// density (and colour) volume. Grids of at most [`DENSE_MAX_SAMPLES`] samples take the dense
/// path anyway (same bits): their volumes are small and the bricks' bookkeeping costs more
/// than it saves there ([`CpuEngine::bricks`] forces bricks). Either way the engine keeps its
/// volumes and Marching Cubes buffers between calls, so a sequence of frames allocates them
/// once.
#[derive(Default)]
pub struct CpuEngine {
    memory_limit: Option<u64>,
    /// Sample the whole grid (the dense reference path) instead of bricks.
    dense: bool,
    /// Use bricks even on grids small enough for the dense path.
    always_bricks: bool,
    /// Dense density volume kept between calls (reused when the grid keeps its size).
    volume: DensityVolume,
    /// Sparse density kept between calls (boxed: the engine stays small to move around).
    bricks: Box<BrickVolume>,
    /// Per-thread working memory of the sparse density stage.
    brick_scratch: BrickScratch,
    /// Brick counts of the last sparse computation.
    last_bricks: Option<BrickStats>,
    /// Marching Cubes working memory kept between calls.
    mc: McScratch,
    /// False when only area, volume and counts are wanted (the mesh is then never assembled;
    /// see [`SurfaceEngine::set_keep_mesh`]).
    measure_only: bool,
    /// Vertex placement and measurement ([`VertexMode`], interpolated by default).
    vertices: VertexMode,
    /// The grid every surface uses instead of its atoms' own ([`SurfaceEngine::set_grid`]).
    forced_grid: Option<GridSpec>,
    /// Whether kept meshes hold positions and triangles only
    /// ([`SurfaceEngine::set_mesh_positions_only`]).
    positions_only: bool,
    /// Whether surfaces keep a copy of their density ([`SurfaceEngine::set_keep_density`]).
    keep_density: bool,
    /// The densities kept last, whose buffers later copies reuse once no output holds them
    /// ([`CpuEngine::keep_copy`]).
    kept: Vec<Arc<KeptDensity>>,
    /// Another surface's refined vertices later surfaces may take
    /// ([`SurfaceEngine::set_refined_reuse`]).
    reuse: Option<Arc<RefinedReuse>>,
}

/// Copies of the density a CPU engine keeps for reuse ([`CpuEngine::keep_copy`]).
const KEPT_BUFFERS: usize = 3;
/// A kept copy of the density may take at most one part in this many of the memory available
/// ([`CpuEngine::can_keep`]); with [`KEPT_BUFFERS`] of them, at most 3/16.
const KEPT_MEMORY_SHARE: u64 = 16;

/// Where a surface's density comes from.
#[derive(Clone, Copy)]
enum DensityFrom<'a> {
    /// Its atoms' Gaussians, sampled.
    Atoms,
    /// A kept dense density less another, on the same grid
    /// ([`SurfaceEngine::compute_difference`]).
    DenseDifference(&'a [f32], &'a [f32]),
    /// Kept sparse bricks less others, on the same grid.
    BrickDifference(&'a BrickVolume, &'a BrickVolume),
}

impl std::fmt::Debug for CpuEngine {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CpuEngine")
            .field("memory_limit", &self.memory_limit)
            .field("dense", &self.dense)
            .field("kept_samples", &self.volume.values.len())
            .field("kept_brick_bytes", &self.bricks.stored_bytes())
            .finish()
    }
}

impl CpuEngine {
    /// An engine that refuses grids larger than the memory currently available.
    pub fn new() -> CpuEngine {
        CpuEngine::default()
    }

    /// An engine that refuses grids whose estimate ([`super::estimate_grid_bytes`]) exceeds
    /// `bytes` instead of the available memory (for tests and embedding).
    pub fn with_memory_limit(bytes: u64) -> CpuEngine {
        CpuEngine {
            memory_limit: Some(bytes),
            ..CpuEngine::default()
        }
    }

    /// An engine on the dense reference path: full density and colour volumes, every cell
    /// marched. Gives the same mesh as the sparse bricks; the default engine takes it on small
    /// grids only.
    pub fn dense() -> CpuEngine {
        CpuEngine {
            dense: true,
            ..CpuEngine::default()
        }
    }

    /// An engine on the sparse bricks whatever the grid's size (for tests and comparison; the
    /// default engine computes small grids dense).
    pub fn bricks() -> CpuEngine {
        CpuEngine {
            always_bricks: true,
            ..CpuEngine::default()
        }
    }

    /// This engine switched to the dense path (`true`) or the default choice (`false`: bricks,
    /// or dense on grids of at most [`DENSE_MAX_SAMPLES`] samples).
    pub fn with_dense(mut self, dense: bool) -> CpuEngine {
        self.dense = dense;
        self
    }

    /// True when this engine computes `grid` on the dense path.
    fn dense_for(&self, grid: &GridSpec) -> bool {
        self.dense || (!self.always_bricks && grid.voxel_count() <= DENSE_MAX_SAMPLES)
    }

    /// This engine with vertices placed as `mode` says.
    pub fn with_vertices(mut self, mode: VertexMode) -> CpuEngine {
        self.vertices = mode;
        self
    }

    /// True when every grid goes the dense path ([`CpuEngine::dense`]).
    pub fn is_dense(&self) -> bool {
        self.dense
    }

    /// Brick counts (total, occupied, active) of the last surface the sparse path computed;
    /// `None` before the first one or on the dense path.
    pub fn brick_stats(&self) -> Option<BrickStats> {
        self.last_bricks
    }

    /// The grid `atoms` need under `params`, after checking the atoms, the parameters and that
    /// the grid fits in memory.
    pub fn plan(
        &self,
        atoms: &AtomSet<'_>,
        params: &SurfaceParams,
    ) -> Result<GridSpec, SurfaceError> {
        params.validate()?;
        atoms.validate()?;
        let own = GridSpec::for_atoms(atoms.positions, atoms.radii, params)?;
        let grid = match self.forced_grid {
            Some(forced) => check_forced_grid(&forced, &own, atoms, params)?,
            None => own,
        };
        // The sparse path stores at most the density of every sample (colours go per vertex).
        let needed = grid.estimated_bytes(self.dense_for(&grid) && atoms.colours.is_some());
        let available = memory::memory_for(needed, self.memory_limit);
        if needed > available {
            return Err(SurfaceError::GridTooLarge {
                dims: grid.dims.map(u64::from),
                bytes_needed: needed,
                bytes_available: available,
            });
        }
        Ok(grid)
    }
}

impl SurfaceEngine for CpuEngine {
    fn name(&self) -> &str {
        "cpu"
    }

    fn set_vertices(&mut self, mode: VertexMode) {
        self.vertices = mode;
    }

    fn set_keep_mesh(&mut self, keep: bool) {
        self.measure_only = !keep;
    }

    fn set_mesh_positions_only(&mut self, only: bool) {
        self.positions_only = only;
    }

    fn set_keep_density(&mut self, keep: bool) {
        self.keep_density = keep;
    }

    fn vertices(&self) -> VertexMode {
        self.vertices
    }

    fn set_grid(&mut self, grid: Option<GridSpec>) -> bool {
        self.forced_grid = grid;
        true
    }

    fn set_refined_reuse(&mut self, reuse: Option<Arc<RefinedReuse>>) -> bool {
        self.reuse = reuse;
        true
    }

    fn compute(
        &mut self,
        atoms: &AtomSet<'_>,
        params: &SurfaceParams,
    ) -> Result<SurfaceOutput, SurfaceError> {
        self.compute_from(atoms, params, DensityFrom::Atoms, None)
    }

    fn compute_difference(
        &mut self,
        atoms: &AtomSet<'_>,
        params: &SurfaceParams,
        whole: &KeptDensity,
        minus: &KeptDensity,
    ) -> Option<Result<SurfaceOutput, SurfaceError>> {
        let effective = self.vertices.effective(params);
        let grid = match self.plan(atoms, &effective) {
            Ok(grid) => grid,
            Err(e) => return Some(Err(e)),
        };
        if atoms.colours.is_some()
            || !whole.fits(&grid, &effective)
            || !minus.fits(&grid, &effective)
        {
            return None;
        }
        // Kept as this engine's path stores this grid.
        let from = match self.dense_for(&grid) {
            true => DensityFrom::DenseDifference(whole.dense()?, minus.dense()?),
            false => DensityFrom::BrickDifference(whole.bricks()?, minus.bricks()?),
        };
        Some(self.compute_from(atoms, params, from, Some(grid)))
    }
}

impl CpuEngine {
    /// The surface of `atoms` with its density from `from`, run on a thread of the pool, on
    /// `planned` ([`CpuEngine::plan`] of these atoms under the effective parameters) when the
    /// caller planned it already.
    fn compute_from(
        &mut self,
        atoms: &AtomSet<'_>,
        params: &SurfaceParams,
        from: DensityFrom<'_>,
        planned: Option<GridSpec>,
    ) -> Result<SurfaceOutput, SurfaceError> {
        // Called from outside the thread pool, the whole frame runs on one of its threads: its
        // dozen parallel stages then start from inside the pool instead of each waking the
        // pool from outside and putting the caller to sleep until it finishes.
        if rayon::current_thread_index().is_none() {
            return rayon::scope(|_| self.compute_in_pool(atoms, params, from, planned));
        }
        self.compute_in_pool(atoms, params, from, planned)
    }

    /// The exact Gaussian sum of `atoms` on `grid` for refined vertices, taking vertices from
    /// the engine's [`RefinedReuse`] when it was refined on this grid at this isovalue.
    fn field_of(
        &self,
        atoms: &[PreparedAtom],
        grid: &GridSpec,
        params: &SurfaceParams,
    ) -> AnalyticField {
        let reuse = self
            .reuse
            .as_ref()
            .filter(|r| r.fits(grid, params.isovalue))
            .cloned();
        AnalyticField::new(atoms, grid).with_reuse(reuse)
    }

    /// True when a copy of `bytes` fits in a [`KEPT_MEMORY_SHARE`] of the memory available
    /// (or of the engine's limit): on a very large grid the difference is not worth the risk,
    /// and the interface samples both sides instead.
    fn can_keep(&self, bytes: u64) -> bool {
        let available = memory::memory_for(bytes, self.memory_limit);
        bytes.saturating_mul(KEPT_MEMORY_SHARE) <= available
    }

    /// When asked to ([`SurfaceEngine::set_keep_density`]) and it fits ([`CpuEngine::can_keep`]),
    /// a copy of the density just computed on `grid` under `params` (the dense volume or the
    /// bricks, as this engine's path for `grid` stores it), in the buffers of an earlier copy
    /// that no output holds any more: their pages are mapped already, where new buffers would
    /// fault them in again (which costs more than the copy). A scene keeps its last result
    /// while the next frame is computed, so up to [`KEPT_BUFFERS`] copies are kept for reuse.
    fn keep_copy(&mut self, grid: GridSpec, params: &SurfaceParams) -> Option<Arc<KeptDensity>> {
        let dense = self.dense_for(&grid);
        let bytes = match dense {
            true => self.volume.values.len() as u64 * 4,
            false => self.bricks.stored_bytes(),
        };
        if !self.keep_density || !self.can_keep(bytes) {
            return None;
        }
        let free = self
            .kept
            .iter()
            .position(|k| Arc::strong_count(k) == 1 && Arc::weak_count(k) == 0);
        let mut kept = match free {
            Some(i) => self.kept.swap_remove(i),
            None => {
                if self.kept.len() >= KEPT_BUFFERS {
                    self.kept.remove(0);
                }
                Arc::new(KeptDensity {
                    grid,
                    params: *params,
                    samples: KeptSamples::Dense(Vec::new()),
                })
            }
        };
        if let Some(k) = Arc::get_mut(&mut kept) {
            k.grid = grid;
            k.params = *params;
            match (&mut k.samples, dense) {
                (KeptSamples::Dense(values), true) => {
                    values.clear();
                    values.extend_from_slice(&self.volume.values);
                }
                (KeptSamples::Bricks(bricks), false) => bricks.copy_from(&self.bricks),
                (samples, true) => *samples = KeptSamples::Dense(self.volume.values.clone()),
                (samples, false) => *samples = KeptSamples::Bricks((*self.bricks).clone()),
            }
        }
        self.kept.push(Arc::clone(&kept));
        Some(kept)
    }

    /// [`CpuEngine::compute_from`] on a thread of the pool.
    fn compute_in_pool(
        &mut self,
        atoms: &AtomSet<'_>,
        params: &SurfaceParams,
        from: DensityFrom<'_>,
        planned: Option<GridSpec>,
    ) -> Result<SurfaceOutput, SurfaceError> {
        // Refined vertices run at quality max (grid and refinement, issue 33).
        let params = &self.vertices.effective(params);
        let grid = match planned {
            Some(grid) => grid,
            None => self.plan(atoms, params)?,
        };
        let ms = |t: Instant| t.elapsed().as_secs_f64() * 1e3;

        let refined = self.vertices == VertexMode::Refined;
        // A surface that is only measured (not refined, see below) needs no vertex colours;
        // they do not move the vertices.
        let measured_only = self.measure_only && !refined;
        // A mesh kept with positions only needs no colours or normals either (refined
        // vertices come with their normals from the field).
        let positions_only = measured_only || (self.positions_only && !refined);
        let with_colour = atoms.colours.is_some() && !positions_only;
        // Nor normals: area and volume read positions only.
        let data = if positions_only {
            VertexData::PositionsOnly
        } else {
            VertexData::Full
        };
        let field;
        let kept;
        let (bin_ms, density_ms, t) = if self.dense_for(&grid) {
            let t = Instant::now();
            // A difference needs the atoms binned only for refined vertices' analytic density.
            let difference = match from {
                DensityFrom::DenseDifference(whole, minus) => Some((whole, minus)),
                _ => None,
            };
            let bins = (difference.is_none() || refined)
                .then(|| bin_atoms(atoms, params, &grid, density::slab_planes(&grid)));
            let bin_ms = ms(t);
            let t = Instant::now();
            // Free a brick store a previous sparse call may have left.
            if self.bricks.stored_bytes() > 0 {
                *self.bricks = BrickVolume::default();
            }
            match (difference, &bins) {
                (Some((whole, minus)), _) => {
                    dense_difference_into(whole, minus, &mut self.volume.values);
                    self.volume.colours = None;
                }
                (None, Some(bins)) => {
                    density::compute_binned_into(bins, params, &grid, with_colour, &mut self.volume)
                }
                (None, None) => {} // sampled atoms are always binned (above)
            }
            kept = self.keep_copy(grid, params);
            let density_ms = ms(t);
            let t = Instant::now();
            field = match (refined, &bins) {
                (true, Some(bins)) => Some(self.field_of(&bins.atoms, &grid, params)),
                _ => None,
            };
            drop(bins);
            let iso = params.isovalue;
            march_dense(&grid, &self.volume, iso, field.as_ref(), data, &mut self.mc);
            self.last_bricks = None;
            (bin_ms, density_ms, t)
        } else {
            // Free a dense volume a previous dense call may have left.
            self.volume = DensityVolume::default();
            let t = Instant::now();
            let planes = bricks::slab_planes(&grid);
            // A difference needs the atoms binned only for refined vertices' analytic density.
            let difference = match from {
                DensityFrom::BrickDifference(whole, minus) => Some((whole, minus)),
                _ => None,
            };
            let bins = (difference.is_none() || refined)
                .then(|| bin_atoms_overlapping(atoms, params, &grid, planes, 1));
            let bin_ms = ms(t);
            let t = Instant::now();
            match (difference, &bins) {
                (Some((whole, minus)), _) => self.bricks.difference_of(whole, minus),
                (None, Some(bins)) => {
                    self.bricks
                        .compute(bins, params, &grid, with_colour, &mut self.brick_scratch)
                }
                (None, None) => {} // sampled atoms are always binned (above)
            }
            kept = self.keep_copy(grid, params);
            let density_ms = ms(t);
            let t = Instant::now();
            field = match (refined, &bins) {
                (true, Some(bins)) => Some(self.field_of(&bins.atoms, &grid, params)),
                _ => None,
            };
            drop(bins);
            march_bricks(&self.bricks, field.as_ref(), data, &mut self.mc);
            self.last_bricks = Some(self.bricks.stats());
            (bin_ms, density_ms, t)
        };
        // Refined vertices are measured on the assembled mesh (curvature needs its edges).
        let (mesh, area, enclosed, counts_without_mesh, sharp) = if measured_only {
            let m = self.mc.measure();
            let counts = MeshCounts {
                vertices: m.vertices,
                triangles: m.triangles,
            };
            (Mesh::default(), m.area, m.volume, Some(counts), None)
        } else {
            let mesh = self.mc.merge();
            // Refined surfaces record their sharp triangles, which an interface's sides on
            // their grid may take (`SurfaceOutput::sharp`).
            let (area, enclosed, sharp) = match &field {
                Some(field) => {
                    let on = curved::OnField {
                        field,
                        iso: params.isovalue,
                    };
                    let measured = curved::curved_measure(&mesh, Some(on), true);
                    (measured.area, measured.volume, measured.sharp.map(Arc::new))
                }
                None => {
                    let (area, volume) = mesh.area_and_volume();
                    (area, volume, None)
                }
            };
            (mesh, area, enclosed, None, sharp)
        };
        let mc_ms = ms(t);

        Ok(SurfaceOutput {
            grid,
            mesh,
            area,
            volume: enclosed,
            timings: StageTimings {
                exposure_ms: 0.0,
                upload_ms: 0.0,
                bin_ms,
                density_ms,
                mc_ms,
            },
            counts_without_mesh,
            density: kept,
            sharp,
            periodic: None,
        })
    }
}

/// `forced` when it can stand for `own` (the grid the atoms would get): same spacing, and it
/// holds the atoms' bounding box padded as [`GridSpec::for_atoms`] pads it, so the density is
/// below the isovalue on its boundary and the surface is closed.
fn check_forced_grid(
    forced: &GridSpec,
    own: &GridSpec,
    atoms: &AtomSet<'_>,
    params: &SurfaceParams,
) -> Result<GridSpec, SurfaceError> {
    let bad = |why: String| SurfaceError::InvalidParameter {
        name: "forced grid",
        value: why,
    };
    if forced.spacing != params.spacing || forced.dims.contains(&0) {
        return Err(bad(format!(
            "spacing {} Å and {:?} samples for H = {} Å",
            forced.spacing, forced.dims, params.spacing
        )));
    }
    // The atoms' padded box: `own` starts at its low corner and ends at or past its high one.
    let hi = atoms
        .positions
        .iter()
        .fold(Vec3::splat(f32::NEG_INFINITY), |m, p| m.max(*p));
    let max_radius = atoms.radii.iter().fold(0.0f32, |m, &r| m.max(r));
    let pad = params.cutoff() * params.radius_scale * max_radius + params.spacing;
    let needed_far = hi + Vec3::splat(pad);
    let tolerance = 1e-3 * params.spacing;
    let forced_far = forced.point(forced.dims[0] - 1, forced.dims[1] - 1, forced.dims[2] - 1);
    let inside = own.origin.cmpge(forced.origin - tolerance).all()
        && needed_far.cmple(forced_far + tolerance).all();
    if !inside {
        return Err(bad(format!(
            "{:?} to {:?} Å does not hold the atoms' padded box {:?} to {:?} Å",
            forced.origin, forced_far, own.origin, needed_far
        )));
    }
    Ok(*forced)
}
