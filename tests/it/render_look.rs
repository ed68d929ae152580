//! The figure look on the offscreen renderer: silhouette outlines darken a ring just inside the
//! silhouette, leave the inside of a smooth sphere and the background alone; key-light shadows darken the surface
//! behind an occluder and nothing on a lone sphere; `mdsurf render --transparent` writes alpha 0
//! on the background and 1 on the molecule. Needs a wgpu adapter (lavapipe is enough); without
//! one the tests return early with a note unless `REQUIRE_GPU=1`.

use std::process::Command;

use glam::Vec3;
use mdsurf::render::{
    Background, Camera, GpuScene, HeadlessGpu, RenderSettings, Renderer, RgbaImage, SphereInstance,
    render_to_rgba, shapes::icosphere, write_png,
};

use crate::cli_common::{data, have_gpu};
use crate::render_images::gpu;

const SIZE: [u32; 2] = [160, 160];

/// Plain lighting on a white background: no ambient occlusion or depth cue.
pub(crate) fn plain() -> RenderSettings {
    RenderSettings {
        background: Background::Light,
        ambient_occlusion: 0.0,
        depth_cue: 0.0,
        ..Default::default()
    }
}

/// Renders a sphere of radius 6 Å at the origin, with an atom sphere `occluder` (centre along
/// the camera's right, up, back axes in Å, radius) when given.
fn render(settings: &RenderSettings, occluder: Option<([f32; 3], f32)>) -> Option<RgbaImage> {
    let g = gpu()?;
    let renderer = Renderer::new(&g.device);
    let (scene, camera) = sphere_scene(&g, occluder);
    let image = render_to_rgba(
        &g.device, &g.queue, &renderer, &scene, &camera, settings, SIZE,
    )
    .expect("render");
    Some(image)
}

/// The scene of [`render`] on `g`, with its camera.
pub(crate) fn sphere_scene(
    g: &HeadlessGpu,
    occluder: Option<([f32; 3], f32)>,
) -> (GpuScene, Camera) {
    let mut scene = GpuScene::new();
    scene.set_mesh(
        &g.device,
        &g.queue,
        &icosphere(Vec3::ZERO, 6.0, 4, Some([0.8, 0.8, 0.8])),
    );
    let mut camera = Camera::default();
    camera.fit(Vec3::splat(-9.0), Vec3::splat(9.0));
    if let Some(([r, u, b], radius)) = occluder {
        let c = camera.right() * r + camera.up() * u + camera.back() * b;
        let s = SphereInstance {
            centre: c.into(),
            radius,
            colour: [0.8, 0.8, 0.8, 1.0],
        };
        scene.set_atoms(&g.device, &g.queue, &[s], &[]);
    }
    (scene, camera)
}

fn luminance(p: [u8; 4]) -> f64 {
    0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64
}

/// Saves `image` for looking at when `MDSURF_KEEP_LOOK` names a folder.
fn keep(name: &str, image: &RgbaImage) {
    if let Ok(dir) = std::env::var("MDSURF_KEEP_LOOK") {
        write_png(&std::path::Path::new(&dir).join(name), image).expect("write png");
    }
}

/// Pixels drawn (differing from the white background) in `image`.
fn drawn(image: &RgbaImage) -> Vec<bool> {
    image
        .pixels
        .chunks_exact(4)
        .map(|p| p[..3] != [255, 255, 255])
        .collect()
}

/// Distance in pixels (chessboard) from each pixel to the nearest pixel whose `mask` differs
/// from its own, up to `max`.
fn edge_distance(mask: &[bool], [w, h]: [u32; 2], max: i32) -> Vec<i32> {
    let (w, h) = (w as i32, h as i32);
    let at = |x: i32, y: i32| mask[(y.clamp(0, h - 1) * w + x.clamp(0, w - 1)) as usize];
    (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| {
            let own = at(x, y);
            (1..=max)
                .find(|&r| {
                    (-r..=r).any(|d| {
                        [(d, -r), (d, r), (-r, d), (r, d)]
                            .iter()
                            .any(|&(dx, dy)| at(x + dx, y + dy) != own)
                    })
                })
                .unwrap_or(max + 1)
        })
        .collect()
}

#[test]
fn outlines_darken_the_silhouette_not_the_inside() {
    let Some(off) = render(&plain(), None) else {
        return;
    };
    let on_settings = RenderSettings {
        outline_width: 2.0,
        ..plain()
    };
    let on = render(&on_settings, None).expect("gpu");
    keep("outline_off.png", &off);
    keep("outline_on.png", &on);
    let mask = drawn(&off);
    let dist = edge_distance(&mask, SIZE, 8);
    // Luminance of each pixel without and with the outlines, by where it lies.
    let (mut ring, mut inside, mut background) = (Vec::new(), Vec::new(), Vec::new());
    for (i, (&m, &d)) in mask.iter().zip(&dist).enumerate() {
        let (x, y) = (i as u32 % SIZE[0], i as u32 / SIZE[0]);
        let pair = (luminance(off.pixel(x, y)), luminance(on.pixel(x, y)));
        if m && d <= 1 {
            ring.push(pair);
        } else if m && d > 4 {
            inside.push(pair);
        } else if !m {
            background.push(pair);
        }
    }
    let mean = |v: &[(f64, f64)], f: fn((f64, f64)) -> f64| {
        v.iter().map(|&p| f(p)).sum::<f64>() / v.len().max(1) as f64
    };
    assert!(
        ring.len() > 50 && inside.len() > 1000 && background.len() > 1000,
        "{} {} {}",
        ring.len(),
        inside.len(),
        background.len()
    );
    let ring_off = mean(&ring, |(a, _)| a);
    let ring_on = mean(&ring, |(_, b)| b);
    assert!(
        ring_on < 60.0 && ring_off - ring_on > 100.0,
        "the silhouette's ring has luminance {ring_on:.1} with outlines, {ring_off:.1} without"
    );
    let inside_change = mean(&inside, |(a, b)| (a - b).abs());
    assert!(inside_change < 1.0, "inside changed by {inside_change:.2}");
    let background_change = mean(&background, |(a, b)| (a - b).abs());
    assert_eq!(background_change, 0.0, "the background changed");
}

#[test]
fn shadows_darken_behind_an_occluder_only() {
    // An atom between the key light (up-left-front, see render_scene.wgsl) and the sphere.
    let l = Vec3::new(-0.4, 0.6, 0.7).normalize() * 9.0;
    let occluder = Some(([l.x, l.y, l.z], 2.5));
    let Some(off) = render(&plain(), occluder) else {
        return;
    };
    let shadowed = RenderSettings {
        shadows: 1.0,
        ..plain()
    };
    let on = render(&shadowed, occluder).expect("gpu");
    keep("shadow_off.png", &off);
    keep("shadow_on.png", &on);
    let darker: Vec<f64> = off
        .pixels
        .chunks_exact(4)
        .zip(on.pixels.chunks_exact(4))
        .map(|(a, b)| {
            let f = |p: &[u8]| luminance([p[0], p[1], p[2], p[3]]);
            f(a) - f(b)
        })
        .collect();
    let shadow_pixels = darker.iter().filter(|&&d| d > 25.0).count();
    assert!(shadow_pixels > 40, "{shadow_pixels} pixels in shadow");
    assert!(darker.iter().all(|&d| d > -1.0), "shadows never lighten");
    // The background keeps its colour.
    assert_eq!(on.pixel(0, 0), off.pixel(0, 0));
    // A lone sphere casts no shadow on itself.
    let lone_off = render(&plain(), None).expect("gpu");
    let lone_on = render(&shadowed, None).expect("gpu");
    keep("shadow_lone.png", &lone_on);
    let (mean, _) = lone_off.difference(&lone_on).expect("same size");
    assert!(mean < 0.5, "a lone sphere darkened by {mean:.2} on average");
}

#[test]
fn render_transparent_writes_alpha() {
    if !have_gpu() {
        return;
    }
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("t.png");
    let r = Command::new(env!("CARGO_BIN_EXE_mdsurf"))
        .args([
            "render",
            &data("1hpv.pdb"),
            "-o",
            out.to_str().expect("utf-8"),
            "--size",
            "160x120",
            "--backend",
            "cpu",
            "--look",
            "figure",
            "--transparent",
        ])
        .output()
        .expect("run mdsurf");
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let img = RgbaImage::read_png(&out).expect("png");
    keep("transparent.png", &img);
    for (x, y) in [(0, 0), (159, 0), (0, 119), (159, 119)] {
        assert_eq!(img.pixel(x, y)[3], 0, "background corner ({x}, {y})");
    }
    assert_eq!(img.pixel(80, 60)[3], 255, "centre of the molecule");
    let alphas: Vec<u8> = img.pixels.chunks_exact(4).map(|p| p[3]).collect();
    let opaque = alphas.iter().filter(|&&a| a == 255).count();
    assert!(opaque > 2000, "{opaque} opaque pixels");
}

#[test]
fn render_look_state_file_keeps_old_files_and_round_trips() {
    use mdsurf::scene::state_file::{LookError, LookState, StateFile, StateFileError};
    // A look section without the new fields loads and leaves the flags' values alone.
    let old = StateFile::parse(
        "version = 1\n[look]\nbackground = \"light\"\nambient_occlusion = 0.5\n",
        "old.toml",
    )
    .expect("old file loads");
    let mut s = RenderSettings::default();
    s.figure();
    old.look.apply(&mut s).expect("apply");
    assert_eq!(s.outline_width, mdsurf::render::settings::FIGURE_OUTLINE_PX);
    // The new fields round-trip.
    let look = RenderSettings {
        outline_width: 3.0,
        outline_colour: [1.0, 0.5, 0.0],
        shadows: 0.4,
        transparent_background: true,
        ..Default::default()
    };
    let mut state = StateFile::new(Vec::new());
    state.look = LookState::from_settings(&look);
    let back = StateFile::parse(&state.to_toml(), "saved.toml").expect("parse");
    let mut s = RenderSettings::default();
    back.look.apply(&mut s).expect("apply");
    assert_eq!(s, look);
    // Out-of-range values are refused.
    let bad = StateFile::parse("version = 1\n[look]\nshadows = 2.0\n", "bad.toml");
    let e = bad.unwrap_err();
    assert!(
        matches!(
            &e,
            StateFileError::Look {
                source: LookError::Setting { key: "shadows", .. },
                ..
            }
        ),
        "{e:?}"
    );
    assert!(e.to_string().contains("look.shadows"), "{e}");
}

/// Mean absolute Laplacian of the luminance over the pixels whose 3 x 3 neighbourhood is all
/// drawn and not outline: the pixel-to-pixel noise of the shading (sample patterns of the
/// occlusion and shadows show up here; smooth shading hardly does).
fn interior_noise(image: &RgbaImage) -> f64 {
    let (w, h) = (image.width as i64, image.height as i64);
    let mask = drawn(image);
    let lum = |x: i64, y: i64| luminance(image.pixel(x as u32, y as u32));
    let (mut sum, mut count) = (0.0, 0usize);
    for y in 1..h - 1 {
        for x in 1..w - 1 {
            // Drawn, and no outline (dark) pixel around: the shading only.
            let shaded = (-1..=1).all(|dy| {
                (-1..=1)
                    .all(|dx| mask[((y + dy) * w + x + dx) as usize] && lum(x + dx, y + dy) > 80.0)
            });
            if shaded {
                let l =
                    4.0 * lum(x, y) - lum(x - 1, y) - lum(x + 1, y) - lum(x, y - 1) - lum(x, y + 1);
                sum += l.abs();
                count += 1;
            }
        }
    }
    assert!(count > 1000, "only {count} interior pixels");
    sum / count as f64
}

#[test]
fn progressive_samples_smooth_the_figure_look() {
    // The figure look with ambient occlusion and full-strength shadows, where their sample
    // patterns show: a sphere with an atom between it and the key light.
    let l = Vec3::new(-0.4, 0.6, 0.7).normalize() * 9.0;
    let occluder = Some(([l.x, l.y, l.z], 2.5));
    let mut figure = RenderSettings {
        ambient_occlusion: 1.0,
        ..plain()
    };
    figure.figure();
    figure.shadows = 1.0;
    let Some(one) = render(&figure, occluder) else {
        return;
    };
    let high = render(
        &RenderSettings {
            samples: 16,
            ..figure
        },
        occluder,
    )
    .expect("gpu");
    keep("samples_1.png", &one);
    keep("samples_16.png", &high);
    let (noise_one, noise_high) = (interior_noise(&one), interior_noise(&high));
    assert!(
        noise_high < 0.6 * noise_one,
        "16 samples: pixel noise {noise_high:.2}, one sample {noise_one:.2}"
    );
    // The same picture on average: averaging smooths, it does not brighten or darken.
    let (mean, _) = one.difference(&high).expect("same size");
    assert!(
        mean < 4.0,
        "mean difference {mean:.2} between 1 and 16 samples"
    );
    // The background stays as it is.
    assert_eq!(one.pixel(0, 0), high.pixel(0, 0));
}
