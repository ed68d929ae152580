//! Periodic density (issue 11 §2, issue 30): the surface of atoms in a periodic cell, where
//! the Gaussians of atoms near a face also reach across it, so a liquid, a material or a
//! membrane patch has no walls or seams at the cell faces.
//!
//! Data flow: [`AtomSet`] + [`PeriodicBox`] + [`SurfaceParams`] -> images of the atoms that reach
//! the box ([`density`]) -> density (and colour) on a periodic grid of `N_i = ceil(L_i / H)`
//! samples per axis, spacing `L_i / N_i <= H` -> Marching Cubes over every cell with wrap-around
//! ([`mc`]) -> the mesh inside one box, open at the faces -> area and per-box volume
//! ([`measure`]) -> optionally `a x b x c` copies side by side ([`replicate_mesh`]).
//!
//! Definitions are those of DESIGN section 2 with every periodic image of every atom counted:
//! `rho(x) = sum_i sum_n exp(-|x - p_i - n L|^2 / (2 alpha_i^2))` over the pairs within the
//! cutoff, the colour volume likewise. Area is the sum of the triangle areas of the mesh in the
//! box; the volume is that of the region `rho >= I` inside the box, exact for the piecewise-
//! linear surface (see [`measure`]). Both are per box, so shifting every atom by any vector and
//! wrapping changes them only by the sampling error.
//!
//! Rectangular boxes (edges along x, y, z) take the path above, unchanged. Triclinic and
//! rotated cells ([`PeriodicCell::Triclinic`]) are sampled along their edge vectors and
//! marched in index space ([`triclinic`], its density in [`triclinic_fill`]), with the same definitions: area of the Cartesian
//! triangles, volume of the region `rho >= I` inside one cell.

pub(crate) mod cell;
pub mod density;
pub(crate) mod mc;
pub mod measure;
pub mod seams;
pub(crate) mod triclinic;
mod triclinic_fill;

pub use cell::{PeriodicCell, TriclinicCell};
pub use seams::{FaceTwin, PeriodicMesh};

use std::fmt;
use std::time::Instant;

use glam::Vec3;

use super::{
    AtomSet, DensityVolume, GridSpec, Mesh, StageTimings, SurfaceError, SurfaceOutput,
    SurfaceParams, available_memory_bytes,
};

/// The largest image count along one axis for `--replicate`.
pub const MAX_REPLICATE: u32 = 16;

/// Boxes narrower than this (Å) along any axis are not treated as periodic boxes (the same
/// limit as [`crate::model::pbc::MIN_WIDTH`]: a placeholder such as PDB's `CRYST1 1 1 1`).
pub const MIN_BOX: f32 = 4.0;

/// An orthorhombic periodic box: `origin + [0, L_x) x [0, L_y) x [0, L_z)` (Å).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PeriodicBox {
    /// The corner of the box with the smallest coordinates (Å).
    pub origin: Vec3,
    /// Edge lengths L_x, L_y, L_z (Å).
    pub lengths: Vec3,
}

/// Why a cell cannot be used as a periodic box; prints as one line (the caller adds the file).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BoxError {
    /// The cell is not a rectangular box aligned with x, y and z (from [`PeriodicBox::from_cell`]
    /// only; [`PeriodicCell::from_cell`] takes such cells as [`TriclinicCell`]s).
    #[error(
        "the cell a = ({:.3}, {:.3}, {:.3}), b = ({:.3}, {:.3}, {:.3}), c = ({:.3}, {:.3}, {:.3}) Å is triclinic (or rotated), not a box with edges along x, y and z",
        rows[0].x, rows[0].y, rows[0].z, rows[1].x, rows[1].y, rows[1].z, rows[2].x, rows[2].y, rows[2].z
    )]
    Triclinic {
        /// Edge vectors a, b, c (Å).
        rows: [Vec3; 3],
    },
    /// An edge length that is not finite or shorter than [`MIN_BOX`].
    #[error(
        "the box {:.3} x {:.3} x {:.3} Å is not a periodic box (each edge must be at least {MIN_BOX} Å)",
        lengths.x, lengths.y, lengths.z
    )]
    TooSmall {
        /// Edge lengths (Å).
        lengths: Vec3,
    },
    /// A cell whose opposite faces are closer than [`MIN_BOX`] (or not finite).
    #[error(
        "the cell is {:.3} x {:.3} x {:.3} Å between opposite faces, not a periodic cell (each width must be at least {MIN_BOX} Å)",
        widths.x, widths.y, widths.z
    )]
    Thin {
        /// Distances between opposite faces (Å).
        widths: Vec3,
    },
}

impl PeriodicBox {
    /// The box `[0, L_x) x [0, L_y) x [0, L_z)` with edge lengths `lengths` (Å).
    pub fn new(lengths: Vec3) -> Result<PeriodicBox, BoxError> {
        if !(lengths.is_finite() && lengths.min_element() >= MIN_BOX) {
            return Err(BoxError::TooSmall { lengths });
        }
        Ok(PeriodicBox {
            origin: Vec3::ZERO,
            lengths,
        })
    }

    /// The box of a frame's cell (rows a, b, c in Å, as [`crate::model::Frame::cell`] holds
    /// them). Refuses cells whose edges are not along x, y and z (relative tolerance 1e-5).
    pub fn from_cell(rows: &[Vec3; 3]) -> Result<PeriodicBox, BoxError> {
        let [a, b, c] = *rows;
        let lengths = Vec3::new(a.x, b.y, c.z);
        let off = |v: Vec3, along: usize| {
            let len = v.length();
            (0..3)
                .filter(|&k| k != along)
                .any(|k| v[k].abs() > 1e-5 * len)
        };
        if !rows.iter().all(|r| r.is_finite()) {
            return Err(BoxError::TooSmall { lengths });
        }
        if off(a, 0) || off(b, 1) || off(c, 2) {
            return Err(BoxError::Triclinic { rows: *rows });
        }
        PeriodicBox::new(lengths)
    }

    /// Samples per axis for grid spacing `h` (Å): `ceil(L / h)`, at least 2.
    pub fn samples(&self, h: f32) -> [u32; 3] {
        self.lengths
            .to_array()
            .map(|l| ((l / h).ceil() as u64).clamp(2, u32::MAX as u64 / 4) as u32)
    }
}

/// How many images of the cell the mesh shows side by side along x, y and z (along a, b and c
/// for a triclinic cell; `--replicate`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(transparent)]
pub struct Replicate(pub [u32; 3]);

impl Default for Replicate {
    fn default() -> Self {
        Replicate([1, 1, 1])
    }
}

impl Replicate {
    /// True for one image (no replication).
    pub fn is_one(&self) -> bool {
        self.0 == [1, 1, 1]
    }

    /// Number of images in all.
    pub fn count(&self) -> u32 {
        self.0.iter().product()
    }

    /// Checks every count is in `1..=MAX_REPLICATE`; the error is one line.
    pub fn validate(&self) -> Result<(), ReplicateError> {
        if self.0.iter().all(|&n| (1..=MAX_REPLICATE).contains(&n)) {
            Ok(())
        } else {
            Err(ReplicateError(*self))
        }
    }
}

/// Replication counts outside `1..=MAX_REPLICATE`.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("--replicate {0}: expected three whole numbers from 1 to {MAX_REPLICATE}, e.g. 2,2,1")]
pub struct ReplicateError(pub Replicate);

impl fmt::Display for Replicate {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let [a, b, c] = self.0;
        write!(f, "{a},{b},{c}")
    }
}

impl std::str::FromStr for Replicate {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let bad = || format!("expected three whole numbers from 1 to {MAX_REPLICATE}, e.g. 2,2,1");
        let parts: Vec<&str> = s.split([',', 'x']).map(str::trim).collect();
        let [a, b, c] = parts[..] else {
            return Err(bad());
        };
        let n = |t: &str| t.parse::<u32>().map_err(|_| bad());
        let r = Replicate([n(a)?, n(b)?, n(c)?]);
        r.validate().map_err(|_| bad())?;
        Ok(r)
    }
}

/// The one-line note printed when a GPU engine was asked for and `--periodic` is on.
pub const GPU_NOTE: &str = "note: --periodic: surfaces are computed by the CPU periodic engine \
                            (the GPU engine has no periodic path)";

/// Why a periodic surface of one frame could not be computed; prints as one line (the caller
/// adds the file and frame).
#[derive(Debug, thiserror::Error)]
pub enum PeriodicError {
    /// The frame has no box.
    #[error("no periodic box (--periodic needs one)")]
    NoBox,
    /// The frame's box cannot be used.
    #[error("--periodic: {0}")]
    Box(#[from] BoxError),
    /// The surface failed (bad atoms or parameters, grid too large).
    #[error("{0}")]
    Surface(#[from] SurfaceError),
}

/// The periodic surface engine (CPU, rayon). Keeps its density volume between calls, so a
/// sequence of frames of the same box allocates it once.
#[derive(Debug, Default)]
pub struct PeriodicEngine {
    memory_limit: Option<u64>,
    volume: DensityVolume,
}

impl PeriodicEngine {
    /// An engine that refuses grids larger than the memory currently available.
    pub fn new() -> PeriodicEngine {
        PeriodicEngine::default()
    }

    /// An engine that refuses grids needing more than `bytes`.
    pub fn with_memory_limit(bytes: u64) -> PeriodicEngine {
        PeriodicEngine {
            memory_limit: Some(bytes),
            ..PeriodicEngine::default()
        }
    }

    /// The surface of `atoms` in the periodic box `pbox` under `params`, shown as `replicate`
    /// images. Positions may lie anywhere (they are wrapped). Area (Å²) and volume (Å³) are
    /// those of the mesh returned: per box, times the number of images with `replicate`.
    pub fn compute(
        &mut self,
        atoms: &AtomSet<'_>,
        params: &SurfaceParams,
        pbox: &PeriodicBox,
        replicate: Replicate,
    ) -> Result<SurfaceOutput, SurfaceError> {
        check_inputs(atoms, params, replicate)?;
        let dims = pbox.samples(params.spacing);
        let with_colour = atoms.colours.is_some();
        let available = self.memory_limit.unwrap_or_else(available_memory_bytes);
        check_grid(dims, with_colour, available)?;
        let grid = density::PeriodicGrid::new(pbox, dims);
        let ms = |t: Instant| t.elapsed().as_secs_f64() * 1e3;

        let t = Instant::now();
        let images = density::bin_images(atoms, params, &grid);
        let bin_ms = ms(t);
        let t = Instant::now();
        density::compute_volume(
            &images,
            &grid,
            params.isovalue,
            with_colour,
            &mut self.volume,
        );
        drop(images);
        let density_ms = ms(t);
        let t = Instant::now();
        let mut mesh = mc::extract(&grid, &self.volume, params.isovalue);
        let area = mesh.area();
        let volume = measure::box_volume(&mesh, &grid, &self.volume.values, params.isovalue, 0);
        check_replicas(mesh.positions.len(), replicate, "box")?;
        // The upper faces' coordinate as Marching Cubes computes it, `(N + 0) h`.
        let top = Vec3::from_array(std::array::from_fn(|k| {
            (dims[k] as f32 + 0.0) * grid.spacing[k]
        }));
        let extent = grid.extent();
        let (face_twins, unmatched) = seams::face_twins(&mesh.positions, top);
        let seams = PeriodicMesh {
            cell: TriclinicCell {
                origin: pbox.origin,
                rows: [Vec3::X * extent.x, Vec3::Y * extent.y, Vec3::Z * extent.z],
            },
            replicate,
            cell_vertices: mesh.positions.len() as u32,
            cell_triangles: mesh.triangle_count() as u32,
            face_twins,
            unmatched,
        };
        for p in &mut mesh.positions {
            *p += pbox.origin;
        }
        let mesh = replicate_mesh(mesh, extent, replicate);
        let timings = StageTimings {
            exposure_ms: 0.0,
            upload_ms: 0.0,
            bin_ms,
            density_ms,
            mc_ms: ms(t),
        };
        let grid = GridSpec {
            origin: pbox.origin,
            spacing: grid.spacing.max_element(),
            dims,
        };
        Ok(periodic_output(grid, mesh, [area, volume], seams, timings))
    }

    /// The surface of `atoms` in the triclinic `cell` (any cell, rectangular ones included,
    /// through the triclinic path of [`triclinic`]), shown as `replicate` images along a, b
    /// and c. Area (Å²) and volume (Å³) per cell, times the number of images.
    pub fn compute_triclinic(
        &mut self,
        atoms: &AtomSet<'_>,
        params: &SurfaceParams,
        cell: &TriclinicCell,
        replicate: Replicate,
    ) -> Result<SurfaceOutput, SurfaceError> {
        check_inputs(atoms, params, replicate)?;
        let memory = self.memory_limit.unwrap_or_else(available_memory_bytes);
        triclinic::compute(&mut self.volume, memory, atoms, params, cell, replicate)
    }

    /// [`PeriodicEngine::compute`] or [`PeriodicEngine::compute_triclinic`], as `cell` is.
    pub fn compute_cell(
        &mut self,
        atoms: &AtomSet<'_>,
        params: &SurfaceParams,
        cell: &PeriodicCell,
        replicate: Replicate,
    ) -> Result<SurfaceOutput, SurfaceError> {
        match cell {
            PeriodicCell::Rectangular(b) => self.compute(atoms, params, b, replicate),
            PeriodicCell::Triclinic(c) => self.compute_triclinic(atoms, params, c, replicate),
        }
    }

    /// [`PeriodicEngine::compute_cell`] in a frame's cell (rows a, b, c in Å, as
    /// [`crate::model::Frame::cell`] holds them): rectangular or triclinic.
    pub fn compute_in_cell(
        &mut self,
        cell: Option<&[Vec3; 3]>,
        atoms: &AtomSet<'_>,
        params: &SurfaceParams,
        replicate: Replicate,
    ) -> Result<SurfaceOutput, PeriodicError> {
        let cell = PeriodicCell::from_cell(cell.ok_or(PeriodicError::NoBox)?)?;
        Ok(self.compute_cell(atoms, params, &cell, replicate)?)
    }

    /// The density volume of the last computation (for tests).
    pub fn last_volume(&self) -> &DensityVolume {
        &self.volume
    }
}

/// `mesh` (one box of edge lengths `extent`, Å) copied `replicate` times side by side along x,
/// y and z; vertices on shared faces are duplicated, not merged.
pub fn replicate_mesh(mesh: Mesh, extent: Vec3, replicate: Replicate) -> Mesh {
    if replicate.is_one() {
        return mesh;
    }
    let n = replicate.count() as usize;
    let verts = mesh.positions.len();
    let mut out = Mesh {
        positions: Vec::with_capacity(verts * n),
        normals: Vec::with_capacity(verts * n),
        colours: Vec::with_capacity(verts * n),
        indices: Vec::with_capacity(mesh.indices.len() * n),
    };
    let [a, b, c] = replicate.0;
    for kc in 0..c {
        for kb in 0..b {
            for ka in 0..a {
                let shift = extent * Vec3::new(ka as f32, kb as f32, kc as f32);
                let base = out.positions.len() as u32;
                out.positions
                    .extend(mesh.positions.iter().map(|&p| p + shift));
                out.normals.extend_from_slice(&mesh.normals);
                out.colours.extend_from_slice(&mesh.colours);
                out.indices.extend(mesh.indices.iter().map(|&i| i + base));
            }
        }
    }
    out
}
/// Checks what every periodic surface needs: parameters, atoms and a sane image count.
fn check_inputs(
    atoms: &AtomSet<'_>,
    params: &SurfaceParams,
    replicate: Replicate,
) -> Result<(), SurfaceError> {
    params.validate()?;
    atoms.validate()?;
    if replicate.validate().is_err() {
        return Err(SurfaceError::InvalidParameter {
            name: "replicate count",
            value: replicate.to_string(),
        });
    }
    Ok(())
}

/// Refuses a grid of `dims` samples that does not fit in `available` bytes.
pub(super) fn check_grid(
    dims: [u32; 3],
    with_colour: bool,
    available: u64,
) -> Result<(), SurfaceError> {
    let dims64 = dims.map(u64::from);
    let needed = super::estimate_grid_bytes(dims64, with_colour);
    if needed > available {
        return Err(SurfaceError::GridTooLarge {
            dims: dims64,
            bytes_needed: needed,
            bytes_available: available,
        });
    }
    Ok(())
}

/// Refuses `replicate` copies of a mesh of `vertices` vertices per `unit` (box or cell) when
/// they would pass 32-bit vertex indices.
pub(super) fn check_replicas(
    vertices: usize,
    replicate: Replicate,
    unit: &str,
) -> Result<(), SurfaceError> {
    if vertices as u64 * replicate.count() as u64 > u32::MAX as u64 {
        return Err(SurfaceError::InvalidParameter {
            name: "replicate count",
            value: format!("{replicate} ({vertices} vertices per {unit})"),
        });
    }
    Ok(())
}

/// A periodic surface's output: `[area, volume]` of one box or cell (Å², Å³) times the images
/// shown (`seams.replicate`).
pub(super) fn periodic_output(
    grid: GridSpec,
    mesh: Mesh,
    [area, volume]: [f64; 2],
    seams: PeriodicMesh,
    timings: StageTimings,
) -> SurfaceOutput {
    let images = seams.replicate.count() as f64;
    SurfaceOutput {
        grid,
        mesh,
        area: area * images,
        volume: volume * images,
        counts_without_mesh: None,
        density: None,
        sharp: None,
        periodic: Some(std::sync::Arc::new(seams)),
        timings,
    }
}
