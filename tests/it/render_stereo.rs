//! Stereo pictures a person can fuse (issue 15): off-axis eyes whose zero-parallax plane is the
//! focal plane at the camera target (a sphere there lands on the same pixels in both eyes,
//! nearer spheres have crossed parallax, farther ones uncrossed; in perspective and orthographic
//! projection), the two side-by-side flavours (wall-eyed `sbs`, cross-eyed `sbs-cross`), and the
//! colour and grey anaglyphs composed from the eyes rendered separately (a side-by-side image at
//! twice the width holds each eye at the anaglyph's size). On the real adenylate kinase surface
//! (tests/data/adk_open.pdb). Needs a wgpu adapter (lavapipe is enough); without one the GPU
//! tests return early with a note, unless `REQUIRE_GPU=1`, where a missing adapter fails them.

use std::process::Command;

use glam::Vec3;
use mdsurf::model::{ParticleOptions, Particles};
use mdsurf::render::{
    AtomStyle, Camera, GpuScene, HeadlessGpu, Projection, RenderSettings, Renderer, RgbaImage,
    Stereo, atom_instances, bounding_sphere, render_to_rgba,
};
use mdsurf::surface::{CpuEngine, SurfaceEngine, SurfaceParams};

use crate::data_support::data;

fn gpu() -> Option<HeadlessGpu> {
    match HeadlessGpu::new() {
        Ok(g) => Some(g),
        Err(e) if std::env::var("REQUIRE_GPU").is_ok_and(|v| v == "1") => {
            panic!("REQUIRE_GPU=1 but no adapter: {e}")
        }
        Err(e) => {
            eprintln!("note: skipping GPU stereo test: {e}");
            None
        }
    }
}

/// Eye image size (lavapipe is slow: keep it small).
const W: u32 = 160;
const H: u32 = 120;

/// The adenylate kinase surface (CPU engine, coarse grid) and a camera fitted to it.
fn adk_scene(g: &HeadlessGpu) -> (GpuScene, Camera) {
    let traj = mdsurf::io::open(&data("adk_open.pdb"), None).expect("open adk_open.pdb");
    let frame = traj.read_frame(0).expect("frame 0");
    let particles =
        Particles::new(traj.topology(), &frame, &ParticleOptions::default()).expect("particles");
    let mut positions = Vec::new();
    particles
        .positions_into(&frame, &mut positions)
        .expect("positions");
    let params = SurfaceParams {
        spacing: 1.5,
        ..SurfaceParams::default()
    };
    let out = CpuEngine::new()
        .compute(&particles.atom_set(&positions), &params)
        .expect("surface");
    assert!(out.mesh.triangle_count() > 1000);
    let mut scene = GpuScene::new();
    scene.set_mesh(&g.device, &g.queue, &out.mesh);
    let (centre, radius) = bounding_sphere(&out.mesh.positions).expect("mesh points");
    let mut camera = Camera::default();
    camera.fit_sphere(centre, radius);
    camera.orbit(0.5, 0.2);
    (scene, camera)
}

fn render(
    g: &HeadlessGpu,
    renderer: &Renderer,
    scene: &GpuScene,
    camera: &Camera,
    settings: &RenderSettings,
    size: [u32; 2],
) -> RgbaImage {
    render_to_rgba(&g.device, &g.queue, renderer, scene, camera, settings, size).expect("render")
}

/// Columns `x0..x0 + w` of `img` as an image of their own.
fn crop(img: &RgbaImage, x0: u32, w: u32) -> RgbaImage {
    let pixels = (0..img.height)
        .flat_map(|y| (x0..x0 + w).flat_map(move |x| img.pixel(x, y)))
        .collect();
    RgbaImage {
        width: w,
        height: img.height,
        pixels,
    }
}

/// The left and right eye images at W x H, rendered separately: the halves of a wall-eyed
/// side-by-side image of twice the width (each half is one eye at W x H).
fn eyes(
    g: &HeadlessGpu,
    renderer: &Renderer,
    scene: &GpuScene,
    camera: &Camera,
    settings: &RenderSettings,
) -> (RgbaImage, RgbaImage) {
    let sbs = render(
        g,
        renderer,
        scene,
        camera,
        &RenderSettings {
            stereo: Stereo::SideBySide,
            ..*settings
        },
        [2 * W, H],
    );
    (crop(&sbs, 0, W), crop(&sbs, W, W))
}

/// Settings without screen-space effects whose noise depends on the absolute pixel position
/// (ambient occlusion), so an eye renders the same in either half of an image.
fn plain() -> RenderSettings {
    RenderSettings {
        ambient_occlusion: 0.0,
        ..RenderSettings::default()
    }
}

fn srgb_to_linear(v: u8) -> f32 {
    let c = v as f32 / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

fn linear_to_srgb(c: f32) -> f32 {
    let c = c.clamp(0.0, 1.0);
    255.0
        * if c <= 0.003_130_8 {
            c * 12.92
        } else {
            1.055 * c.powf(1.0 / 2.4) - 0.055
        }
}

/// Rec. 709 luminance of an sRGB pixel, as an sRGB byte value (what the grey anaglyph stores).
fn luminance(p: [u8; 4]) -> f32 {
    let [r, g, b] = [p[0], p[1], p[2]].map(srgb_to_linear);
    linear_to_srgb(0.2126 * r + 0.7152 * g + 0.0722 * b)
}

/// Checks `image` against the expected `(r, g, b)` of every pixel: at most 0.5 % of the pixels
/// may be off by more than 2 (edges rasterised at another place in the target).
fn assert_pixels(name: &str, image: &RgbaImage, expected: impl Fn(u32, u32) -> [f32; 3]) {
    let mut off = 0;
    let mut worst = 0.0f32;
    for y in 0..image.height {
        for x in 0..image.width {
            let p = image.pixel(x, y);
            let e = expected(x, y);
            let d = (0..3)
                .map(|i| (p[i] as f32 - e[i]).abs())
                .fold(0.0, f32::max);
            worst = worst.max(d);
            off += usize::from(d > 2.0);
        }
    }
    let n = (image.width * image.height) as usize;
    assert!(
        off * 200 <= n,
        "{name}: {off} of {n} pixels differ by more than 2 (worst {worst})"
    );
    eprintln!("{name}: {off} of {n} pixels differ by more than 2 (worst {worst})");
}

#[test]
fn eye_images_differ_and_sbs_cross_swaps_the_halves() {
    let Some(g) = gpu() else { return };
    let renderer = Renderer::new(&g.device);
    let (scene, camera) = adk_scene(&g);
    let s = plain();
    let (l, r) = eyes(&g, &renderer, &scene, &camera, &s);
    let (mean, _) = l.difference(&r).expect("same size");
    assert!(mean > 0.5, "the eyes should see different images: {mean}");
    assert!(l.distinct_colours() > 100, "left eye looks blank");
    let cross = render(
        &g,
        &renderer,
        &scene,
        &camera,
        &RenderSettings {
            stereo: Stereo::SideBySideCross,
            ..s
        },
        [2 * W, H],
    );
    // Cross-eyed: the right eye on the left, the left eye on the right.
    for (name, half, eye) in [
        ("left half = right eye", crop(&cross, 0, W), &r),
        ("right half = left eye", crop(&cross, W, W), &l),
    ] {
        let (mean, frac) = half.difference(eye).expect("same size");
        assert!(mean < 0.05 && frac < 0.002, "{name}: {mean} {frac}");
    }
}

#[test]
fn anaglyphs_take_red_from_the_left_eye_and_cyan_from_the_right() {
    let Some(g) = gpu() else { return };
    let renderer = Renderer::new(&g.device);
    let (scene, camera) = adk_scene(&g);
    let s = plain();
    let (l, r) = eyes(&g, &renderer, &scene, &camera, &s);
    let colour = render(
        &g,
        &renderer,
        &scene,
        &camera,
        &RenderSettings {
            stereo: Stereo::Anaglyph,
            ..s
        },
        [W, H],
    );
    assert_pixels("colour anaglyph", &colour, |x, y| {
        let (a, b) = (l.pixel(x, y), r.pixel(x, y));
        [a[0], b[1], b[2]].map(f32::from)
    });
    let grey = render(
        &g,
        &renderer,
        &scene,
        &camera,
        &RenderSettings {
            stereo: Stereo::AnaglyphGrey,
            ..s
        },
        [W, H],
    );
    assert_pixels("grey anaglyph", &grey, |x, y| {
        let (a, b) = (luminance(l.pixel(x, y)), luminance(r.pixel(x, y)));
        [a, b, b]
    });
    // The grey variant really is luminance, not the colour channels: the coloured surface
    // makes them differ somewhere.
    let (mean, _) = grey.difference(&colour).expect("same size");
    assert!(mean > 0.5, "grey and colour anaglyphs are the same: {mean}");
    // Green and blue of the grey anaglyph are equal (one luminance).
    assert!(
        grey.pixels
            .chunks_exact(4)
            .all(|p| p[1].abs_diff(p[2]) <= 1)
    );
}

/// x of the centroid of the pixels that differ from the background corner.
fn centroid_x(img: &RgbaImage) -> f32 {
    let bg = img.pixel(0, 0);
    let (mut sum, mut n) = (0.0f64, 0usize);
    for y in 0..img.height {
        for x in 0..img.width {
            let p = img.pixel(x, y);
            if (0..3).any(|i| p[i].abs_diff(bg[i]) > 8) {
                sum += x as f64 + 0.5;
                n += 1;
            }
        }
    }
    assert!(n > 20, "nothing drawn");
    (sum / n as f64) as f32
}

/// Parallax (right eye's x minus left eye's, pixels) of a sphere at `offset` Å from the target
/// along the camera's back axis (positive: nearer the camera).
fn parallax(
    g: &HeadlessGpu,
    renderer: &Renderer,
    projection: Projection,
    offset: f32,
    separation: f32,
) -> f32 {
    let settings = RenderSettings {
        show_surface: false,
        atom_style: AtomStyle::Spheres,
        eye_separation: separation,
        ..plain()
    };
    let mut camera = Camera {
        projection,
        ..Camera::default()
    };
    camera.fit_sphere(Vec3::ZERO, 20.0);
    camera.orbit(0.3, 0.2);
    let centre = camera.back() * offset + camera.right() * 2.0;
    let (spheres, cylinders) = atom_instances(&[centre], &[3.0], None, &[], &settings);
    let mut scene = GpuScene::new();
    scene.set_atoms(&g.device, &g.queue, &spheres, &cylinders);
    let (l, r) = eyes(g, renderer, &scene, &camera, &settings);
    centroid_x(&r) - centroid_x(&l)
}

#[test]
fn the_target_depth_fuses_nearer_is_crossed_farther_uncrossed() {
    let Some(g) = gpu() else { return };
    let renderer = Renderer::new(&g.device);
    for projection in [Projection::Perspective, Projection::Orthographic] {
        let at = parallax(&g, &renderer, projection, 0.0, 1.0 / 30.0);
        assert!(
            at.abs() < 0.5,
            "{projection:?}: parallax at the target {at} px"
        );
        let near = parallax(&g, &renderer, projection, 12.0, 0.08);
        let far = parallax(&g, &renderer, projection, -12.0, 0.08);
        eprintln!(
            "{projection:?}: parallax at the target {at:.3} px, near {near:.2}, far {far:.2}"
        );
        // Crossed: the left eye's image of a near point is right of the right eye's.
        assert!(near < -1.5, "{projection:?}: near parallax {near} px");
        assert!(far > 1.5, "{projection:?}: far parallax {far} px");
    }
}

#[test]
fn bad_stereo_numbers_are_refused_in_one_line() {
    let pdb = data("adk_open.pdb");
    for (flag, value, what) in [
        ("--eye-separation", "nan", "eye separation"),
        ("--eye-separation", "-0.1", "eye separation"),
        ("--eye-separation", "inf", "eye separation"),
        ("--focal", "-20", "focal distance"),
        ("--focal", "NaN", "focal distance"),
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_mdsurf"))
            .arg("render")
            .arg(&pdb)
            .args(["--stereo", "anaglyph", "-o", "/nonexistent/never.png"])
            .args([flag, value])
            .output()
            .expect("run mdsurf");
        assert!(!out.status.success(), "{flag} {value} was accepted");
        let err = String::from_utf8_lossy(&out.stderr);
        let line = err
            .lines()
            .find(|l| l.contains(what))
            .unwrap_or_else(|| panic!("{flag} {value}: no '{what}' in {err}"));
        assert!(line.starts_with("error:") && line.contains(value), "{line}");
    }
    let out = Command::new(env!("CARGO_BIN_EXE_mdsurf"))
        .args(["render", "x.pdb", "-o", "x.png", "--stereo", "wobble"])
        .output()
        .expect("run mdsurf");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("sbs-cross") && err.contains("anaglyph-grey"),
        "{err}"
    );
}
