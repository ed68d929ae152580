//! The window's progressive samples ([`StillView`], issue 31): while the view stays still each
//! draw adds one of the look's samples, and after all of them the window shows the very picture
//! a screenshot of the same view gives (`render_to_rgba`, which averages on the same GPU path);
//! a camera move starts again from one sample; the default look (one sample) is the plain draw.
//! Needs a wgpu adapter, as tests/it/render_images.rs.

use mdsurf::render::{
    Camera, RenderSettings, Renderer, RgbaImage, StillView, read_texture, render_to_rgba,
};

use crate::render_images::gpu;
use crate::render_look::{plain, sphere_scene};

const SIZE: [u32; 2] = [160, 160];

/// The figure look with full shadows, whose sample patterns show.
fn figure(samples: u32) -> RenderSettings {
    let mut s = RenderSettings {
        ambient_occlusion: 1.0,
        samples,
        ..plain()
    };
    s.figure();
    s.shadows = 1.0;
    s
}

#[test]
fn still_view_converges_to_the_screenshot_and_restarts_on_a_move() {
    let Some(g) = gpu() else { return };
    let renderer = Renderer::new(&g.device);
    let occluder = Some(([-2.9, 4.4, 5.1], 2.5));
    let (scene, mut camera) = sphere_scene(&g, occluder);
    let shown = |view: &StillView| -> RgbaImage {
        let (texture, _) = view.shown().expect("drawn");
        read_texture(&g.device, &g.queue, texture).expect("read back")
    };
    let screenshot = |settings: &RenderSettings, camera: &Camera| {
        render_to_rgba(
            &g.device, &g.queue, &renderer, &scene, camera, settings, SIZE,
        )
        .expect("render")
    };
    let settings = figure(8);
    let mut view = StillView::default();
    let draw = |view: &mut StillView, camera: &Camera, changed: bool| {
        view.draw(
            &g.device, &g.queue, &renderer, &scene, camera, &settings, SIZE, changed,
        )
    };
    let first = draw(&mut view, &camera, true);
    assert!(first.new_texture && first.more, "{first:?}");
    let one_sample = shown(&view);
    for k in 2..=8 {
        let d = draw(&mut view, &camera, false);
        assert!(!d.new_texture, "sample {k}: {d:?}");
        assert_eq!(d.more, k < 8, "sample {k}");
        assert_eq!(view.samples_shown(), k);
    }
    let converged = shown(&view);
    assert_eq!(
        converged.pixels,
        screenshot(&settings, &camera).pixels,
        "after 8 still draws the window differs from the 8-sample screenshot"
    );
    // The samples did something: the mean differs from the first sample.
    let (mean, _) = one_sample.difference(&converged).expect("same size");
    assert!(
        mean > 0.05,
        "8 samples equal 1 sample (mean difference {mean:.3})"
    );
    // Still after the last sample: nothing more is drawn.
    let idle = draw(&mut view, &camera, false);
    assert!(!idle.more && view.samples_shown() == 8, "{idle:?}");
    assert_eq!(shown(&view).pixels, converged.pixels);
    // A changed scene starts again.
    draw(&mut view, &camera, true);
    assert_eq!(view.samples_shown(), 1);
    // A camera move starts again from one sample: the first sample of the new view.
    camera.orbit(0.3, 0.0);
    let moved = draw(&mut view, &camera, false);
    assert!(moved.more && view.samples_shown() == 1, "{moved:?}");
    let single = screenshot(&figure(1), &camera);
    let (mean, frac) = single.difference(&shown(&view)).expect("same size");
    assert!(
        mean < 0.5 && frac < 0.001,
        "one sample of the moved view differs from its plain draw: mean {mean:.3}, {frac:.4} outliers"
    );
}

#[test]
fn default_look_draws_once_and_shows_the_plain_picture() {
    let Some(g) = gpu() else { return };
    let renderer = Renderer::new(&g.device);
    let (scene, camera) = sphere_scene(&g, None);
    let settings = figure(1);
    let mut view = StillView::default();
    let d = view.draw(
        &g.device, &g.queue, &renderer, &scene, &camera, &settings, SIZE, true,
    );
    assert!(d.new_texture && !d.more, "{d:?}");
    let (texture, _) = view.shown().expect("drawn");
    let image = read_texture(&g.device, &g.queue, texture).expect("read back");
    let plain = render_to_rgba(
        &g.device, &g.queue, &renderer, &scene, &camera, &settings, SIZE,
    )
    .expect("render");
    assert_eq!(image.pixels, plain.pixels);
}
