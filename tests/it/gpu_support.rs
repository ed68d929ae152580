//! Shared helpers of the GPU parity tests: opening the engine (skip with a note without an
//! adapter, fail under REQUIRE_GPU=1), the reference the GPU is compared with (the real CPU
//! engine, dense, and its density volume: same definitions as DESIGN section 2 and the same
//! vertex numbering as the GPU), and comparisons that use the tolerances of
//! `mdsurf::gpu::tolerance`.
#![allow(dead_code)]

use glam::Vec3;
use mdsurf::gpu::{GpuContext, GpuEngine, tolerance as tol};
use mdsurf::surface::{AtomSet, CpuEngine, GridSpec, Mesh, SurfaceEngine, SurfaceParams};

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

/// The reference surface of `atoms`: the CPU engine's grid, its density volume (the engine's
/// stage 2, [`mdsurf::surface::density::compute`]) and the mesh of [`CpuEngine::dense`], which
/// numbers vertices as the GPU does (crossed edges in x-fastest point order, x/y/z edge order).
pub fn reference(atoms: &Atoms, p: &SurfaceParams) -> (GridSpec, Vec<f32>, Mesh) {
    let out = CpuEngine::dense()
        .compute(&atoms.set(), p)
        .expect("the CPU engine computes the test atoms");
    let density = mdsurf::surface::density::compute(&atoms.set(), p, &out.grid)
        .expect("the CPU density of the test atoms");
    (out.grid, density.values, out.mesh)
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

/// Atoms of the first frame of a structure under `tests/data`, read by mdsurf's own reader,
/// with the radii and element colours `mdsurf surface` gives them (so the colour pass has
/// something to do).
pub fn load_pdb(name: &str) -> Atoms {
    let path = crate::data_support::data(name);
    let traj = mdsurf::io::open(&path, None)
        .unwrap_or_else(|e| panic!("{}: {e}; see tests/data/README.md", path.display()));
    let frame = traj.read_frame(0).expect("frame 0");
    let options = mdsurf::model::ParticleOptions::default();
    let particles = mdsurf::model::Particles::new_subset(traj.topology(), &frame, &options, None)
        .expect("particles");
    assert!(
        !frame.positions.is_empty(),
        "no atoms in {}",
        path.display()
    );
    Atoms {
        radii: particles.radii().to_vec(),
        colours: Some(particles.colours().to_vec()),
        positions: frame.positions,
    }
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
