//! The area buried between two groups of atoms, A and B: `(area(A) + area(B) - area(A and B)) /
//! 2`, all three surfaces on the union's grid so that the grid's sampling cancels, and the
//! residues that lose area from alone to the complex. The complex may be a surface the caller
//! already has ([`interface_on`]). With refined vertices the sides take the complex's vertices
//! and sharp triangles where no atom that differs reaches them
//! ([`crate::surface::analytic::RefinedReuse`]), which spares most of their root finding.

use std::sync::Arc;

use glam::Vec3;

use super::residues::residue_areas;
use super::{MeasureError, ResidueArea, atom_areas_of};
use crate::model::Topology;
use crate::surface::analytic::{RefinedReuse, ReusableSurface};
use crate::surface::{
    AtomSet, CpuEngine, GridSpec, KeptDensity, SurfaceEngine, SurfaceOutput, SurfaceParams,
    VertexMode,
};

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
    /// Area of each atom of A alone (Å², in A's order; this and the three below are empty when
    /// the per-atom areas were not asked for).
    pub atoms_a_alone: Vec<f64>,
    /// Area of each atom of B alone (Å², in B's order).
    pub atoms_b_alone: Vec<f64>,
    /// Area of each atom of A in the complex (Å²).
    pub atoms_a_complex: Vec<f64>,
    /// Area of each atom of B in the complex (Å²).
    pub atoms_b_complex: Vec<f64>,
    /// For A and for B, what its surface took from the complex's instead of computing it
    /// again.
    pub taken: [TakenFromComplex; 2],
}

/// What one side of an interface took from the complex's surface where the two are the same.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct TakenFromComplex {
    /// Refined vertices taken instead of solved ([`crate::surface::analytic::RefinedReuse`];
    /// 0 with interpolated vertices).
    pub vertices: usize,
    /// Sharp triangles taken instead of measured on the Gaussian sum.
    pub sharp_triangles: usize,
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
    interface_with(engine, a, b, None, params, true)
}

/// [`interface`], the complex with `complex_radii` (Å, `a`'s atoms then `b`'s) instead of each
/// side's own: radii that follow each atom's surroundings (the SES preset's exposure) are then
/// counted over the complex for the complex, as a surface of both sides together has them.
/// Without `per_atom` the per-atom areas are not weighed (their vectors are empty).
/// Fails as [`interface`] does, or when `complex_radii` has another length.
pub fn interface_with(
    engine: &mut dyn SurfaceEngine,
    a: &AtomSet<'_>,
    b: &AtomSet<'_>,
    complex_radii: Option<&[f32]>,
    params: &SurfaceParams,
    per_atom: bool,
) -> Result<InterfaceResult, MeasureError> {
    check_inputs(a, b, params)?;
    let (positions, radii) = complex_of(a, b, complex_radii)?;
    let union = AtomSet {
        positions: &positions,
        radii: &radii,
        colours: None,
    };
    let mut fallback = None;
    let engine = grid_engine(engine, &mut fallback);
    engine.set_grid(None);
    engine.set_keep_mesh(per_atom);
    // The complex's density, where the engine keeps it, spares sampling one side; not with
    // radii of its own (they differ from the sides' at the contact).
    engine.set_keep_density(complex_radii.is_none());
    let output = engine.compute(&union, params);
    engine.set_keep_mesh(true);
    engine.set_keep_density(false);
    let output = output?;
    let a_at: Vec<u32> = (0..a.len() as u32).collect();
    let b_at: Vec<u32> = (a.len() as u32..union.len() as u32).collect();
    let complex = Complex {
        output: &output,
        atoms: union,
        a_at: &a_at,
        b_at: &b_at,
    };
    interface_on(engine, a, b, &complex, params, per_atom)
}

/// A surface of both sides together computed elsewhere, such as the frame's own surface of the
/// same atoms, so that [`interface_on`] need not compute it again.
#[derive(Debug, Clone, Copy)]
pub struct Complex<'a> {
    /// The surface, its mesh kept, on the grid the engine gave these atoms.
    pub output: &'a SurfaceOutput,
    /// The atoms it was computed from, in its own order (the radii the complex has).
    pub atoms: AtomSet<'a>,
    /// For each atom of A (in A's order), its index in `atoms`.
    pub a_at: &'a [u32],
    /// For each atom of B (in B's order), its index in `atoms`.
    pub b_at: &'a [u32],
}

/// [`interface`] with the complex's surface already computed (`complex`, under the same
/// `params` and vertex mode as `engine`'s): A and B are computed on its grid. When the complex
/// kept its density ([`SurfaceOutput::density`]) and the sides have its radii, the side with
/// more atoms is the complex's density less the other's (to rounding the same; bitwise where
/// no atom of the other side reaches). Bitwise what
/// [`interface_with`] computes when `complex` came
/// from the same engine with the atoms in the same order; another order sums each sample's
/// Gaussians in another order (the same to rounding). Without `per_atom` the per-atom areas
/// are not weighed (their vectors are empty; the contact residues need them).
///
/// Fails as [`interface`] does, when the index maps do not fit, or when the per-atom areas
/// are asked for and `complex` has no mesh.
pub fn interface_on(
    engine: &mut dyn SurfaceEngine,
    a: &AtomSet<'_>,
    b: &AtomSet<'_>,
    complex: &Complex<'_>,
    params: &SurfaceParams,
    per_atom: bool,
) -> Result<InterfaceResult, MeasureError> {
    check_inputs(a, b, params)?;
    complex.check(a.len(), b.len(), per_atom)?;
    let [a, b] = [a, b].map(|s| AtomSet {
        colours: None,
        ..*s
    });
    let mut fallback = None;
    let engine = grid_engine(engine, &mut fallback);
    // Per-atom areas are weighed on the meshes (their positions); the areas alone need none.
    engine.set_keep_mesh(per_atom);
    engine.set_mesh_positions_only(true);
    let measure = engine.vertices().effective(params);
    engine.set_grid(Some(complex.output.grid));
    let whole = complex
        .output
        .density
        .as_deref()
        .filter(|_| complex.holds_sides(&a, &b));
    let reuse = complex.refined_reuse(engine, [&a, &b], &measure);
    let counters = reuse.clone();
    let sides = sides_on_grid(engine, [&a, &b], whole, params, reuse);
    engine.set_refined_reuse(None);
    engine.set_grid(None);
    engine.set_keep_mesh(true);
    engine.set_mesh_positions_only(false);
    engine.set_keep_density(false);
    let [out_a, out_b] = sides?;
    // Per atom: A and B alone, then each side's atoms in the complex.
    let mut per_atom_areas: [Vec<f64>; 4] = Default::default();
    if per_atom {
        let in_complex = atom_areas_of(complex.output, &complex.atoms, &measure)?;
        let pick = |at: &[u32]| at.iter().map(|&i| in_complex[i as usize]).collect();
        per_atom_areas = [
            atom_areas_of(&out_a, &a, &measure)?,
            atom_areas_of(&out_b, &b, &measure)?,
            pick(complex.a_at),
            pick(complex.b_at),
        ];
    }
    let taken = counters.map(|r| {
        let (vertices, sharp_triangles) = r.map_or((0, 0), |r| r.taken());
        TakenFromComplex {
            vertices,
            sharp_triangles,
        }
    });
    Ok(InterfaceResult::of(
        [&out_a, &out_b, complex.output],
        per_atom_areas,
        taken,
    ))
}

impl InterfaceResult {
    /// The interface of the surfaces `[a, b, complex]` (their areas, the complex's grid), with
    /// the per-atom areas `[a alone, b alone, a in the complex, b in the complex]` (empty when
    /// not weighed) and what each side took from the complex.
    pub(super) fn of(
        [a, b, complex]: [&SurfaceOutput; 3],
        per_atom: [Vec<f64>; 4],
        taken: [TakenFromComplex; 2],
    ) -> InterfaceResult {
        let [
            atoms_a_alone,
            atoms_b_alone,
            atoms_a_complex,
            atoms_b_complex,
        ] = per_atom;
        InterfaceResult {
            grid: complex.grid,
            area_a: a.area,
            area_b: b.area,
            area_complex: complex.area,
            buried: 0.5 * (a.area + b.area - complex.area),
            atoms_a_alone,
            atoms_b_alone,
            atoms_a_complex,
            atoms_b_complex,
            taken,
        }
    }
}

impl Complex<'_> {
    /// For each side, the atoms whose terms differ between it and the complex: the other
    /// side's, and this side's whose radius or position is not its complex atom's, each with
    /// the longer of its cutoffs under `measure` (the effective parameters; Å).
    fn changed_atoms(
        &self,
        sides: [&AtomSet<'_>; 2],
        measure: &SurfaceParams,
    ) -> [Vec<(Vec3, f32)>; 2] {
        let cut = |radius: f32| measure.cutoff() * measure.radius_scale * radius;
        let maps = [self.a_at, self.b_at];
        [0, 1].map(|s| {
            let (side, at, other) = (sides[s], maps[s], maps[1 - s]);
            let mut changed: Vec<(Vec3, f32)> = other
                .iter()
                .map(|&j| {
                    let j = j as usize;
                    (self.atoms.positions[j], cut(self.atoms.radii[j]))
                })
                .collect();
            for (i, &j) in at.iter().enumerate() {
                let j = j as usize;
                let (p, r) = (side.positions[i], side.radii[i]);
                let (pc, rc) = (self.atoms.positions[j], self.atoms.radii[j]);
                if p != pc {
                    changed.push((p, cut(r)));
                    changed.push((pc, cut(rc)));
                } else if r.to_bits() != rc.to_bits() {
                    changed.push((p, cut(r.max(rc))));
                }
            }
            changed
        })
    }

    /// For each side, the complex's refined vertices and sharp triangles it may take
    /// ([`crate::surface::analytic::RefinedReuse`]) given its changed atoms
    /// ([`Complex::changed_atoms`]). `None` for both when the engine does not refine or cannot
    /// take them, or the complex has no normals.
    fn refined_reuse(
        &self,
        engine: &mut dyn SurfaceEngine,
        sides: [&AtomSet<'_>; 2],
        measure: &SurfaceParams,
    ) -> [Option<Arc<RefinedReuse>>; 2] {
        if engine.vertices() != VertexMode::Refined || !engine.set_refined_reuse(None) {
            return [None, None];
        }
        let Some(vertices) = ReusableSurface::new(
            &self.output.mesh,
            self.output.sharp.as_deref(),
            &self.output.grid,
            measure.isovalue,
        ) else {
            return [None, None];
        };
        let vertices = Arc::new(vertices);
        let changed = self.changed_atoms(sides, measure);
        [0, 1].map(|s| {
            Some(Arc::new(RefinedReuse::new(
                Arc::clone(&vertices),
                &changed[s],
            )))
        })
    }

    /// True when every atom of `a` and `b` is its atom of the complex, at the same position
    /// with the same radius (bit for bit), so that the complex's density is the sum of the
    /// sides'. Radii that follow exposure differ between a side and the complex at the
    /// contact.
    fn holds_sides(&self, a: &AtomSet<'_>, b: &AtomSet<'_>) -> bool {
        let n = self.atoms.len();
        [(a, self.a_at), (b, self.b_at)].iter().all(|(side, at)| {
            side.len() == at.len()
                && at.iter().enumerate().all(|(i, &j)| {
                    let j = j as usize;
                    j < n
                        && self.atoms.positions[j] == side.positions[i]
                        && self.atoms.radii[j].to_bits() == side.radii[i].to_bits()
                })
        })
    }

    /// Fails unless the maps give each of A's `a_len` and B's `b_len` atoms its own atom of
    /// the complex, and every atom of the complex is one of them, or when the mesh is needed
    /// (`per_atom`) and was not kept.
    fn check(&self, a_len: usize, b_len: usize, per_atom: bool) -> Result<(), MeasureError> {
        let n = self.atoms.len();
        for (what, at, len) in [
            ("complex atoms of A", self.a_at, a_len),
            ("complex atoms of B", self.b_at, b_len),
        ] {
            if at.len() != len {
                return Err(MeasureError::LengthMismatch {
                    what,
                    expected: len,
                    got: at.len(),
                });
            }
        }
        if a_len + b_len != n {
            return Err(MeasureError::LengthMismatch {
                what: "complex atoms",
                expected: a_len + b_len,
                got: n,
            });
        }
        let mut seen = vec![false; n];
        for &i in self.a_at.iter().chain(self.b_at) {
            let Some(slot) = seen.get_mut(i as usize).filter(|s| !**s) else {
                return Err(MeasureError::IndexOutOfRange {
                    what: "complex atom",
                    index: i as usize,
                    len: n,
                });
            };
            *slot = true;
        }
        if per_atom && self.output.counts_without_mesh.is_some() {
            return Err(MeasureError::NoMesh);
        }
        Ok(())
    }
}

/// The surfaces of `sides` (A, B) on the engine's grid, each taking the complex's refined
/// vertices where its `reuse` allows. With `whole`, the complex's density
/// on that grid with each side's atoms and radii, the side with fewer atoms is sampled (its
/// density kept) and the other is the complex less it
/// ([`SurfaceEngine::compute_difference`]), which saves sampling its Gaussians; the engine
/// computes it from its atoms when it cannot.
fn sides_on_grid(
    engine: &mut dyn SurfaceEngine,
    sides: [&AtomSet<'_>; 2],
    whole: Option<&KeptDensity>,
    params: &SurfaceParams,
    mut reuse: [Option<Arc<RefinedReuse>>; 2],
) -> Result<[SurfaceOutput; 2], MeasureError> {
    let sampled = usize::from(sides[1].len() < sides[0].len());
    engine.set_keep_density(whole.is_some());
    engine.set_refined_reuse(reuse[sampled].take());
    let first = engine.compute(sides[sampled], params);
    engine.set_keep_density(false);
    let first = first?;
    let other = sides[1 - sampled];
    engine.set_refined_reuse(reuse[1 - sampled].take());
    let difference = match (whole, first.density.as_deref()) {
        (Some(whole), Some(minus)) => engine.compute_difference(other, params, whole, minus),
        _ => None,
    };
    let second = match difference {
        Some(second) => second?,
        None => engine.compute(other, params)?,
    };
    Ok(match sampled {
        0 => [first, second],
        _ => [second, first],
    })
}

/// `engine` when it can compute on a given grid ([`SurfaceEngine::set_grid`]), otherwise a
/// CPU engine with its vertex mode, kept in `fallback`.
fn grid_engine<'e>(
    engine: &'e mut dyn SurfaceEngine,
    fallback: &'e mut Option<CpuEngine>,
) -> &'e mut dyn SurfaceEngine {
    if engine.set_grid(None) {
        engine
    } else {
        fallback.insert(CpuEngine::new().with_vertices(engine.vertices()))
    }
}

/// Fails on invalid atoms of either side or invalid parameters.
fn check_inputs(
    a: &AtomSet<'_>,
    b: &AtomSet<'_>,
    params: &SurfaceParams,
) -> Result<(), MeasureError> {
    a.validate()?;
    b.validate()?;
    Ok(params.validate()?)
}

/// The positions (Å) and radii (Å) of `a`'s atoms followed by `b`'s: the complex.
pub(super) fn union_of(a: &AtomSet<'_>, b: &AtomSet<'_>) -> (Vec<Vec3>, Vec<f32>) {
    let positions = a.positions.iter().chain(b.positions).copied().collect();
    let radii = a.radii.iter().chain(b.radii).copied().collect();
    (positions, radii)
}

/// [`union_of`], with the radii `complex_radii` (Å, `a`'s atoms then `b`'s) when given. Fails
/// when they are of another length.
pub(super) fn complex_of(
    a: &AtomSet<'_>,
    b: &AtomSet<'_>,
    complex_radii: Option<&[f32]>,
) -> Result<(Vec<Vec3>, Vec<f32>), MeasureError> {
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
    Ok((positions, radii))
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
