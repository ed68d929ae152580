//! Shading with analytic normals (issue 13 section 3): 1hpv at H = 2 Å with refined vertices is
//! drawn offscreen and compared with a golden image (`tests/golden/render_1hpv_h2_refined.png`,
//! tolerance in `mdsurf::render`, regenerate with `UPDATE_GOLDEN=1`), and against a fine
//! surface (H = 0.5 Å) standing in for the smooth truth: refined H = 2 looks closer to it than
//! interpolated H = 2 (whose central-difference normals facet the shading). Uniform white
//! surface, so only shading and shape differ. Needs a wgpu adapter, as tests/it/render_images.rs.

use crate::gpu_support::load_pdb;
use crate::render_images::{compare_golden, gpu};
use mdsurf::render::{
    Camera, GpuScene, HeadlessGpu, RenderSettings, Renderer, RgbaImage, render_to_rgba,
};
use mdsurf::surface::{CpuEngine, Mesh, Quality, SurfaceEngine, SurfaceParams, VertexMode};

fn surface(spacing: f32, mode: VertexMode) -> Mesh {
    let mut atoms = load_pdb("1hpv.pdb");
    atoms.colours = None;
    let p = SurfaceParams {
        spacing,
        quality: Quality::High,
        ..Default::default()
    };
    CpuEngine::new()
        .with_vertices(mode)
        .compute(&atoms.set(), &p)
        .expect("surface")
        .mesh
}

/// `mesh` drawn at 160×160 with the camera fitted to `frame` (Å) and turned a little.
fn draw(
    g: &HeadlessGpu,
    renderer: &Renderer,
    mesh: &Mesh,
    frame: (glam::Vec3, glam::Vec3),
) -> RgbaImage {
    let mut scene = GpuScene::new();
    scene.set_mesh(&g.device, &g.queue, mesh);
    let mut camera = Camera::default();
    camera.fit(frame.0, frame.1);
    camera.orbit(0.5, 0.25);
    let settings = RenderSettings::default();
    render_to_rgba(
        &g.device,
        &g.queue,
        renderer,
        &scene,
        &camera,
        &settings,
        [160, 160],
    )
    .expect("render")
}

#[test]
fn refined_h2_matches_golden_and_looks_like_the_fine_surface() {
    let Some(g) = gpu() else { return };
    let renderer = Renderer::new(&g.device);
    let fine = surface(0.5, VertexMode::Interpolated);
    let frame = fine.bounds().expect("fine mesh has bounds");
    let truth = draw(&g, &renderer, &fine, frame);
    let refined = draw(&g, &renderer, &surface(2.0, VertexMode::Refined), frame);
    let linear = draw(
        &g,
        &renderer,
        &surface(2.0, VertexMode::Interpolated),
        frame,
    );
    compare_golden("render_1hpv_h2_refined.png", &refined);
    let (d_ref, o_ref) = truth.difference(&refined).expect("same size");
    let (d_lin, o_lin) = truth.difference(&linear).expect("same size");
    eprintln!(
        "vs H = 0.5: refined mean {d_ref:.2} ({:.1} % outliers), interpolated {d_lin:.2} ({:.1} %)",
        100.0 * o_ref,
        100.0 * o_lin
    );
    assert!(
        d_ref < d_lin && o_ref < o_lin,
        "refined H = 2 ({d_ref:.2}, {o_ref:.3}) is not closer to H = 0.5 than interpolated \
         ({d_lin:.2}, {o_lin:.3})"
    );
}
