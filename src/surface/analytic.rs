//! The exact Gaussian sum near the surface, for refined vertices and curvature-aware measurement
//! (issue 13). Sits beside the sampled density: [`super::bin`] prepares the atoms, this module
//! puts them in a uniform cell grid (cells half the largest reach wide, so a point's atoms are in
//! its 5³ neighbouring cells) and evaluates `rho(x)` and `grad rho(x)` in f32.
//!
//! Reach: every atom counts out to [`REFINE_REACH`] = 4 alpha (the `max` quality's cutoff, where
//! a term is below 3.4e-4), whatever the quality. The sampled density keeps the quality's cutoff
//! (it decides the topology), but the surface the vertices are placed on is the Gaussian sum
//! itself: with the `high` cutoff (3 alpha) each atom's term would jump by 0.011 at its cutoff
//! sphere, and the level set of such a sum has small cliffs whose measured area keeps growing as
//! H shrinks (1hpv, I = 0.5: +0.6 % from H = 1 to H = 0.25), where at 4 alpha it converges
//! (within 0.001 % from H = 0.5 down).
//!
//! Data flow: [`PreparedAtom`]s -> [`AnalyticField`] -> [`AnalyticField::refine_edge`] (one
//! Marching Cubes vertex: position where `rho = I` on its grid edge, normal `-grad rho`
//! normalised) and [`AnalyticField::project`] (a point moved onto the surface along the
//! gradient, for [`super::curved`]).

use glam::Vec3;

use super::GridSpec;
use super::bin::PreparedAtom;

/// How Marching Cubes places its vertices and normals.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum VertexMode {
    /// Linear interpolation of the samples along the edge, normals from central differences
    /// (DESIGN section 2; the area and volume are those of the flat triangles). The default.
    #[default]
    Interpolated,
    /// The root of the exact Gaussian sum on the edge, normals from its analytic gradient; the
    /// area and volume account for curvature ([`super::curved`]). Costs about three times a
    /// CPU frame (`mdsurf bench` reports it), so it is not the default.
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
}

impl std::fmt::Display for VertexMode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for VertexMode {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        VertexMode::ALL
            .into_iter()
            .find(|m| m.name().eq_ignore_ascii_case(s))
            .ok_or_else(|| format!("unknown vertex mode '{s}' (expected interpolated or refined)"))
    }
}

/// How far each atom's Gaussian reaches in the analytic sum, in units of its alpha.
pub const REFINE_REACH: f32 = 4.0;
/// Most safeguarded Newton steps per edge (each one evaluation of rho and its gradient).
pub const REFINE_ITERATIONS: u32 = 8;
/// An edge's root is accepted when the next Newton step would move it less than this (Å).
pub const REFINE_STEP: f32 = 1e-4;

/// One atom of the field (position in Å, exponent factor in Å⁻², squared cutoff in Å²).
#[derive(Debug, Clone, Copy)]
struct FieldAtom {
    pos: Vec3,
    k: f32,
    cut2: f32,
}

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
}

impl AnalyticField {
    /// Bins `atoms` (in canonical order; kept within each cell) into cells half the largest
    /// reach wide over the bounding box of `grid`; each atom reaches [`REFINE_REACH`] alpha
    /// (`alpha² = 0.5 / k`).
    pub fn new(atoms: &[PreparedAtom], grid: &GridSpec) -> AnalyticField {
        let reach2 = |a: &PreparedAtom| REFINE_REACH * REFINE_REACH * 0.5 / a.k;
        let cell = 0.5
            * atoms
                .iter()
                .map(reach2)
                .fold(0.0f32, f32::max)
                .sqrt()
                .max(1e-3);
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
        };
        field.atoms.resize(atoms.len(), placeholder);
        for (a, &c) in atoms.iter().zip(&cells) {
            field.atoms[fill[c] as usize] = FieldAtom {
                pos: Vec3::from(a.pos),
                k: a.k,
                cut2: reach2(a),
            };
            fill[c] += 1;
        }
        field
    }

    fn cell_of(&self, p: Vec3) -> [i32; 3] {
        let c = (p - self.origin) / self.cell;
        [0, 1, 2].map(|a| (c[a].floor() as i32).clamp(0, self.dims[a] - 1))
    }

    fn cell_index(&self, c: [i32; 3]) -> usize {
        (c[0] + self.dims[0] * (c[1] + self.dims[1] * c[2])) as usize
    }

    /// `rho(p)` and `grad rho(p)` (Å⁻¹) at `p` (Å): the sum over the atoms with
    /// `|p - p_i| < 4 alpha_i` of `exp(-k_i |p - p_i|²)` and its gradient.
    pub fn eval(&self, p: Vec3) -> (f32, Vec3) {
        let c = (p - self.origin) / self.cell;
        let lo = [0, 1, 2].map(|a| ((c[a].floor() as i32) - 2).max(0));
        let hi = [0, 1, 2].map(|a| ((c[a].floor() as i32) + 2).min(self.dims[a] - 1));
        let mut rho = 0.0f32;
        let mut grad = Vec3::ZERO;
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                if lo[0] > hi[0] {
                    continue;
                }
                let first = self.cell_index([lo[0], y, z]);
                let last = self.cell_index([hi[0], y, z]);
                let (s, e) = (self.cell_start[first], self.cell_start[last + 1]);
                for atom in &self.atoms[s as usize..e as usize] {
                    let d = p - atom.pos;
                    let d2 = (d.x * d.x + d.y * d.y) + d.z * d.z;
                    if d2 < atom.cut2 {
                        let w = (-atom.k * d2).exp();
                        rho += w;
                        grad -= (2.0 * atom.k * w) * d;
                    }
                }
            }
        }
        (rho, grad)
    }

    /// The vertex on the grid edge from `pa` (density `va`) to `pb` (density `vb`), Å, where
    /// `va >= iso` differs from `vb >= iso`: the root of `rho = iso` on the segment by Newton
    /// steps safeguarded by the bracket (regula falsi when a step leaves it), starting from the
    /// linear estimate `t0`. It stops when the next step would be shorter than [`REFINE_STEP`]
    /// (and takes it) or after [`REFINE_ITERATIONS`] evaluations. The bracket's end values are
    /// the samples', so a root the 4-alpha sum does not have on the edge (the samples use the
    /// quality's shorter cutoff) ends at the end point nearest to it. Returns the position (Å) and
    /// the unit normal `-grad rho / |grad rho|` from the last evaluation, `None` when the
    /// gradient vanishes there.
    pub fn refine_edge(
        &self,
        pa: Vec3,
        pb: Vec3,
        va: f32,
        vb: f32,
        iso: f32,
        t0: f32,
    ) -> (Vec3, Option<Vec3>) {
        let dir = pb - pa;
        let len = dir.length();
        let (mut lo, mut hi) = (0.0f32, 1.0f32);
        let (mut flo, mut fhi) = (va - iso, vb - iso);
        let lo_inside = flo >= 0.0;
        let mut t = t0.clamp(0.0, 1.0);
        let mut g = Vec3::ZERO;
        let mut f_last = 0.0f32;
        for _ in 0..REFINE_ITERATIONS {
            let (rho, grad) = self.eval(pa + t * dir);
            g = grad;
            let f = rho - iso;
            f_last = f;
            if f == 0.0 {
                break;
            }
            if (f >= 0.0) == lo_inside {
                (lo, flo) = (t, f);
            } else {
                (hi, fhi) = (t, f);
            }
            let df = grad.dot(dir);
            let newton = t - f / df;
            if df != 0.0 && newton >= lo && newton <= hi {
                let done = (newton - t).abs() * len < REFINE_STEP;
                t = newton;
                if done {
                    break;
                }
            } else {
                t = if flo != fhi {
                    (lo - flo * (hi - lo) / (fhi - flo)).clamp(lo, hi)
                } else {
                    0.5 * (lo + hi)
                };
                if (hi - lo) * len < REFINE_STEP {
                    break;
                }
            }
        }
        let mut position = pa + t * dir;
        let found = f_last.abs() * len <= 0.1 * REFINE_STEP * g.length() * len + 1e-4;
        if !found {
            // No root of the 4-alpha sum on this edge (its end point's sample, cut off at the
            // quality's shorter reach, is on the other side): move onto the surface along the
            // gradient instead, at most half an edge length.
            if let Some((p, n)) = self.project(position, iso, 0.5 * len) {
                position = p;
                g = n;
            }
        }
        let n = -g;
        let normal = (n.length_squared() > 0.0 && n.is_finite()).then(|| n.normalize());
        (position, normal)
    }

    /// `p` (Å) moved onto `rho = iso` by Newton steps along the gradient (at most four), with
    /// the gradient there; `None` when that does not converge within `max_dist` Å of `p`.
    pub fn project(&self, p: Vec3, iso: f32, max_dist: f32) -> Option<(Vec3, Vec3)> {
        let mut x = p;
        for _ in 0..4 {
            let (rho, g) = self.eval(x);
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
            if step.length() < REFINE_STEP {
                return Some((x, g));
            }
        }
        None
    }
}
