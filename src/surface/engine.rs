//! The interface every surface engine offers (the CPU reference here, the GPU engine in
//! [`crate::gpu`]): atoms in, mesh plus measurements and stage timings out.

use std::sync::Arc;

use glam::Vec3;

use super::scan::first_failing;
use super::{GridSpec, KeptDensity, Mesh, SurfaceError, SurfaceParams, VertexMode};

/// The particles one surface is built from. All slices have the same length.
#[derive(Debug, Clone, Copy)]
pub struct AtomSet<'a> {
    /// Positions in Å.
    pub positions: &'a [Vec3],
    /// Radii in Å (before scaling by R).
    pub radii: &'a [f32],
    /// Linear RGB colour per atom in 0..1; `None` gives a white surface and skips the colour pass.
    pub colours: Option<&'a [[f32; 3]]>,
}

impl AtomSet<'_> {
    /// Number of atoms.
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// True when there are no atoms.
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// Linear RGB colour of atom `i` (white when the set has no colours).
    pub fn colour(&self, i: usize) -> [f32; 3] {
        self.colours.map_or([1.0; 3], |c| c[i])
    }

    /// Checks the atoms: at least one, equal slice lengths, finite coordinates (Å), positive
    /// finite radii (Å) and finite colours.
    pub fn validate(&self) -> Result<(), SurfaceError> {
        let n = self.positions.len();
        if n == 0 {
            return Err(SurfaceError::EmptySystem);
        }
        if self.radii.len() != n {
            return Err(SurfaceError::LengthMismatch {
                what: "radii",
                expected: n,
                got: self.radii.len(),
            });
        }
        if let Some(c) = self.colours
            && c.len() != n
        {
            return Err(SurfaceError::LengthMismatch {
                what: "colours",
                expected: n,
                got: c.len(),
            });
        }
        if let Some(atom) = first_failing(self.positions, |p| p.is_finite()) {
            return Err(SurfaceError::NonFiniteCoordinate { atom });
        }
        if let Some(atom) = first_failing(self.radii, |r| r.is_finite() && *r > 0.0) {
            return Err(SurfaceError::InvalidRadius {
                atom,
                radius: self.radii[atom],
            });
        }
        if let Some(atom) = self
            .colours
            .and_then(|c| first_failing(c, |c| c.iter().all(|v| v.is_finite())))
        {
            return Err(SurfaceError::NonFiniteColour { atom });
        }
        Ok(())
    }
}

/// Wall-clock or GPU-timestamp time of each stage, in milliseconds (0 where a stage did not run).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StageTimings {
    /// Exposure counts and radii of the SES preset on the GPU (0 elsewhere: the host computes
    /// them with the particles, [`crate::model::exposure`]).
    pub exposure_ms: f64,
    /// Upload of positions (and radii/colours when they changed) to the engine.
    pub upload_ms: f64,
    /// Binning atoms into cells (the paper's t_sort).
    pub bin_ms: f64,
    /// Density and colour volumes (the paper's t_d).
    pub density_ms: f64,
    /// Marching Cubes, area and volume (the paper's t_MC).
    pub mc_ms: f64,
}

impl StageTimings {
    /// Exposure + binning + density + Marching Cubes in ms (without exposure radii, the
    /// paper's Table 1 total).
    pub fn compute_ms(&self) -> f64 {
        self.exposure_ms + self.bin_ms + self.density_ms + self.mc_ms
    }
}

/// One computed surface.
#[derive(Debug, Clone, Default)]
pub struct SurfaceOutput {
    /// The grid the density was sampled on.
    pub grid: GridSpec,
    /// The isosurface.
    pub mesh: Mesh,
    /// Surface area in Å².
    pub area: f64,
    /// Enclosed volume in Å³.
    pub volume: f64,
    /// Time spent per stage.
    pub timings: StageTimings,
    /// Set when the engine measured the surface without keeping its mesh (see
    /// [`SurfaceEngine::set_keep_mesh`]); `mesh` is then empty.
    pub counts_without_mesh: Option<MeshCounts>,
    /// The density at every sample of `grid`, when the engine was asked to keep it
    /// ([`SurfaceEngine::set_keep_density`]) and sampled the whole grid.
    pub density: Option<Arc<KeptDensity>>,
    /// A refined surface's sharp triangles as it measured them on the Gaussian sum
    /// ([`crate::surface::curved::SharpTriangles`]), for the sides of an interface on its grid
    /// to take; `None` from engines that do not record them.
    pub sharp: Option<Arc<crate::surface::curved::SharpTriangles>>,
    /// A periodic surface's cell, images and face seams (the periodic engine's; `None` from
    /// the others), which measurements on its open mesh need.
    pub periodic: Option<Arc<crate::surface::periodic::PeriodicMesh>>,
}

/// Size of a mesh that was measured but not kept.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct MeshCounts {
    /// Vertices of the mesh.
    pub vertices: usize,
    /// Triangles of the mesh.
    pub triangles: usize,
}

impl SurfaceOutput {
    /// The area (Å²) the surface's per-atom areas sum to ([`crate::measure::atom_areas_of`]):
    /// [`Self::area`], or, for a periodic surface shown as several images, one cell's (the
    /// area over the images shown).
    pub fn measured_area(&self) -> f64 {
        match &self.periodic {
            Some(seams) => self.area / f64::from(seams.replicate.count()),
            None => self.area,
        }
    }

    /// Vertices of the surface (kept or not).
    pub fn vertex_count(&self) -> usize {
        self.counts_without_mesh
            .map_or(self.mesh.vertex_count(), |c| c.vertices)
    }

    /// Triangles of the surface (kept or not).
    pub fn triangle_count(&self) -> usize {
        self.counts_without_mesh
            .map_or(self.mesh.triangle_count(), |c| c.triangles)
    }
}

impl Default for GridSpec {
    fn default() -> Self {
        GridSpec {
            origin: Vec3::ZERO,
            spacing: 1.0,
            dims: [0; 3],
        }
    }
}

/// A surface engine (CPU or GPU).
pub trait SurfaceEngine {
    /// Short name for messages and benchmark tables (`cpu`, `gpu`).
    fn name(&self) -> &str;

    /// Computes the surface of `atoms` under `params`.
    fn compute(
        &mut self,
        atoms: &AtomSet<'_>,
        params: &SurfaceParams,
    ) -> Result<SurfaceOutput, SurfaceError>;

    /// With `false`, later surfaces may be measured (area, volume, counts) without keeping
    /// their mesh, which saves the memory and time of assembling it (`mdsurf surface` with
    /// `--stats` and no `-o`); see [`SurfaceOutput::counts_without_mesh`]. An engine that always
    /// builds the mesh ignores it. Default: the mesh is kept.
    fn set_keep_mesh(&mut self, _keep: bool) {}

    /// With `true`, later surfaces whose mesh is kept keep only its positions and triangles
    /// (no normals or colours), where the engine can: for meshes that are only measured, such
    /// as the interface's sides weighed per atom. Default: the whole mesh.
    fn set_mesh_positions_only(&mut self, _only: bool) {}

    /// With `true`, later surfaces keep their sampled density in
    /// [`SurfaceOutput::density`] where the engine samples the whole grid (the CPU engine's
    /// dense path), for [`SurfaceEngine::compute_difference`]. An engine that cannot ignores
    /// it. Default: not kept.
    fn set_keep_density(&mut self, _keep: bool) {}

    /// The surface of `atoms` computed from the density `whole` less `minus` instead of from
    /// its atoms' Gaussians. Both were kept ([`SurfaceEngine::set_keep_density`]) on the grid
    /// this engine gives `atoms` (force it with [`SurfaceEngine::set_grid`]) under `params`:
    /// when `whole` is the density of `atoms` together with the atoms `minus` is the density
    /// of, the result is [`SurfaceEngine::compute`]'s to rounding (refined vertices are placed
    /// on `atoms`' own analytic density). `None` when this engine cannot, or the densities do
    /// not fit that grid and parameters, or `atoms` carry colours: then call `compute`.
    fn compute_difference(
        &mut self,
        _atoms: &AtomSet<'_>,
        _params: &SurfaceParams,
        _whole: &KeptDensity,
        _minus: &KeptDensity,
    ) -> Option<Result<SurfaceOutput, SurfaceError>> {
        None
    }

    /// Sets how later surfaces place their vertices and normals (issue 13); an engine that
    /// cannot refine keeps interpolating and reports so through [`SurfaceEngine::vertices`].
    fn set_vertices(&mut self, _mode: VertexMode) {}

    /// How this engine places vertices and normals.
    fn vertices(&self) -> VertexMode {
        VertexMode::Interpolated
    }

    /// With `Some`, later refined surfaces take their vertices from another surface's on the
    /// same grid where no atom that differs between the two reaches
    /// ([`crate::surface::analytic::RefinedReuse`]; the interface's sides take the complex's);
    /// `None` solves every vertex. Returns `false` when this engine cannot (the default; then
    /// nothing changes).
    fn set_refined_reuse(
        &mut self,
        _reuse: Option<Arc<crate::surface::analytic::RefinedReuse>>,
    ) -> bool {
        false
    }

    /// Makes later surfaces use `grid` (origin, spacing and sample counts) instead of the grid
    /// their atoms would get, so that several surfaces share one grid (the buried area of an
    /// interface compares A, B and A with B on the union's grid); `None` goes back to the
    /// default. The grid must hold every atom's padded bounding box (see
    /// [`GridSpec::for_atoms`]) and have the spacing of the parameters, or `compute` fails.
    /// Returns `false` when this engine cannot force a grid (the default; then nothing changes).
    fn set_grid(&mut self, _grid: Option<GridSpec>) -> bool {
        false
    }
}
