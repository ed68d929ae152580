//! The area buried between two groups of atoms, A and B: `(area(A) + area(B) - area(A and B)) /
//! 2`, all three surfaces on the union's grid so that the grid's sampling cancels, and the
//! residues that lose area from alone to the complex.

use glam::Vec3;

use super::residues::residue_areas;
use super::{MeasureError, ResidueArea, atom_areas_of};
use crate::model::Topology;
use crate::surface::{AtomSet, CpuEngine, GridSpec, SurfaceEngine, SurfaceOutput, SurfaceParams};

/// Areas of A, B and the complex, on one grid.
#[derive(Debug, Clone, PartialEq)]
pub struct InterfaceResult {
    /// The grid all three surfaces were computed on (the complex's own).
    pub grid: GridSpec,
    /// Area of A alone in Å².
    pub area_a: f64,
    /// Area of B alone in Å².
    pub area_b: f64,
    /// Area of A and B together in Å².
    pub area_complex: f64,
    /// Buried area in Å²: `(area_a + area_b - area_complex) / 2` (the area each side loses,
    /// averaged; some papers report twice this).
    pub buried: f64,
    /// Area of each atom of A alone (Å², in A's order).
    pub atoms_a_alone: Vec<f64>,
    /// Area of each atom of B alone (Å², in B's order).
    pub atoms_b_alone: Vec<f64>,
    /// Area of each atom of A in the complex (Å²).
    pub atoms_a_complex: Vec<f64>,
    /// Area of each atom of B in the complex (Å²).
    pub atoms_b_complex: Vec<f64>,
}

/// The buried area between `a` and `b` under `params`, with per-atom areas alone and in the
/// complex ([`super::atom_areas_of`], so they sum to each surface's reported area). The complex
/// is computed first; A and B then reuse its grid through
/// [`SurfaceEngine::set_grid`]; an engine that cannot force a grid is replaced for this call
/// by a CPU engine with the same vertex mode. Colours are ignored. The engine is left keeping
/// meshes and back on its default grid.
///
/// Fails on invalid atoms or parameters, or when a surface fails.
pub fn interface(
    engine: &mut dyn SurfaceEngine,
    a: &AtomSet<'_>,
    b: &AtomSet<'_>,
    params: &SurfaceParams,
) -> Result<InterfaceResult, MeasureError> {
    interface_with(engine, a, b, None, params)
}

/// [`interface`], the complex with `complex_radii` (Å, `a`'s atoms then `b`'s) instead of each
/// side's own: radii that follow each atom's surroundings (the SES preset's exposure) are then
/// counted over the complex for the complex, as a surface of both sides together has them.
/// Fails as [`interface`] does, or when `complex_radii` has another length.
pub fn interface_with(
    engine: &mut dyn SurfaceEngine,
    a: &AtomSet<'_>,
    b: &AtomSet<'_>,
    complex_radii: Option<&[f32]>,
    params: &SurfaceParams,
) -> Result<InterfaceResult, MeasureError> {
    a.validate()?;
    b.validate()?;
    params.validate()?;
    let (positions, mut radii) = union_of(a, b);
    if let Some(own) = complex_radii {
        if own.len() != radii.len() {
            return Err(MeasureError::LengthMismatch {
                what: "complex radii",
                expected: radii.len(),
                got: own.len(),
            });
        }
        radii.copy_from_slice(own);
    }
    let union = AtomSet {
        positions: &positions,
        radii: &radii,
        colours: None,
    };
    let [a, b] = [a, b].map(|s| AtomSet {
        colours: None,
        ..*s
    });
    let mut fallback = None;
    let engine: &mut dyn SurfaceEngine = if engine.set_grid(None) {
        engine
    } else {
        fallback.insert(CpuEngine::new().with_vertices(engine.vertices()))
    };
    engine.set_keep_mesh(true);
    let measure = engine.vertices().effective(params);
    let complex = engine.compute(&union, params)?;
    engine.set_grid(Some(complex.grid));
    let alone = |engine: &mut dyn SurfaceEngine, set: &AtomSet<'_>| -> Result<_, MeasureError> {
        let out: SurfaceOutput = engine.compute(set, params)?;
        let areas = atom_areas_of(&out, set, &measure)?;
        Ok((out.area, areas))
    };
    let both = (|| Ok::<_, MeasureError>((alone(engine, &a)?, alone(engine, &b)?)))();
    engine.set_grid(None);
    let ((area_a, atoms_a_alone), (area_b, atoms_b_alone)) = both?;
    let mut atoms_a_complex = atom_areas_of(&complex, &union, &measure)?;
    let atoms_b_complex = atoms_a_complex.split_off(a.len());
    Ok(InterfaceResult {
        grid: complex.grid,
        area_a,
        area_b,
        area_complex: complex.area,
        buried: 0.5 * (area_a + area_b - complex.area),
        atoms_a_alone,
        atoms_b_alone,
        atoms_a_complex,
        atoms_b_complex,
    })
}

/// The positions (Å) and radii (Å) of `a`'s atoms followed by `b`'s: the complex.
pub(super) fn union_of(a: &AtomSet<'_>, b: &AtomSet<'_>) -> (Vec<Vec3>, Vec<f32>) {
    let positions = a.positions.iter().chain(b.positions).copied().collect();
    let radii = a.radii.iter().chain(b.radii).copied().collect();
    (positions, radii)
}

/// Which group of an interface a residue belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// The first group.
    A,
    /// The second group.
    B,
}

/// A residue that loses area when the two groups meet.
#[derive(Debug, Clone, PartialEq)]
pub struct ContactResidue {
    /// Its group.
    pub side: Side,
    /// The residue with its area alone (Å²).
    pub residue: ResidueArea,
    /// Its area in the complex (Å²).
    pub area_complex: f64,
    /// Area lost: alone minus in the complex (Å²).
    pub buried: f64,
}

/// Default threshold of [`contact_residues`]: 1 Å² lost.
pub const CONTACT_THRESHOLD: f64 = 1.0;

/// The residues of A, then of B, whose area alone minus their area in the complex exceeds
/// `threshold` (Å², [`CONTACT_THRESHOLD`] by default), in topology order. `a_indices` and
/// `b_indices` are the topology atoms of the two sets (`None`: all atoms).
///
/// Fails on a negative or non-finite threshold, mismatched lengths or indices past the topology.
pub fn contact_residues(
    topology: &Topology,
    a_indices: Option<&[u32]>,
    b_indices: Option<&[u32]>,
    result: &InterfaceResult,
    threshold: f64,
) -> Result<Vec<ContactResidue>, MeasureError> {
    if !(threshold.is_finite() && threshold >= 0.0) {
        return Err(MeasureError::InvalidOption {
            name: "contact threshold",
            value: threshold,
        });
    }
    let mut out = Vec::new();
    for (side, indices, alone, complex) in [
        (
            Side::A,
            a_indices,
            &result.atoms_a_alone,
            &result.atoms_a_complex,
        ),
        (
            Side::B,
            b_indices,
            &result.atoms_b_alone,
            &result.atoms_b_complex,
        ),
    ] {
        let alone = residue_areas(topology, indices, alone)?;
        let complex = residue_areas(topology, indices, complex)?;
        for (residue, with) in alone.into_iter().zip(complex) {
            let buried = residue.area - with.area;
            if buried > threshold {
                out.push(ContactResidue {
                    side,
                    residue,
                    area_complex: with.area,
                    buried,
                });
            }
        }
    }
    Ok(out)
}
