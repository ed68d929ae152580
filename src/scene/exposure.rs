//! Exposure colours (`--color exposure`): each atom takes the colour of its residue's exposure
//! on the representation's own surface in this frame, the same numbers `surface --per-residue`
//! writes: the residue's area (the sum of its atoms' shares, [`measure::atom_areas`]) over the
//! largest area a residue of its name has alone ([`ExposureTable`], built once per
//! representation from its first frame). The colour map spans exposure 0 (buried) to 1 (as
//! exposed as alone); larger values take the top colour.
//!
//! The surface must exist before its exposure does, so a representation coloured this way is
//! computed in two passes: the surface, then (these colours known) its colour pass again. On the
//! GPU the second pass is a colour-only submit ([`crate::gpu::Work::Colour`], asked for by an
//! [`ExposureRequest`]); host engines compute the surface again with the colours
//! ([`host_surface`]).

use std::collections::HashMap;

use super::frame::SceneError;
use super::representation::Representation;
use crate::measure::{self, ExposureTable, MeasureError};
use crate::model::pbc::PbcCell;
use crate::model::{ColorScheme, ColourMap, Topology};
use crate::surface::periodic::PeriodicMesh;
use crate::surface::{AtomSet, CpuEngine, Mesh, SurfaceOutput, SurfaceParams};

/// The scene error of representation `rep`'s exposure colours failing in frame `frame`.
pub(crate) fn exposure_failed(frame: usize, rep: &str) -> impl FnOnce(MeasureError) -> SceneError {
    move |source| SceneError::Exposure {
        frame,
        rep: rep.to_string(),
        source,
    }
}

/// What one representation keeps between frames for its exposure colours.
#[derive(Debug, Default)]
pub(crate) struct ExposureColouring {
    /// The residue names' isolated areas (Å²), from the first frame coloured.
    table: Option<ExposureTable>,
}

/// A representation's surface in one frame, as exposure colouring reads it.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ColouredSurface<'a> {
    /// The mesh (of every image shown, for a periodic surface).
    pub mesh: &'a Mesh,
    /// The area (Å²) its per-atom areas sum to (`SurfaceOutput::measured_area`: one cell's
    /// for a periodic surface).
    pub area: f64,
    /// A periodic surface's seams (`SurfaceOutput::periodic`).
    pub seams: Option<&'a PeriodicMesh>,
    /// The frame's periodic cell, if it has one: the isolated residues of the exposure table
    /// are made whole in it (see [`ExposureTable::from_residue_members`]).
    pub cell: Option<PbcCell>,
}

impl ExposureColouring {
    /// The colour of each atom of `atoms` (the topology atoms `atom_indices`, all of them for
    /// `None`) through `map`, from `surface`, computed with `params` (the effective ones, see
    /// [`crate::surface::VertexMode::effective`]).
    ///
    /// Fails on mismatched lengths or indices (see [`measure::atom_areas`]) or when an
    /// isolated residue's surface fails.
    pub fn colours(
        &mut self,
        topology: &Topology,
        atom_indices: Option<&[u32]>,
        atoms: &AtomSet<'_>,
        params: &SurfaceParams,
        surface: ColouredSurface<'_>,
        map: ColourMap,
    ) -> Result<Vec<[f32; 3]>, MeasureError> {
        let plain = AtomSet {
            colours: None,
            ..*atoms
        };
        let table = match &mut self.table {
            Some(t) => t,
            empty => empty.insert(ExposureTable::from_isolated_residues(
                &mut CpuEngine::new(),
                topology,
                atom_indices,
                &plain,
                surface.cell.as_ref(),
                params,
            )?),
        };
        // As `--per-residue` weighs them.
        let (mesh, seams) = (surface.mesh, surface.seams);
        let areas = measure::scaled_atom_areas(mesh, seams, surface.area, &plain, params)?;
        let residues = measure::residue_areas(topology, atom_indices, &areas)?;
        let exposure: HashMap<u32, f32> = residues
            .iter()
            .map(|r| {
                let resname = r.names(topology).resname;
                let exposure = table.exposure(resname, r.area);
                (r.residue, exposure.map_or(f32::NAN, |e| e as f32))
            })
            .collect();
        let colour_of = |atom: u32| {
            let residue = topology.residue_index[atom as usize];
            map.colour(
                exposure.get(&residue).copied().unwrap_or(f32::NAN),
                [0.0, 1.0],
            )
        };
        Ok(match atom_indices {
            Some(ix) => ix.iter().map(|&a| colour_of(a)).collect(),
            None => (0..atoms.len() as u32).map(colour_of).collect(),
        })
    }
}

/// A GPU surface's exposure colours, asked for when it is submitted.
pub(crate) struct ExposureRequest {
    /// The colour map.
    pub map: ColourMap,
    /// The topology atoms of the particles (`None`: all).
    pub subset: Option<Vec<u32>>,
    /// The frame's periodic cell, if any (see [`ColouredSurface::cell`]).
    pub cell: Option<PbcCell>,
}

/// The colour map of `rep`'s exposure colours, when its surface takes them (atoms, not
/// beads).
pub(crate) fn exposure_map(rep: &Representation, beads: bool) -> Option<ColourMap> {
    match rep.colour {
        ColorScheme::Exposure(map) if rep.style.is_surface() && !beads => Some(map),
        _ => None,
    }
}

/// Linear RGB colour per atom (0 to 1).
pub(crate) type AtomColours = Vec<[f32; 3]>;

/// A host engine's surface of `atoms` (`compute`), coloured by exposure through `map` in a
/// second pass: the first pass, uncoloured, gives the per-atom areas whose colours `colour`
/// returns (when its mesh was kept), and the surface is computed again with them. Returns
/// the surface and the colours of the second pass.
pub(crate) fn host_surface(
    atoms: AtomSet<'_>,
    map: Option<ColourMap>,
    mut compute: impl FnMut(&AtomSet<'_>) -> Result<SurfaceOutput, SceneError>,
    colour: impl FnOnce(&SurfaceOutput, ColourMap) -> Result<AtomColours, SceneError>,
) -> Result<(SurfaceOutput, Option<AtomColours>), SceneError> {
    let first = AtomSet {
        colours: atoms.colours.filter(|_| map.is_none()),
        ..atoms
    };
    let output = compute(&first)?;
    // Exposure colours need the mesh (kept unless only measured).
    let Some(map) = map.filter(|_| output.counts_without_mesh.is_none()) else {
        return Ok((output, None));
    };
    let colours = colour(&output, map)?;
    let coloured = AtomSet {
        colours: Some(&colours),
        ..atoms
    };
    let output = compute(&coloured)?;
    Ok((output, Some(colours)))
}
