//! The exact Gaussian sum near the surface, for refined vertices and curvature-aware measurement
//! (issue 13). Sits beside the sampled density: [`super::bin`] prepares the atoms, this module
//! puts them in a uniform cell grid (cells half the largest reach wide, so a point's atoms are in
//! its 5³ neighbouring cells) and evaluates `rho(x)` and `grad rho(x)` in f32.
//!
//! Cost: refining one edge gathers the atoms that reach it once (the cells within the largest
//! reach of the edge, row by row, cut to that sphere, then a per-atom distance test without
//! branches) into blocks of eight lanes, and every Newton step sums those blocks without
//! branches with a polynomial exponential ([`exp_fast`]), which the compiler vectorises. The
//! gather dominates (about two thirds of the refinement). `mdsurf bench --vertices refined`
//! reports the cost per frame; the GPU twin is `shaders/refine.wgsl`.
//!
//! Cutoff (issue 33): the vertices lie on the level set of the very function the grid samples,
//! and for refined vertices that function is the sum at quality max. An engine computing refined
//! vertices samples its grid at [`REFINED_QUALITY`] (cutoff [`REFINE_REACH`] = 4 alpha, where a
//! term is below 3.4e-4) whatever quality it is asked for ([`VertexMode::effective`]), and the
//! field counts each atom out to its own cutoff with the density's f32 test (`d² < cut2`, `d²`
//! summed x, y, z in that order), so at a grid point an atom counts here exactly when it counts
//! in the sample. Why not refine at a shorter cutoff: each term jumps at its cutoff sphere by
//! `exp(-q²/2)` (0.044 at medium, 0.011 at high), so the level set of such a sum has steps about
//! `jump / |grad rho|` high (about 0.1 Å at medium, 0.03 Å at high) along every cutoff sphere
//! that crosses it; their area comes in only as H approaches that height, so neither vertex mode
//! converges at usable H (1hpv, I = 0.5, H = 1 to 0.125 Å: interpolated 7648 to 8032 Å² at
//! medium and 7463 to 7549 Å² at high; refined on those sums 7791 to 8154 and 7524 to 7571 Å²),
//! where at quality max both converge on 7472 Å². Refining on 4 alpha over a grid sampled at a
//! shorter cutoff (the scheme before issue 33) put the vertices on another surface than the one
//! the grid's topology follows: at H = 0.25 Å, refined areas of 7500 Å² at high (0.4 % above the
//! 7472 Å² that sum converges on) and 8514 Å² at medium.
//!
//! Data flow: [`PreparedAtom`]s -> [`AnalyticField`] -> [`AnalyticField::refine_edge`] (one
//! Marching Cubes vertex: position where `rho = I` on its grid edge, normal `-grad rho`
//! normalised) and [`AnalyticField::project`] (a point moved onto the surface along the
//! gradient, for [`super::curved`]).

use std::sync::Arc;

use glam::Vec3;

use super::bin::PreparedAtom;
use super::{GridSpec, Quality, SurfaceParams};

mod near;
mod reuse;

pub use near::exp_fast;
use near::*;
pub use reuse::{RefinedReuse, ReusableSurface};

/// How Marching Cubes places its vertices and normals.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum VertexMode {
    /// Linear interpolation of the samples along the edge, normals from central differences
    /// (DESIGN section 2; the area and volume are those of the flat triangles). The default.
    #[default]
    Interpolated,
    /// The root of the exact Gaussian sum on the edge, normals from its analytic gradient; the
    /// area and volume account for curvature ([`super::curved`]). Computed at quality max
    /// whatever the quality asked for ([`VertexMode::effective`]). Costs about 2 to 7 times
    /// an interpolated CPU frame (`mdsurf bench` reports it; the bar for the default
    /// is 15 %), so it is not the default.
    Refined,
}

impl VertexMode {
    /// Both modes, the default first.
    pub const ALL: [VertexMode; 2] = [VertexMode::Interpolated, VertexMode::Refined];

    /// Lower-case name as used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            VertexMode::Interpolated => "interpolated",
            VertexMode::Refined => "refined",
        }
    }

    /// The parameters an engine computes a surface with in this mode from the ones it is asked
    /// for: refined vertices run at [`REFINED_QUALITY`] whatever `params.quality` says (the
    /// module docs say why), interpolated ones as asked. Both engines apply it before planning
    /// the grid, so the grid and the refinement sample one function.
    pub fn effective(self, params: &SurfaceParams) -> SurfaceParams {
        match self {
            VertexMode::Interpolated => *params,
            VertexMode::Refined => SurfaceParams {
                quality: REFINED_QUALITY,
                ..*params
            },
        }
    }
}

super::params::display_and_parse_by_name!(VertexMode, "vertex mode", "interpolated or refined");

/// The quality every refined surface is computed at (grid and refinement), whatever quality it
/// is asked for: the sum out to 4 alpha, whose level set has no steps worth measuring.
pub const REFINED_QUALITY: Quality = Quality::Max;
/// The cutoff of [`REFINED_QUALITY`] in units of alpha: how far each atom counts in the sum of
/// a refined surface (the GPU's twin is `REFINE_REACH` in `shaders/field.wgsl`).
pub const REFINE_REACH: f32 = 4.0;
/// Most safeguarded Newton steps per edge (each one evaluation of rho and its gradient).
pub const REFINE_ITERATIONS: u32 = 16;
/// An edge's root is accepted when the next Newton step would move it less than this (Å).
pub const REFINE_STEP: f32 = 1e-4;
/// Most Newton steps of [`AnalyticField::project`] (a vertex whose edge has no root).
pub const PROJECT_ITERATIONS: u32 = 4;
/// Most Newton steps of [`AnalyticField::project_points`] (points of a sharp triangle measured
/// on the surface, [`super::curved`]): they start up to a few tenths of an Å off it.
pub const PROJECT_POINTS_ITERATIONS: u32 = 8;
/// A point of [`AnalyticField::project_points`] is on the surface when the next Newton step
/// would move it less than this (Å): its error in a sharp triangle's area is second order in it.
pub const PROJECT_POINTS_STEP: f32 = 1e-3;

/// The Gaussian sum of a set of atoms, binned for evaluation at arbitrary points.
#[derive(Debug, Clone, Default)]
pub struct AnalyticField {
    atoms: Vec<FieldAtom>,
    /// `cell_start[c]..cell_start[c + 1]` are the atoms of cell `c` (x fastest).
    cell_start: Vec<u32>,
    origin: Vec3,
    /// Cell edge in Å (the largest cutoff).
    cell: f32,
    dims: [i32; 3],
    /// Another surface's vertices this one may take instead of solving ([`RefinedReuse`]).
    reuse: Option<Arc<RefinedReuse>>,
}

impl AnalyticField {
    /// Bins `atoms` (in canonical order; kept within each cell) into cells half the largest
    /// cutoff wide over the bounding box of `grid`; each atom counts out to its own cutoff
    /// ([`PreparedAtom::cut`], `q alpha`, tested as the density tests it: in a refined frame
    /// `q` is [`REFINE_REACH`]).
    pub fn new(atoms: &[PreparedAtom], grid: &GridSpec) -> AnalyticField {
        let cell = 0.5 * atoms.iter().map(|a| a.cut).fold(0.0f32, f32::max).max(1e-3);
        let extent = grid.spacing
            * Vec3::new(
                grid.dims[0] as f32,
                grid.dims[1] as f32,
                grid.dims[2] as f32,
            );
        let dims = [0, 1, 2].map(|a| ((extent[a] / cell).ceil() as i32).clamp(1, 1024));
        let mut field = AnalyticField {
            atoms: Vec::with_capacity(atoms.len()),
            cell_start: vec![0; (dims[0] * dims[1] * dims[2]) as usize + 1],
            origin: grid.origin,
            cell,
            dims,
            reuse: None,
        };
        let cells: Vec<usize> = atoms
            .iter()
            .map(|a| field.cell_index(field.cell_of(Vec3::from(a.pos))))
            .collect();
        for &c in &cells {
            field.cell_start[c + 1] += 1;
        }
        for c in 1..field.cell_start.len() {
            field.cell_start[c] += field.cell_start[c - 1];
        }
        let mut fill = field.cell_start.clone();
        let placeholder = FieldAtom {
            pos: Vec3::ZERO,
            k: 0.0,
            cut2: 0.0,
            reach: 0.0,
        };
        field.atoms.resize(atoms.len(), placeholder);
        for (a, &c) in atoms.iter().zip(&cells) {
            field.atoms[fill[c] as usize] = FieldAtom {
                pos: Vec3::from(a.pos),
                k: a.k,
                cut2: a.cut2,
                reach: a.cut,
            };
            fill[c] += 1;
        }
        field
    }

    /// This field, taking vertices and sharp triangles from `reuse` where its rule allows
    /// ([`RefinedReuse::vertex`], [`RefinedReuse::sharp`]).
    pub fn with_reuse(mut self, reuse: Option<Arc<RefinedReuse>>) -> AnalyticField {
        self.reuse = reuse;
        self
    }

    /// The other surface this field takes vertices and sharp triangles from, when it was
    /// given one ([`AnalyticField::with_reuse`]).
    #[inline]
    pub fn reuse(&self) -> Option<&RefinedReuse> {
        self.reuse.as_deref()
    }

    fn cell_of(&self, p: Vec3) -> [i32; 3] {
        let c = (p - self.origin) / self.cell;
        [0, 1, 2].map(|a| (c[a].floor() as i32).clamp(0, self.dims[a] - 1))
    }

    fn cell_index(&self, c: [i32; 3]) -> usize {
        (c[0] + self.dims[0] * (c[1] + self.dims[1] * c[2])) as usize
    }

    /// `rho(p)` and `grad rho(p)` (Å⁻¹) at `p` (Å): the sum over the atoms with
    /// `|p - p_i|² < cut2_i` (the density's cutoff) of `exp(-k_i |p - p_i|²)` and its gradient.
    pub fn eval(&self, p: Vec3) -> (f32, Vec3) {
        let mut rho = 0.0f32;
        let mut grad = Vec3::ZERO;
        self.for_cell_runs(p, 0.0, |run| accumulate(run, p, &mut rho, &mut grad));
        (rho, grad)
    }

    /// Calls `f` with the atoms of each x-run of cells that can hold an atom reaching a point
    /// within `radius` Å of `centre`: the cells within the largest reach (two cells) plus
    /// `radius` of `centre`, row by row (rows farther away skipped, each row's x-run cut to
    /// that sphere), in cell order (z, then y, then x). Boundary cells count as reaching to
    /// infinity (they hold any atom beyond the grid).
    #[inline]
    fn for_cell_runs(&self, centre: Vec3, radius: f32, mut f: impl FnMut(&[FieldAtom])) {
        let rr = 2.0 * self.cell + radius;
        let rel = centre - self.origin;
        let lo_c = (rel - rr) / self.cell;
        let hi_c = (rel + rr) / self.cell;
        // Truncation equals floor once clamped at 0 (and avoids a libm call without SSE4.1).
        let lo = [0, 1, 2].map(|a| (lo_c[a] as i32).clamp(0, self.dims[a] - 1));
        let hi = [0, 1, 2].map(|a| (hi_c[a] as i32).clamp(0, self.dims[a] - 1));
        // Distance along axis `a` from `centre` to cell `c`'s slab (0 inside it).
        let gap = |a: usize, c: i32| -> f32 {
            let below = if c > 0 {
                c as f32 * self.cell
            } else {
                f32::NEG_INFINITY
            };
            let above = if c < self.dims[a] - 1 {
                (c + 1) as f32 * self.cell
            } else {
                f32::INFINITY
            };
            (below - rel[a]).max(rel[a] - above).max(0.0)
        };
        let rr2 = rr * rr;
        for z in lo[2]..=hi[2] {
            let gz = gap(2, z);
            for y in lo[1]..=hi[1] {
                let gy = gap(1, y);
                let left = rr2 - (gy * gy + gz * gz);
                if left < 0.0 {
                    continue;
                }
                let hx = left.sqrt();
                let x0 = (((rel.x - hx) / self.cell) as i32).clamp(lo[0], hi[0]);
                let x1 = (((rel.x + hx) / self.cell) as i32).clamp(lo[0], hi[0]);
                let first = self.cell_index([x0, y, z]);
                let last = self.cell_index([x1, y, z]);
                let (s, e) = (self.cell_start[first], self.cell_start[last + 1]);
                f(&self.atoms[s as usize..e as usize]);
            }
        }
    }

    /// Fills `out` with the atoms that reach some point within `radius` Å of `centre`
    /// (`|centre - p_i| < cut_i + radius`), in the order [`Self::eval`] sums them, so a sum
    /// over `out` at such a point has the same terms in the same order as `eval` there.
    fn gather(&self, centre: Vec3, radius: f32, out: &mut NearAtoms) {
        out.clear();
        self.for_cell_runs(centre, radius, |run| {
            out.reserve(run.len());
            for a in run {
                let r = a.reach + radius;
                out.push_if(a, (centre - a.pos).length_squared() < r * r);
            }
        });
        out.finish();
    }

    /// The vertex on the grid edge from `pa` (density sample `va`) to `pb`, Å, where the samples
    /// lie on either side of `iso`: the root of `rho = iso` on the segment by Newton steps from
    /// the linear estimate `t0` (edge parameter), safeguarded by halving the bracket
    /// ([`refine_in`] says when). The samples are of the same sum up to the rounding of the
    /// exponential, so the edge has a root or a term's 3.4e-4 step at its cutoff sphere across
    /// `iso` (where the search ends at the step), but where a sample lies within that rounding
    /// of `iso`. When the search does not converge in [`REFINE_ITERATIONS`] evaluations, the
    /// point is moved onto the surface along the gradient instead. Returns the position (Å) and
    /// the unit normal `-grad rho / |grad rho|` from the last evaluation, `None` when the
    /// gradient vanishes there.
    pub fn refine_edge(
        &self,
        pa: Vec3,
        pb: Vec3,
        va: f32,
        iso: f32,
        t0: f32,
    ) -> (Vec3, Option<Vec3>) {
        NEAR.with_borrow_mut(|near| {
            // Newton stays on the edge, within half its length of the midpoint; the rare
            // fallback projection moves up to half an edge further and gathers again.
            let (mid, len) = (0.5 * (pa + pb), (pb - pa).length());
            self.gather(mid, 0.5 * len, near);
            let (position, grad, found) = refine_in(|x| near.eval(x), pa, pb, va, iso, t0);
            let (position, grad) = if found {
                (position, grad)
            } else {
                // Not converged on this edge (see above): move onto the surface along the
                // gradient instead, at most half an edge length.
                self.gather(mid, len, near);
                project_in(
                    |x| near.eval(x),
                    position,
                    iso,
                    0.5 * len,
                    PROJECT_ITERATIONS,
                    REFINE_STEP,
                )
                .unwrap_or((position, grad))
            };
            let n = -grad;
            let normal = (n.length_squared() > 0.0 && n.is_finite()).then(|| n.normalize());
            (position, normal)
        })
    }

    /// `p` (Å) moved onto `rho = iso` by Newton steps along the gradient (at most four), with
    /// the gradient there; `None` when that does not converge within `max_dist` Å of `p`.
    pub fn project(&self, p: Vec3, iso: f32, max_dist: f32) -> Option<(Vec3, Vec3)> {
        NEAR.with_borrow_mut(|near| {
            self.gather(p, max_dist, near);
            project_in(
                |x| near.eval(x),
                p,
                iso,
                max_dist,
                PROJECT_ITERATIONS,
                REFINE_STEP,
            )
        })
    }

    /// Moves every point of `points` (Å, all within `radius` Å of `centre`) onto `rho = iso`
    /// along the gradient, as [`Self::project`] with up to [`PROJECT_POINTS_ITERATIONS`] Newton
    /// steps each, done at [`PROJECT_POINTS_STEP`], and the atoms gathered once for all of them. False (and `points` partly
    /// moved) when one of them does not converge within `max_dist` Å of where it started.
    pub fn project_points(
        &self,
        points: &mut [Vec3],
        centre: Vec3,
        radius: f32,
        iso: f32,
        max_dist: f32,
    ) -> bool {
        NEAR.with_borrow_mut(|near| {
            self.gather(centre, radius + max_dist, near);
            points.iter_mut().all(|p| {
                let moved = project_in(
                    |x| near.eval(x),
                    *p,
                    iso,
                    max_dist,
                    PROJECT_POINTS_ITERATIONS,
                    PROJECT_POINTS_STEP,
                );
                moved.map(|(x, _)| *p = x).is_some()
            })
        })
    }
}

/// The safeguarded Newton part of [`AnalyticField::refine_edge`] with `eval` summing the atoms
/// near the edge: position (Å), `grad rho` there (Å⁻¹) and whether it converged.
///
/// Each evaluation narrows the bracket `[lo, hi]` (edge parameters whose values lie on either
/// side of `iso`). A Newton step is taken when it stays in the bracket and is at most half the
/// step before it; otherwise the bracket is halved. The halving is what ends the search where
/// the sum jumps across `iso` (a term's step at its cutoff sphere) instead of crossing it
/// smoothly: there Newton steps from either side overshoot to the other side and back without
/// getting closer. Converged: a Newton step shorter than [`REFINE_STEP`] (taken), a bracket
/// narrower than that (its middle taken), or an exact root. Halving alone narrows an edge of
/// 1 Å to that in 14 evaluations, within [`REFINE_ITERATIONS`].
fn refine_in(
    eval: impl Fn(Vec3) -> (f32, Vec3),
    pa: Vec3,
    pb: Vec3,
    va: f32,
    iso: f32,
    t0: f32,
) -> (Vec3, Vec3, bool) {
    let dir = pb - pa;
    let len = dir.length();
    let (mut lo, mut hi) = (0.0f32, 1.0f32);
    let lo_inside = va >= iso;
    let mut t = t0.clamp(0.0, 1.0);
    let mut g = Vec3::ZERO;
    let mut last_step = 1.0f32;
    for _ in 0..REFINE_ITERATIONS {
        let (rho, grad) = eval(pa + t * dir);
        g = grad;
        let f = rho - iso;
        if f == 0.0 {
            return (pa + t * dir, g, true);
        }
        if (f >= 0.0) == lo_inside {
            lo = t;
        } else {
            hi = t;
        }
        let df = grad.dot(dir);
        let newton = t - f / df;
        let step = (newton - t).abs();
        if df != 0.0 && newton >= lo && newton <= hi && step <= 0.5 * last_step {
            t = newton;
            last_step = step;
            if step * len < REFINE_STEP {
                return (pa + t * dir, g, true);
            }
        } else {
            t = 0.5 * (lo + hi);
            last_step = 0.5 * (hi - lo);
            if (hi - lo) * len < REFINE_STEP {
                return (pa + t * dir, g, true);
            }
        }
    }
    (pa + t * dir, g, false)
}

/// [`AnalyticField::project`] with `eval` summing the atoms near `p`, at most `iterations`
/// Newton steps, done when a step is shorter than `tolerance` Å.
fn project_in(
    eval: impl Fn(Vec3) -> (f32, Vec3),
    p: Vec3,
    iso: f32,
    max_dist: f32,
    iterations: u32,
    tolerance: f32,
) -> Option<(Vec3, Vec3)> {
    let mut x = p;
    for _ in 0..iterations {
        let (rho, g) = eval(x);
        let f = rho - iso;
        let g2 = g.length_squared();
        let usable = g2 > 0.0;
        if !usable {
            return None;
        }
        let step = (f / g2) * g;
        x -= step;
        let near = (x - p).length() <= max_dist;
        if !near {
            return None;
        }
        if step.length() < tolerance {
            return Some((x, g));
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Refined surfaces run at one quality, whatever the asked one, and the GPU's field counts
    /// atoms out to that quality's cutoff (issue 33); interpolated ones run as asked.
    #[test]
    fn refined_vertices_run_at_the_quality_whose_cutoff_the_field_uses() {
        assert_eq!(REFINE_REACH, REFINED_QUALITY.cutoff());
        for quality in Quality::ALL {
            let asked = SurfaceParams {
                spacing: 0.7,
                quality,
                ..SurfaceParams::default()
            };
            let refined = SurfaceParams {
                quality: REFINED_QUALITY,
                ..asked
            };
            assert_eq!(VertexMode::Refined.effective(&asked), refined);
            assert_eq!(VertexMode::Interpolated.effective(&asked), asked);
        }
    }
}
