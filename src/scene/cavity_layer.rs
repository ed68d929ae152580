//! The cavities of a surface representation in one frame, for the window and `render`: when a
//! representation's `cavities` switch is on ([`Representation::cavities`]), the scene engine
//! runs [`measure::cavities`] on its surface (the host mesh, or the GPU mesh read back) and keeps
//! the cavities, their lining residues and their walls as one mesh in the
//! [`super::LayerResult`]. With the switch off nothing here runs.
//!
//! Each cavity's wall is coloured by its id ([`cavity_rgb`], per vertex): the ids the engine
//! gives are 1, 2, … largest volume first (what a tracker starting at that frame gives); the
//! window's tracks hand their ids over with [`with_cavity_ids`], so a cavity is drawn in the
//! colour its id has in the Cavities panel.
//!
//! The walls are turned inside out: the surface's triangles face into the void (outward from the
//! density), the cavity mesh's face out of it, so a cavity is drawn as a solid blob seen through
//! the (translucent) surface around it.
//!
//! [`Representation::cavities`]: super::representation::Representation::cavities

use std::collections::HashMap;
use std::ops::Range;
use std::sync::Arc;

use super::engine::SceneEngine;
use super::frame::{LayerResult, RepId, SceneError, SceneFrame};
use crate::measure::{self, Cavity, CavityOptions, CavityTracker, MeasureError};
use crate::model::Topology;
use crate::surface::periodic::PeriodicMesh;
use crate::surface::{AtomSet, Mesh, SurfaceParams};

/// Smallest cavity kept, in Å³ (as `surface --min-cavity-volume`'s default: smaller voids are
/// mostly gaps between a few atoms).
pub const MIN_CAVITY_VOLUME_A3: f64 = 1.0;

/// The colours of cavity ids, sRGB bytes: id 1 takes the first, id 7 the first again.
const CAVITY_PALETTE_SRGB: [[u8; 3]; 6] = [
    [255, 140, 40],
    [90, 170, 255],
    [120, 210, 110],
    [230, 90, 160],
    [200, 190, 70],
    [170, 130, 255],
];

/// The colour of cavity id `id` (ids from 1) as sRGB bytes: the Cavities panel's colour for it.
pub fn cavity_srgb8(id: u64) -> [u8; 3] {
    let n = CAVITY_PALETTE_SRGB.len() as u64;
    CAVITY_PALETTE_SRGB[(id.saturating_sub(1) % n) as usize]
}

/// The colour cavity id `id`'s wall is drawn in, linear RGB 0..1 ([`cavity_srgb8`] made
/// linear).
pub fn cavity_rgb(id: u64) -> [f32; 3] {
    cavity_srgb8(id).map(|v| crate::model::colour::srgb_to_linear(f32::from(v) / 255.0))
}

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
    /// Per cavity, the id its wall is coloured by (1, 2, … as found; tracked ids once
    /// [`with_cavity_ids`] handed them over).
    pub ids: Vec<u64>,
    /// Per cavity, its wall's vertices in `mesh` (a range of vertex indices).
    pub wall_vertices: Vec<Range<usize>>,
    /// The walls of every cavity, turned to face out of the void, each in the colour of its
    /// id ([`cavity_rgb`]); positions in Å.
    pub mesh: Mesh,
}

impl CavityLayer {
    /// The layer with its cavities coloured by `ids` (one per cavity, in order; a cavity past
    /// the end of `ids` keeps its id).
    pub fn recoloured(&self, ids: &[u64]) -> CavityLayer {
        let mut out = self.clone();
        for (k, (range, &id)) in self.wall_vertices.iter().zip(ids).enumerate() {
            out.ids[k] = id;
            out.mesh.colours[range.clone()].fill(cavity_rgb(id));
        }
        out
    }
}

/// Hands tracked `ids` (one per cavity of `layer`, in the order found) to `layer`'s cavities,
/// so their walls are drawn in those ids' colours. The layer is left as it is when it has no
/// cavities or already has these ids; otherwise it becomes a copy with recoloured walls (the
/// engine may share the original).
pub fn with_cavity_ids(layer: &mut Arc<LayerResult>, ids: &[u64]) {
    let Some(found) = &layer.cavities else {
        return;
    };
    if found.ids.iter().zip(ids).all(|(a, b)| a == b) {
        return;
    }
    let recoloured = Arc::new(found.recoloured(ids));
    Arc::make_mut(layer).cavities = Some(recoloured);
}

/// Cavity ids over the frames of a movie (`mdsurf render`): one tracker per representation,
/// fed the frames in the order drawn, so a cavity keeps its colour from frame to frame.
#[derive(Debug, Default)]
pub struct MovieCavityIds {
    trackers: HashMap<RepId, CavityTracker>,
}

impl MovieCavityIds {
    /// Tracks the cavities of `scene`'s layers from the frame before and hands their ids to
    /// the layers ([`with_cavity_ids`]).
    pub fn track(&mut self, scene: &mut SceneFrame) {
        for layer in &mut scene.layers {
            let Some(found) = layer.cavities.clone() else {
                continue;
            };
            let tracker = self.trackers.entry(layer.id).or_default();
            let update = tracker.update(scene.frame, &found.cavities);
            let ids: Vec<u64> = update.cavities.iter().map(|c| c.id).collect();
            with_cavity_ids(layer, &ids);
        }
    }
}

/// Which atoms a surface was computed from, for the lining residues.
#[derive(Debug, Clone, PartialEq)]
pub struct CavitySource {
    /// The topology atoms of the particles (`None`: all).
    pub subset: Option<Vec<u32>>,
    /// True when the particles are residue beads (no lining residues then).
    pub beads: bool,
    /// The representation's cavity probe (Å): the cavities are the probe's
    /// ([`measure::probe_cavities`]), not the surface's voids.
    pub probe: Option<f32>,
}

/// Finds the cavities of `mesh`, the surface of `atoms` computed under `params` (the parameters
/// the engine used; `periodic` for a periodic surface's mesh), with their lining residues
/// (labels from `topology`) and their walls.
pub fn find_cavities(
    topology: &Topology,
    source: &CavitySource,
    (mesh, periodic): (&Mesh, Option<&PeriodicMesh>),
    atoms: &AtomSet<'_>,
    params: &SurfaceParams,
) -> Result<CavityLayer, MeasureError> {
    if let Some(probe) = source.probe {
        if periodic.is_some() {
            return Err(MeasureError::PeriodicProbe);
        }
        return find_probe_cavities(topology, source, atoms, probe);
    }
    if let Some(seams) = periodic {
        let options = cavity_options();
        let found = measure::periodic_cavity_walls(mesh, seams, atoms, params, &options)?;
        return layer_of_walls(topology, source, found, true);
    }
    let cavities = measure::cavities(mesh, atoms, params, &cavity_options())?;
    let lining = lining_labels(topology, source, &cavities)?;
    let (mesh, wall_vertices) = if cavities.is_empty() {
        (Mesh::default(), Vec::new())
    } else {
        walls(mesh, &cavities)?
    };
    Ok(CavityLayer {
        ids: (1..=cavities.len() as u64).collect(),
        cavities,
        lining,
        wall_vertices,
        mesh,
    })
}

/// The cavities of a probe of radius `probe` Å among `atoms` (Bondi's radii for atoms, the
/// particles' own for beads), their lining residues and their walls.
fn find_probe_cavities(
    topology: &Topology,
    source: &CavitySource,
    atoms: &AtomSet<'_>,
    probe: f32,
) -> Result<CavityLayer, MeasureError> {
    let options = measure::ProbeOptions {
        probe,
        min_volume: MIN_CAVITY_VOLUME_A3,
        ..measure::ProbeOptions::default()
    };
    let found = if source.beads {
        measure::probe_cavity_walls(atoms, &options)?
    } else {
        measure::ses_probe_cavity_walls(topology, source.subset.as_deref(), atoms, &options)?
    };
    layer_of_walls(topology, source, found, false)
}

/// The layer of cavities found with their walls, each wall in its cavity's colour; `turn`
/// reverses walls that face into their voids (a surface's own triangles).
fn layer_of_walls(
    topology: &Topology,
    source: &CavitySource,
    found: Vec<(Cavity, Mesh)>,
    turn: bool,
) -> Result<CavityLayer, MeasureError> {
    let mut out = Mesh::default();
    let mut wall_vertices = Vec::with_capacity(found.len());
    for (k, (_, wall)) in found.iter().enumerate() {
        let start = out.positions.len();
        let first = start as u32;
        out.positions.extend_from_slice(&wall.positions);
        let sign = if turn { -1.0 } else { 1.0 };
        out.normals.extend(wall.normals.iter().map(|&n| n * sign));
        out.colours.extend(std::iter::repeat_n(
            cavity_rgb(k as u64 + 1),
            wall.positions.len(),
        ));
        for t in wall.indices.chunks_exact(3) {
            // Reversed winding where the wall faced into the void: it now faces out of it.
            let [a, b, d] = [t[0], t[1], t[2]].map(|i| i + first);
            out.indices.extend(if turn { [a, d, b] } else { [a, b, d] });
        }
        wall_vertices.push(start..out.positions.len());
    }
    let cavities: Vec<Cavity> = found.into_iter().map(|(cavity, _)| cavity).collect();
    let lining = lining_labels(topology, source, &cavities)?;
    Ok(CavityLayer {
        ids: (1..=cavities.len() as u64).collect(),
        cavities,
        lining,
        wall_vertices,
        mesh: out,
    })
}

/// Per cavity, the labels of its lining residues (at most [`MAX_LINING_LABELS`]; none for
/// beads).
fn lining_labels(
    topology: &Topology,
    source: &CavitySource,
    cavities: &[Cavity],
) -> Result<Vec<Vec<String>>, MeasureError> {
    Ok(if source.beads {
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
        let params = result.measured_params();
        let periodic = result.output.periodic.as_deref();
        find_cavities(topology, source, (mesh, periodic), &atoms, &params)
            .map(|c| Some(Arc::new(c)))
            .map_err(|source| SceneError::Cavities {
                frame: index,
                rep: result.rep.name.clone(),
                source,
            })
    }
}

/// The triangles of the components of `mesh` that are `cavities` (the same area and volume as
/// [`measure::components`] computes them), turned inside out, cavity by cavity in the order of
/// `cavities`, each in the colour of its place (id 1, 2, …); with each cavity's vertex range.
fn walls(mesh: &Mesh, cavities: &[Cavity]) -> Result<(Mesh, Vec<Range<usize>>), MeasureError> {
    let components = measure::components(mesh)?;
    let mut out = Mesh::default();
    let mut ranges = Vec::with_capacity(cavities.len());
    let mut new_index = vec![u32::MAX; mesh.positions.len()];
    for (k, cavity) in cavities.iter().enumerate() {
        let start = out.positions.len();
        let wall = components.iter().find(|c| {
            cavity.volume == -c.volume && cavity.area == c.area && cavity.centroid == c.centroid
        });
        if let Some(c) = wall {
            let colour = cavity_rgb(k as u64 + 1);
            for &v in &c.vertices {
                new_index[v as usize] = out.positions.len() as u32;
                out.positions.push(mesh.positions[v as usize]);
                out.normals
                    .push(-mesh.normals.get(v as usize).copied().unwrap_or_default());
                out.colours.push(colour);
            }
            for &t in &c.triangles {
                let t = 3 * t as usize;
                let [a, b, d] = [0, 1, 2].map(|j| new_index[mesh.indices[t + j] as usize]);
                // Reversed winding: the triangle now faces out of the void.
                out.indices.extend([a, d, b]);
            }
        }
        ranges.push(start..out.positions.len());
    }
    Ok((out, ranges))
}
