//! Shared helpers of the GPU parity tests: opening the engine (skip with a note without an
//! adapter, fail under REQUIRE_GPU=1), a straightforward CPU reference of density, colour and
//! Marching Cubes written for the tests (same definitions as DESIGN section 2 and the same vertex
//! numbering as the GPU: crossed edges in x-fastest point order, x/y/z edge order), and
//! comparisons that use the tolerances of `mdsurf::gpu::tolerance`.
#![allow(dead_code)]

use glam::Vec3;
use mdsurf::gpu::{GpuContext, GpuEngine, tolerance as tol};
use mdsurf::surface::tables::{EDGE_CORNERS, McTables, corner_offset};
use mdsurf::surface::{AtomSet, GridSpec, Mesh, SurfaceParams};

/// The headless GPU context; `None` (test skipped) only without `REQUIRE_GPU=1`, a panic with
/// it when no adapter is found.
pub fn context() -> Option<GpuContext> {
    match GpuContext::headless_or_skip() {
        Ok(ctx) => ctx,
        Err(e) => panic!("REQUIRE_GPU=1 but no GPU adapter: {e}"),
    }
}

/// The engine, or None (with a note) when there is no adapter and REQUIRE_GPU is not 1.
pub fn engine() -> Option<GpuEngine> {
    context().map(|ctx| GpuEngine::with_context(ctx).expect("GPU engine on a working adapter"))
}

/// Owned atoms for tests.
#[derive(Debug, Clone, Default)]
pub struct Atoms {
    pub positions: Vec<Vec3>,
    pub radii: Vec<f32>,
    pub colours: Option<Vec<[f32; 3]>>,
}

impl Atoms {
    pub fn set(&self) -> AtomSet<'_> {
        AtomSet {
            positions: &self.positions,
            radii: &self.radii,
            colours: self.colours.as_deref(),
        }
    }
}

/// Density and (normalised by nothing: sum of w * colour) colour sums on `grid`, brute force.
pub fn density(grid: &GridSpec, atoms: &Atoms, p: &SurfaceParams) -> (Vec<f32>, Vec<[f32; 3]>) {
    let n = grid.voxel_count() as usize;
    let mut d = vec![0.0f32; n];
    let mut c = vec![[0.0f32; 3]; n];
    let q = p.cutoff();
    for (a, (&pos, &r)) in atoms.positions.iter().zip(&atoms.radii).enumerate() {
        let alpha = r * p.radius_scale;
        let cut = q * alpha;
        let scale = -1.0 / (2.0 * alpha * alpha);
        let lo = ((pos - cut - grid.origin) / grid.spacing)
            .floor()
            .max(Vec3::ZERO);
        let hi = ((pos + cut - grid.origin) / grid.spacing).ceil();
        let rgb = atoms.colours.as_ref().map(|c| c[a]).unwrap_or([0.0; 3]);
        for k in lo.z as u32..=(hi.z as u32).min(grid.dims[2] - 1) {
            for j in lo.y as u32..=(hi.y as u32).min(grid.dims[1] - 1) {
                for i in lo.x as u32..=(hi.x as u32).min(grid.dims[0] - 1) {
                    let x = grid.point(i, j, k);
                    let (dx, dy, dz) = (x.x - pos.x, x.y - pos.y, x.z - pos.z);
                    let d2 = dx * dx + dy * dy + dz * dz;
                    if d2 < cut * cut {
                        let w = (d2 * scale).exp();
                        let v = grid.index(i, j, k);
                        d[v] += w;
                        for ch in 0..3 {
                            c[v][ch] += w * rgb[ch];
                        }
                    }
                }
            }
        }
    }
    (d, c)
}

fn neg_grad(grid: &GridSpec, d: &[f32], p: [u32; 3]) -> Vec3 {
    let mut g = [0.0f32; 3];
    for a in 0..3 {
        let (mut lo, mut hi) = (p, p);
        if p[a] > 0 {
            lo[a] -= 1;
        }
        if p[a] + 1 < grid.dims[a] {
            hi[a] += 1;
        }
        let at = |q: [u32; 3]| d[grid.index(q[0], q[1], q[2])];
        g[a] = (at(lo) - at(hi)) / (hi[a] - lo[a]) as f32;
    }
    Vec3::from(g).normalize_or_zero()
}

/// Marching Cubes with the shared tables and the GPU's vertex numbering.
pub fn marching_cubes(grid: &GridSpec, d: &[f32], c: Option<&[[f32; 3]]>, iso: f32) -> Mesh {
    let [nx, ny, nz] = grid.dims;
    let inside = |i: u32, j: u32, k: u32| d[grid.index(i, j, k)] >= iso;
    let mut ids = vec![[u32::MAX; 3]; d.len()];
    let mut mesh = Mesh::default();
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let p = [i, j, k];
                for axis in 0..3 {
                    let mut q = p;
                    q[axis] += 1;
                    if q[axis] >= grid.dims[axis] || inside(i, j, k) == inside(q[0], q[1], q[2]) {
                        continue;
                    }
                    let (v0, v1) = (grid.index(i, j, k), grid.index(q[0], q[1], q[2]));
                    let t = (iso - d[v0]) / (d[v1] - d[v0]);
                    let x0 = grid.point(i, j, k);
                    let x1 = grid.point(q[0], q[1], q[2]);
                    ids[v0][axis] = mesh.positions.len() as u32;
                    mesh.positions.push(x0 + (x1 - x0) * t);
                    let (n0, n1) = (neg_grad(grid, d, p), neg_grad(grid, d, q));
                    mesh.normals.push((n0 + (n1 - n0) * t).normalize_or_zero());
                    let col = match c {
                        Some(c) => {
                            let (c0, c1) = (Vec3::from(c[v0]), Vec3::from(c[v1]));
                            ((c0 + (c1 - c0) * t) / iso).to_array()
                        }
                        None => [1.0; 3],
                    };
                    mesh.colours.push(col);
                }
            }
        }
    }
    let tables = McTables::get();
    for k in 0..nz.saturating_sub(1) {
        for j in 0..ny.saturating_sub(1) {
            for i in 0..nx.saturating_sub(1) {
                let mut case = 0u8;
                for corner in 0..8u8 {
                    let o = corner_offset(corner);
                    if inside(i + o[0], j + o[1], k + o[2]) {
                        case |= 1 << corner;
                    }
                }
                for tri in tables.case_triangles(case) {
                    for &e in tri {
                        let o = corner_offset(EDGE_CORNERS[e as usize][0]);
                        let v = grid.index(i + o[0], j + o[1], k + o[2]);
                        mesh.indices.push(ids[v][(e / 4) as usize]);
                    }
                }
            }
        }
    }
    mesh
}

/// Reference surface of `atoms`: grid, density, mesh.
pub fn reference(atoms: &Atoms, p: &SurfaceParams) -> (GridSpec, Vec<f32>, Mesh) {
    let grid = GridSpec::for_atoms(&atoms.positions, &atoms.radii, p).expect("valid test atoms");
    let (d, c) = density(&grid, atoms, p);
    let mesh = marching_cubes(
        &grid,
        &d,
        atoms.colours.is_some().then_some(&c[..]),
        p.isovalue,
    );
    (grid, d, mesh)
}

/// Asserts that a GPU mesh matches the reference within the tolerances; where the triangles are
/// identical (no corner classified differently) also compares every vertex and colour and
/// returns true.
pub fn assert_mesh_close(
    what: &str,
    gpu: &Mesh,
    cpu: &Mesh,
    gpu_area: f64,
    gpu_volume: f64,
) -> bool {
    assert!(
        cpu.triangle_count() > 0,
        "{what}: the reference mesh is empty"
    );
    assert!(
        tol::triangles_close(gpu.triangle_count(), cpu.triangle_count()),
        "{what}: {} GPU triangles vs {} CPU",
        gpu.triangle_count(),
        cpu.triangle_count()
    );
    let (ca, cv) = (cpu.area(), cpu.volume());
    for (name, g, c) in [
        ("mesh area", gpu.area(), ca),
        ("mesh volume", gpu.volume(), cv),
        ("reduced area", gpu_area, ca),
        ("reduced volume", gpu_volume, cv),
    ] {
        assert!(
            tol::rel_close(g, c, tol::AREA_VOLUME_REL),
            "{what}: {name} {g} vs CPU {c}"
        );
    }
    if gpu.vertex_count() == cpu.vertex_count() && gpu.indices == cpu.indices {
        for (v, (g, c)) in gpu.colours.iter().zip(&cpu.colours).enumerate() {
            assert!(
                tol::colour_close(*g, *c),
                "{what}: vertex {v} colour {g:?} vs {c:?}"
            );
        }
        for (v, (g, c)) in gpu.positions.iter().zip(&cpu.positions).enumerate() {
            assert!(
                (*g - *c).length() < 1e-3,
                "{what}: vertex {v} at {g} vs {c}"
            );
        }
        for (v, (g, c)) in gpu.normals.iter().zip(&cpu.normals).enumerate() {
            assert!(g.dot(*c) > 0.999, "{what}: vertex {v} normal {g} vs {c}");
        }
        return true;
    }
    false
}

/// Radius in Å of an element symbol (DESIGN section 2).
pub fn element_radius(element: &str) -> f32 {
    match element.trim().to_ascii_uppercase().as_str() {
        "H" => 1.0,
        "C" => 1.5,
        "N" => 1.4,
        "O" => 1.3,
        "F" => 1.2,
        "S" => 1.9,
        "P" => 1.8,
        _ => 1.5,
    }
}

/// Atoms of a wwPDB file under `tests/data` (ATOM/HETATM records, element column), coloured
/// by element so the colour pass has something to do.
pub fn load_pdb(name: &str) -> Atoms {
    let path = crate::data_support::DATA.to_string() + name;
    let text = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("test data {path} is missing ({e}); see tests/data/README.md"));
    let mut atoms = Atoms {
        colours: Some(Vec::new()),
        ..Default::default()
    };
    for line in text
        .lines()
        .filter(|l| l.starts_with("ATOM") || l.starts_with("HETATM"))
    {
        let f = |a: usize, b: usize| line.get(a..b).unwrap_or("").trim();
        let xyz = [f(30, 38), f(38, 46), f(46, 54)].map(|s| s.parse::<f32>().expect("coordinate"));
        let element = f(76, 78);
        atoms.positions.push(Vec3::from(xyz));
        atoms.radii.push(element_radius(element));
        let colour = match element {
            "C" => [0.5, 0.5, 0.5],
            "N" => [0.2, 0.2, 1.0],
            "O" => [1.0, 0.1, 0.1],
            "S" => [1.0, 0.9, 0.2],
            _ => [0.9, 0.9, 0.9],
        };
        if let Some(c) = atoms.colours.as_mut() {
            c.push(colour);
        }
    }
    assert!(!atoms.positions.is_empty(), "no atoms in {path}");
    atoms
}

/// A copy of `atoms` with every coordinate moved by up to `amp` Å (deterministic per `seed`).
pub fn jitter(atoms: &Atoms, seed: u64, amp: f32) -> Atoms {
    let mut s = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    let mut next = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 33) as f32 / (1u64 << 31) as f32) * 2.0 - 1.0
    };
    let mut out = atoms.clone();
    for p in &mut out.positions {
        *p += Vec3::new(next(), next(), next()) * amp;
    }
    out
}
