//! Offscreen pictures from the renderer: small golden images (compared within one tolerance,
//! regenerate with `UPDATE_GOLDEN=1`), stereo output sizes, transparency, and a non-uniform
//! screenshot. Needs a wgpu adapter (lavapipe is enough); without one the tests return early
//! with a note, unless `REQUIRE_GPU=1`, where a missing adapter fails them.

use std::path::PathBuf;

use glam::Vec3;
use mdsurf::render::{
    AtomStyle, Background, Camera, GpuScene, HeadlessGpu, MEAN_TOLERANCE, OUTLIER_FRACTION,
    RenderSettings, Renderer, RgbaImage, Stereo, atom_instances, render_to_rgba, shapes::icosphere,
    write_png,
};

/// The headless device, or `None` (with a note) when there is none and `REQUIRE_GPU` is unset.
pub(crate) fn gpu() -> Option<HeadlessGpu> {
    match HeadlessGpu::new() {
        Ok(g) => Some(g),
        Err(e) if std::env::var("REQUIRE_GPU").is_ok_and(|v| v == "1") => {
            panic!("REQUIRE_GPU=1 but no adapter: {e}")
        }
        Err(e) => {
            eprintln!("note: skipping GPU render test: {e}");
            None
        }
    }
}

/// A sphere coloured by direction with three atoms inside it.
fn demo_scene(g: &HeadlessGpu, settings: &RenderSettings) -> (GpuScene, Camera) {
    let mut scene = GpuScene::new();
    scene.set_mesh(&g.device, &g.queue, &icosphere(Vec3::ZERO, 6.0, 3, None));
    let atoms = [
        Vec3::new(-2.0, 0.0, 0.0),
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.4, 0.2, 0.0),
    ];
    let colours = [[0.9, 0.1, 0.1], [0.1, 0.9, 0.1], [0.1, 0.2, 0.9]];
    let (s, c) = atom_instances(
        &atoms,
        &[1.5, 1.5, 1.0],
        Some(&colours),
        &[[1, 2]],
        settings,
    );
    scene.set_atoms(&g.device, &g.queue, &s, &c);
    let mut camera = Camera::default();
    let (lo, hi) = scene.bounds().expect("scene has bounds");
    camera.fit(lo, hi);
    camera.orbit(0.4, 0.3);
    (scene, camera)
}

fn render(g: &HeadlessGpu, settings: &RenderSettings, size: [u32; 2]) -> RgbaImage {
    let renderer = Renderer::new(&g.device);
    let (scene, camera) = demo_scene(g, settings);
    render_to_rgba(
        &g.device, &g.queue, &renderer, &scene, &camera, settings, size,
    )
    .expect("render")
}

pub(crate) fn compare_golden(name: &str, image: &RgbaImage) {
    let path = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/golden")).join(name);
    if std::env::var("UPDATE_GOLDEN").is_ok_and(|v| v == "1") {
        write_png(&path, image).expect("write golden");
        eprintln!("wrote {}", path.display());
        return;
    }
    let golden = RgbaImage::read_png(&path)
        .unwrap_or_else(|e| panic!("{e} (run with UPDATE_GOLDEN=1 to create it)"));
    assert_eq!(
        (golden.width, golden.height),
        (image.width, image.height),
        "{name}: size"
    );
    let (mean, frac) = golden.difference(image).expect("same size");
    if mean > MEAN_TOLERANCE || frac > OUTLIER_FRACTION {
        let out = std::env::temp_dir().join(format!("mdsurf-actual-{name}"));
        let _ = write_png(&out, image);
        panic!(
            "{name}: mean difference {mean:.2}, {:.2}% outliers; actual image at {}",
            frac * 100.0,
            out.display()
        );
    }
}

#[test]
fn opaque_sphere_matches_golden() {
    let Some(g) = gpu() else { return };
    let image = render(&g, &RenderSettings::default(), [128, 128]);
    compare_golden("render_sphere_opaque.png", &image);
}

#[test]
fn transparent_surface_over_sticks_matches_golden() {
    let Some(g) = gpu() else { return };
    let settings = RenderSettings {
        background: Background::Light,
        surface_opacity: 0.35,
        atom_style: AtomStyle::BallAndStick,
        ..Default::default()
    };
    let image = render(&g, &settings, [128, 128]);
    compare_golden("render_sphere_transparent.png", &image);
}

#[test]
fn transparency_shows_the_atoms_inside() {
    let Some(g) = gpu() else { return };
    let base = RenderSettings {
        atom_style: AtomStyle::Spheres,
        ..Default::default()
    };
    let opaque = render(&g, &base, [96, 96]);
    let clear = render(
        &g,
        &RenderSettings {
            surface_opacity: 0.3,
            ..base
        },
        [96, 96],
    );
    let no_atoms = render(
        &g,
        &RenderSettings {
            surface_opacity: 0.3,
            atom_style: AtomStyle::Hidden,
            ..base
        },
        [96, 96],
    );
    // The centre pixel of the opaque surface does not change when atoms are hidden inside it,
    // but the transparent one shows them.
    let c = |img: &RgbaImage| img.pixel(48, 48);
    assert_ne!(
        c(&clear),
        c(&no_atoms),
        "atoms inside a transparent surface should show"
    );
    assert_ne!(c(&opaque), c(&clear));
}

#[test]
fn screenshot_is_not_uniform_and_background_is_in_the_corner() {
    let Some(g) = gpu() else { return };
    for bg in [Background::Dark, Background::Light] {
        let image = render(
            &g,
            &RenderSettings {
                background: bg,
                ..Default::default()
            },
            [64, 48],
        );
        assert_eq!((image.width, image.height), (64, 48));
        assert!(
            image.distinct_colours() > 50,
            "only {} colours",
            image.distinct_colours()
        );
        let corner = image.pixel(0, 0);
        let expect = if bg == Background::Light { 255 } else { 30 };
        assert!(
            if bg == Background::Light {
                corner[0] == expect
            } else {
                corner[0] < expect
            },
            "{bg:?}: {corner:?}"
        );
    }
}

#[test]
fn stereo_outputs_have_the_requested_size_and_differ_per_eye() {
    let Some(g) = gpu() else { return };
    let sbs = render(
        &g,
        &RenderSettings {
            stereo: Stereo::SideBySide,
            eye_separation: 0.08,
            ..Default::default()
        },
        [160, 80],
    );
    assert_eq!((sbs.width, sbs.height), (160, 80));
    let half = |img: &RgbaImage, x0: u32| -> Vec<u8> {
        (0..80)
            .flat_map(|y| (x0..x0 + 80).flat_map(move |x| img.pixel(x, y)))
            .collect()
    };
    let (l, r) = (half(&sbs, 0), half(&sbs, 80));
    assert_ne!(l, r, "the two eyes should see different images");
    // Each half holds a whole view: the centre of each half is surface, not background.
    assert!(sbs.pixel(40, 40)[..3].iter().any(|&v| v > 40));
    assert!(sbs.pixel(120, 40)[..3].iter().any(|&v| v > 40));

    let settings = RenderSettings {
        surface_colour: Some([0.8, 0.8, 0.8]),
        ..Default::default()
    };
    let mono = render(&g, &settings, [120, 90]);
    let ana = render(
        &g,
        &RenderSettings {
            stereo: Stereo::Anaglyph,
            eye_separation: 0.1,
            ..settings
        },
        [120, 90],
    );
    assert_eq!((ana.width, ana.height), (120, 90));
    // A grey surface stays grey in mono; in the anaglyph, the eyes' offsets leave red-only and
    // cyan-only fringes at the silhouette.
    let fringes = |img: &RgbaImage| {
        img.pixels
            .chunks_exact(4)
            .filter(|p| (p[0] as i32 - p[1] as i32).abs() > 40)
            .count()
    };
    assert_eq!(fringes(&mono), 0);
    assert!(fringes(&ana) > 20, "anaglyph fringes: {}", fringes(&ana));
}

#[test]
fn ambient_occlusion_darkens_creases_but_not_the_background() {
    let Some(g) = gpu() else { return };
    // Three touching spheres make creases where they meet.
    let settings = |ao: f32| RenderSettings {
        ambient_occlusion: ao,
        depth_cue: 0.0,
        show_surface: false,
        atom_style: AtomStyle::Spheres,
        ..Default::default()
    };
    let renderer = Renderer::new(&g.device);
    let atoms = [
        Vec3::new(-1.5, 0.0, 0.0),
        Vec3::new(1.5, 0.0, 0.0),
        Vec3::new(0.0, 1.8, 1.0),
    ];
    let mut scene = GpuScene::new();
    let (s, c) = atom_instances(&atoms, &[2.0; 3], None, &[], &settings(0.0));
    scene.set_atoms(&g.device, &g.queue, &s, &c);
    let mut camera = Camera::default();
    let (lo, hi) = scene.bounds().expect("bounds");
    camera.fit(lo, hi);
    let shot = |ao| {
        render_to_rgba(
            &g.device,
            &g.queue,
            &renderer,
            &scene,
            &camera,
            &settings(ao),
            [96, 96],
        )
        .expect("render")
    };
    let (off, on) = (shot(0.0), shot(1.0));
    let sum = |img: &RgbaImage| {
        img.pixels
            .chunks_exact(4)
            .map(|p| p[0] as u64 + p[1] as u64 + p[2] as u64)
            .sum::<u64>()
    };
    assert!(
        sum(&on) < sum(&off) * 97 / 100,
        "AO should darken: {} vs {}",
        sum(&on),
        sum(&off)
    );
    assert_eq!(
        on.pixel(0, 0),
        off.pixel(0, 0),
        "background must not change"
    );
}
