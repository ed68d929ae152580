//! The cavities of a surface representation in one frame, for the window and `render`: when a
//! representation's `cavities` switch is on ([`Representation::cavities`]), the scene engine
//! runs [`measure::cavities`] on its surface (the host mesh, or the GPU mesh read back) and keeps
//! the cavities, their lining residues and their walls as one mesh in [`CAVITY_RGB`] in the
//! [`super::LayerResult`]. With the switch off nothing here runs.
//!
//! The walls are turned inside out: the surface's triangles face into the void (outward from the
//! density), the cavity mesh's face out of it, so a cavity is drawn as a solid blob seen through
//! the (translucent) surface around it.
//!
//! [`Representation::cavities`]: super::representation::Representation::cavities

use std::sync::Arc;

use super::engine::SceneEngine;
use super::frame::{LayerResult, SceneError};
use crate::measure::{self, Cavity, CavityOptions, MeasureError};
use crate::model::Topology;
use crate::surface::{AtomSet, Mesh, SurfaceParams};

/// Smallest cavity kept, in Å³ (as `surface --min-cavity-volume`'s default: smaller voids are
/// mostly gaps between a few atoms).
pub const MIN_CAVITY_VOLUME_A3: f64 = 1.0;

/// The colour cavities are drawn in: orange, linear RGB 0..1.
pub const CAVITY_RGB: [f32; 3] = [1.0, 0.35, 0.02];

/// Lining residues listed per cavity at most (the panel shows the first few).
const MAX_LINING_LABELS: usize = 64;

/// The options the scene engine finds cavities with.
pub fn cavity_options() -> CavityOptions {
    CavityOptions {
        min_volume: MIN_CAVITY_VOLUME_A3,
        ..CavityOptions::default()
    }
}

/// The cavities of one representation's surface in one frame.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CavityLayer {
    /// The cavities, largest volume first ([`measure::cavities`] with [`cavity_options`]).
    pub cavities: Vec<Cavity>,
    /// Per cavity, labels (`A:LEU12`) of its lining residues in topology order, at most 64
    /// (empty for bead surfaces, whose particles are not atoms).
    pub lining: Vec<Vec<String>>,
    /// The walls of every cavity, turned to face out of the void, in [`CAVITY_RGB`];
    /// positions in Å.
    pub mesh: Mesh,
}

/// Which atoms a surface was computed from, for the lining residues.
#[derive(Debug, Clone, PartialEq)]
pub struct CavitySource {
    /// The topology atoms of the particles (`None`: all).
    pub subset: Option<Vec<u32>>,
    /// True when the particles are residue beads (no lining residues then).
    pub beads: bool,
}

/// Finds the cavities of `mesh`, the surface of `atoms` computed under `params` (the parameters
/// the engine used), with their lining residues (labels from `topology`) and their walls.
pub fn find_cavities(
    topology: &Topology,
    source: &CavitySource,
    mesh: &Mesh,
    atoms: &AtomSet<'_>,
    params: &SurfaceParams,
) -> Result<CavityLayer, MeasureError> {
    let cavities = measure::cavities(mesh, atoms, params, &cavity_options())?;
    let lining = if source.beads {
        vec![Vec::new(); cavities.len()]
    } else {
        cavities
            .iter()
            .map(|c| {
                let mut labels =
                    measure::lining_residues(topology, source.subset.as_deref(), &c.lining_atoms)?;
                labels.truncate(MAX_LINING_LABELS);
                Ok(labels)
            })
            .collect::<Result<_, MeasureError>>()?
    };
    let mesh = if cavities.is_empty() {
        Mesh::default()
    } else {
        walls(mesh, &cavities)?
    };
    Ok(CavityLayer {
        cavities,
        lining,
        mesh,
    })
}

impl SceneEngine {
    /// The cavities of `result`'s surface (frame `index`; the GPU mesh is read back), from the
    /// atoms `source` names. `None` for a host surface whose mesh was not kept (measured only).
    pub(super) fn cavities_of(
        &mut self,
        topology: &Topology,
        index: usize,
        result: &LayerResult,
        source: &CavitySource,
    ) -> Result<Option<Arc<CavityLayer>>, SceneError> {
        if result.gpu_surface.is_none() && result.output.counts_without_mesh.is_some() {
            return Ok(None);
        }
        let read;
        let mesh = match result.gpu_surface {
            Some(_) => {
                read = self.read_mesh(index, result)?;
                &read
            }
            None => &result.output.mesh,
        };
        let p = &result.particles;
        let atoms = AtomSet {
            positions: &p.positions,
            radii: &p.radii,
            colours: None,
        };
        let params = result.rep.vertices.effective(&result.rep.params());
        find_cavities(topology, source, mesh, &atoms, &params)
            .map(|c| Some(Arc::new(c)))
            .map_err(|source| SceneError::Cavities {
                frame: index,
                rep: result.rep.name.clone(),
                source,
            })
    }
}

/// The triangles of the components of `mesh` that are `cavities` (the same area and volume as
/// [`measure::components`] computes them), turned inside out, in the cavity colour.
fn walls(mesh: &Mesh, cavities: &[Cavity]) -> Result<Mesh, MeasureError> {
    let is_cavity = |c: &measure::Component| {
        cavities
            .iter()
            .any(|k| k.volume == -c.volume && k.area == c.area && k.centroid == c.centroid)
    };
    let mut out = Mesh::default();
    let mut new_index = vec![u32::MAX; mesh.positions.len()];
    for c in measure::components(mesh)?.iter().filter(|c| is_cavity(c)) {
        for &v in &c.vertices {
            new_index[v as usize] = out.positions.len() as u32;
            out.positions.push(mesh.positions[v as usize]);
            out.normals
                .push(-mesh.normals.get(v as usize).copied().unwrap_or_default());
            out.colours.push(CAVITY_RGB);
        }
        for &t in &c.triangles {
            let t = 3 * t as usize;
            let [a, b, d] = [0, 1, 2].map(|k| new_index[mesh.indices[t + k] as usize]);
            // Reversed winding: the triangle now faces out of the void.
            out.indices.extend([a, d, b]);
        }
    }
    Ok(out)
}
