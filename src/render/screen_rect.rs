//! Where a box around part of the scene lies seen through an eye's matrices. The part of the
//! viewport it can cover, in pixels: the full-screen passes after the opaque scene (ambient
//! occlusion, outlines, shadows) are clipped to it with a scissor, so that the empty background
//! around a molecule is not shaded at all. And whether it lies wholly beyond the near plane:
//! then no cut opens a closed surface inside it, and its back faces need not be drawn.

use glam::{Mat4, Vec3, Vec4};

/// The pixel rectangle `[x, y, width, height]` of `viewport` (pixels) that the box `bounds` (Å)
/// covers seen through `view_proj`, widened by `margin` pixels on every side.
/// - The whole viewport when there is no box or when a corner of the box lies at or behind the
///   eye (its projection has no bound on screen).
/// - `None` when the box lies entirely outside the viewport: nothing there to shade.
pub(crate) fn covered_rect(
    bounds: Option<(Vec3, Vec3)>,
    view_proj: Mat4,
    viewport: [u32; 4],
    margin: f32,
) -> Option<[u32; 4]> {
    let [vx, vy, vw, vh] = viewport;
    let Some((lo, hi)) = bounds else {
        return Some(viewport);
    };
    // Pixel corners of the box's projection: x right, y down, as the viewport counts them.
    let (mut min, mut max) = ([f32::INFINITY; 2], [f32::NEG_INFINITY; 2]);
    for corner in 0..8 {
        let p = Vec3::new(
            if corner & 1 == 0 { lo.x } else { hi.x },
            if corner & 2 == 0 { lo.y } else { hi.y },
            if corner & 4 == 0 { lo.z } else { hi.z },
        );
        let clip: Vec4 = view_proj * p.extend(1.0);
        if clip.w <= 1e-6 || !clip.is_finite() {
            return Some(viewport);
        }
        let px = [
            vx as f32 + (clip.x / clip.w * 0.5 + 0.5) * vw as f32,
            vy as f32 + (0.5 - clip.y / clip.w * 0.5) * vh as f32,
        ];
        for a in 0..2 {
            min[a] = min[a].min(px[a]);
            max[a] = max[a].max(px[a]);
        }
    }
    let clamp_x = |v: f32| (v.max(vx as f32).min((vx + vw) as f32)) as u32;
    let clamp_y = |v: f32| (v.max(vy as f32).min((vy + vh) as f32)) as u32;
    let (x0, x1) = (
        clamp_x((min[0] - margin).floor()),
        clamp_x((max[0] + margin).ceil()),
    );
    let (y0, y1) = (
        clamp_y((min[1] - margin).floor()),
        clamp_y((max[1] + margin).ceil()),
    );
    (x1 > x0 && y1 > y0).then_some([x0, y0, x1 - x0, y1 - y0])
}

/// True when the box `bounds` (Å) lies wholly beyond the near clip plane of `view_proj` (depth 0
/// near, 1 far), so that the plane cuts nothing inside it; false without a box.
pub(crate) fn beyond_near_plane(bounds: Option<(Vec3, Vec3)>, view_proj: Mat4) -> bool {
    let Some((lo, hi)) = bounds else {
        return false;
    };
    (0..8).all(|corner| {
        let p = Vec3::new(
            if corner & 1 == 0 { lo.x } else { hi.x },
            if corner & 2 == 0 { lo.y } else { hi.y },
            if corner & 4 == 0 { lo.z } else { hi.z },
        );
        let clip: Vec4 = view_proj * p.extend(1.0);
        clip.is_finite() && clip.w > 1e-6 && clip.z > 1e-6 * clip.w
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const VIEWPORT: [u32; 4] = [100, 0, 400, 200];

    /// The window's camera fitted to a 2 Å cube at the origin, 20 Å away (aspect 2).
    fn camera(distance: f32) -> Mat4 {
        let mut camera = crate::render::Camera::default();
        camera.fit(Vec3::splat(-1.0), Vec3::splat(1.0));
        camera.distance = distance;
        let (view, proj) = camera.matrices(2.0);
        proj * view
    }

    #[test]
    fn a_small_box_covers_a_rectangle_around_its_projection() {
        let vp = camera(20.0);
        let (lo, hi) = (Vec3::splat(-1.0), Vec3::splat(1.0));
        let [x, y, w, h] = covered_rect(Some((lo, hi)), vp, VIEWPORT, 3.0).unwrap();
        // Every corner's pixel lies inside, at least the margin away from the edges.
        for corner in [
            lo,
            hi,
            Vec3::new(lo.x, hi.y, lo.z),
            Vec3::new(hi.x, lo.y, hi.z),
        ] {
            let c = vp * corner.extend(1.0);
            let px = 100.0 + (c.x / c.w * 0.5 + 0.5) * 400.0;
            let py = (0.5 - c.y / c.w * 0.5) * 200.0;
            assert!(
                px - 3.0 >= x as f32 && px + 3.0 <= (x + w) as f32,
                "{px} in {x}+{w}"
            );
            assert!(
                py - 3.0 >= y as f32 && py + 3.0 <= (y + h) as f32,
                "{py} in {y}+{h}"
            );
        }
        // And it is much smaller than the viewport, centred in it.
        assert!(w < 100 && h < 100, "{w}x{h}");
        assert!((x as f32 + w as f32 / 2.0 - 300.0).abs() <= 1.0);
    }

    #[test]
    fn a_box_around_the_eye_or_none_takes_the_viewport_and_one_off_screen_nothing() {
        let vp = camera(20.0);
        let around = (Vec3::splat(-30.0), Vec3::splat(30.0));
        assert_eq!(
            covered_rect(Some(around), vp, VIEWPORT, 2.0),
            Some(VIEWPORT)
        );
        assert_eq!(covered_rect(None, vp, VIEWPORT, 2.0), Some(VIEWPORT));
        // Far to the side: outside the viewport, so nothing to shade.
        let aside = (Vec3::new(200.0, -1.0, -1.0), Vec3::new(202.0, 1.0, 1.0));
        assert_eq!(covered_rect(Some(aside), vp, VIEWPORT, 2.0), None);
    }

    #[test]
    fn only_a_box_wholly_past_the_near_plane_is_beyond_it() {
        let cube = Some((Vec3::splat(-1.0), Vec3::splat(1.0)));
        assert!(beyond_near_plane(cube, camera(20.0)));
        // The eye inside the box (zoomed into it): not beyond.
        assert!(!beyond_near_plane(
            Some((Vec3::splat(-30.0), Vec3::splat(30.0))),
            camera(20.0)
        ));
        assert!(!beyond_near_plane(cube, camera(0.5)));
        // The near plane through the box, the eye outside it.
        let (view, _) = crate::render::Camera::default().matrices(2.0);
        let eye_z = (view * Vec3::ZERO.extend(1.0)).z;
        let proj = glam::camera::rh::proj::directx::perspective(1.0, 2.0, -eye_z, 100.0);
        let cube_at_origin = Some((Vec3::splat(-1.0), Vec3::splat(1.0)));
        assert!(!beyond_near_plane(cube_at_origin, proj * view));
        assert!(!beyond_near_plane(None, camera(20.0)));
    }
}
