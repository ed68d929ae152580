//! The per-view uniform block every render pass reads (`View` in shaders/render_view.wgsl): the
//! camera's matrices, the key light, the look's strengths and the viewport, filled from a
//! [`Camera`] and [`RenderSettings`] for one eye.

use glam::{Mat4, Vec3};

use super::camera::{Camera, Projection};
use super::settings::{MAX_OUTLINE_PX, RenderSettings};

/// Direction towards the key light in view space (unnormalised): above, left and in front.
const KEY_LIGHT: Vec3 = Vec3::new(-0.4, 0.6, 0.7);

/// Per-view uniforms. Twin of `View` in shaders/render_view.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct ViewUniform {
    view: [[f32; 4]; 4],
    proj: [[f32; 4]; 4],
    light_dir: [f32; 4],
    light_across: [f32; 4],
    light_up: [f32; 4],
    background: [f32; 4],
    fog: [f32; 4],
    surface: [f32; 4],
    surface_colour: [f32; 4],
    misc: [f32; 4],
    ao: [f32; 4],
    viewport: [f32; 4],
    unproject_px: [f32; 4],
    unproject_z: [f32; 4],
    look: [f32; 4],
    outline_colour: [f32; 4],
}

const _: () = assert!(std::mem::size_of::<ViewUniform>() == 352);

impl ViewUniform {
    /// Uniforms for `camera` seen through `view` and `proj` (the camera's own matrices, or one
    /// stereo eye's) into `viewport`.
    pub(crate) fn new(
        camera: &Camera,
        (view, proj): (Mat4, Mat4),
        viewport: [u32; 4],
        settings: &RenderSettings,
    ) -> Self {
        let (near, far) = camera.clip_range();
        // A progressive sample's sub-pixel camera offset: the projection moved in clip space.
        let [jx, jy] = RenderSettings::sample_offset(settings.sample);
        let proj = if settings.sample == 0 {
            proj
        } else {
            let (w, h) = (viewport[2].max(1) as f32, viewport[3].max(1) as f32);
            Mat4::from_translation(Vec3::new(2.0 * jx / w, 2.0 * jy / h, 0.0)) * proj
        };
        let bg = settings.background.linear_rgb();
        // Depth cue from the front to the back of the scene's bounding sphere.
        let r = camera.scene_radius.max(1.0);
        let (cue_start, cue_end) = (camera.distance - r * 0.5, camera.distance + r);
        let ortho = if camera.projection == Projection::Orthographic {
            1.0
        } else {
            0.0
        };
        let (unproject_px, unproject_z) = unprojection(proj, viewport);
        let light = KEY_LIGHT.normalize();
        // Two unit vectors across the light (the shadow rays' cone), the same for every pixel.
        let across = light.any_orthogonal_vector().normalize();
        let up = light.cross(across);
        let oc = settings.outline_colour;
        let (single, sc) = match settings.surface_colour {
            Some(c) => (1.0, c),
            None => (0.0, [1.0; 3]),
        };
        ViewUniform {
            view: view.to_cols_array_2d(),
            proj: proj.to_cols_array_2d(),
            light_dir: [light.x, light.y, light.z, 0.0],
            light_across: [across.x, across.y, across.z, 0.0],
            light_up: [up.x, up.y, up.z, 0.0],
            background: [bg[0], bg[1], bg[2], 1.0],
            fog: [
                cue_start,
                cue_end,
                settings.depth_cue.clamp(0.0, 1.0),
                ortho,
            ],
            surface: [settings.surface_opacity.clamp(0.0, 1.0), single, 0.0, 0.0],
            surface_colour: [sc[0], sc[1], sc[2], 1.0],
            // w: the progressive sample's turn of the AO and shadow patterns (0 to 1).
            misc: [
                0.35,
                near,
                far,
                (settings.sample as f32 * 0.618_034).fract(),
            ],
            ao: [
                settings.ambient_occlusion.clamp(0.0, 1.0),
                AO_RADIUS,
                viewport[3] as f32,
                0.0,
            ],
            viewport: viewport.map(|v| v as f32),
            unproject_px,
            unproject_z,
            look: [
                settings.outline_width.clamp(0.0, MAX_OUTLINE_PX),
                settings.shadows.clamp(0.0, 1.0),
                SHADOW_REACH,
                0.0,
            ],
            outline_colour: [oc[0], oc[1], oc[2], 1.0],
        }
    }
}

/// Reach of the screen-space ambient occlusion in Å (about one atom diameter).
pub const AO_RADIUS: f32 = 3.0;
/// How far towards the key light the screen-space shadow rays look for an occluder, in Å.
pub const SHADOW_REACH: f32 = 12.0;

/// The coefficients that take a render-target pixel at view depth `zv` back to view space
/// (`view_at` in shaders/render_look.wgsl): `proj` maps view x to clip x as
/// `P00 x + P20 zv + P30` (y likewise), with `w = P23 zv + P33`, and the pixel to
/// normalised device coordinates linearly, so view x = `(px sx + tx) w - ax zv - bx`.
/// Returns `[sx, sy, tx, ty]` and `[ax, ay, bx, by]`; Å per pixel at w = 1 and Å.
fn unprojection(proj: Mat4, viewport: [u32; 4]) -> ([f32; 4], [f32; 4]) {
    let [x, y, w, h] = viewport.map(|v| v as f32);
    let (w, h) = (w.max(1.0), h.max(1.0));
    // Pixel to normalised device coordinates: ndc = px * scale + offset (y grows upwards).
    let scale = [2.0 / w, -2.0 / h];
    let offset = [-2.0 * x / w - 1.0, 1.0 + 2.0 * y / h];
    let diagonal = [proj.x_axis.x, proj.y_axis.y];
    let (z_col, t_col) = (proj.z_axis, proj.w_axis);
    (
        [
            scale[0] / diagonal[0],
            scale[1] / diagonal[1],
            offset[0] / diagonal[0],
            offset[1] / diagonal[1],
        ],
        [
            z_col.x / diagonal[0],
            z_col.y / diagonal[1],
            t_col.x / diagonal[0],
            t_col.y / diagonal[1],
        ],
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// View point → pixel (through `proj` and the viewport) → view point again through the
    /// coefficients, as `view_at` in shaders/render_look.wgsl computes it.
    fn round_trip(proj: Mat4, viewport: [u32; 4], point: Vec3) -> Vec3 {
        let clip = proj * point.extend(1.0);
        let ndc = clip.truncate() / clip.w;
        let [x, y, w, h] = viewport.map(|v| v as f32);
        let px = [x + (ndc.x + 1.0) * 0.5 * w, y + (1.0 - ndc.y) * 0.5 * h];
        let (s, z) = unprojection(proj, viewport);
        let zv = point.z;
        let cw = proj.z_axis.w * zv + proj.w_axis.w;
        Vec3::new(
            (px[0] * s[0] + s[2]) * cw - z[0] * zv - z[2],
            (px[1] * s[1] + s[3]) * cw - z[1] * zv - z[3],
            zv,
        )
    }

    #[test]
    fn unprojection_takes_pixels_back_to_the_view_point() {
        let camera = Camera {
            distance: 120.0,
            scene_radius: 40.0,
            ..Camera::default()
        };
        let perspective = camera.projection_matrix(16.0 / 9.0);
        let orthographic = Camera {
            projection: Projection::Orthographic,
            ..camera
        }
        .projection_matrix(16.0 / 9.0);
        // A progressive sample's shift, and a stereo eye's off-axis frustum.
        let shifted = Mat4::from_translation(Vec3::new(0.003, -0.002, 0.0)) * perspective;
        let (_, eye) = camera.eye_matrices(super::super::camera::Eye::Left, 0.05, None, 0.9);
        let points = [
            Vec3::new(3.0, -2.0, -60.0),
            Vec3::new(-20.0, 11.0, -150.0),
            Vec3::new(0.5, 0.25, -90.0),
        ];
        for proj in [perspective, orthographic, shifted, eye] {
            for viewport in [[0, 0, 1920, 1080], [960, 0, 960, 1080]] {
                for p in points {
                    let back = round_trip(proj, viewport, p);
                    assert!(
                        (back - p).length() < 1e-3 * p.z.abs(),
                        "{p} came back as {back} ({proj:?}, {viewport:?})"
                    );
                }
            }
        }
    }
}
