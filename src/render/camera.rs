//! The orbit camera the renderer looks through: it circles a target point, pans in the view
//! plane, zooms along the view direction, fits a bounding box, and gives the view and projection
//! of each stereo eye (off-axis frusta whose zero-parallax plane is the focal plane). The app
//! turns mouse drags into calls here; headless renders set it up directly.

use glam::camera::rh::proj::directx;
use glam::{Mat4, Quat, Vec3};

/// One eye of a stereo pair.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Eye {
    /// The left eye (displaced towards the image's left).
    Left,
    /// The right eye.
    Right,
}

impl Eye {
    /// -1 for the left eye, +1 for the right eye.
    pub fn side(self) -> f32 {
        match self {
            Eye::Left => -1.0,
            Eye::Right => 1.0,
        }
    }
}

/// How 3D positions are projected onto the image.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Projection {
    /// Perspective with the camera's vertical field of view.
    #[default]
    Perspective,
    /// Parallel projection; the visible height matches the perspective view at the target.
    Orthographic,
}

/// An orbit camera around `target`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// Point the camera looks at and orbits around (Å).
    pub target: Vec3,
    /// Distance from the eye to the target (Å).
    pub distance: f32,
    /// Rotation about the vertical (y) axis in radians.
    pub yaw: f32,
    /// Elevation above the horizontal plane in radians, within about ±89°.
    pub pitch: f32,
    /// Vertical field of view in radians (perspective; also sets the orthographic height).
    pub fov_y: f32,
    /// Perspective or orthographic.
    pub projection: Projection,
    /// Radius of the scene's bounding sphere around `target` (Å); sets clip planes and depth cue.
    pub scene_radius: f32,
    /// The world direction shown upwards on screen (unit vector; +y by default, a membrane's
    /// normal in its side view). Yaw turns about it, pitch tilts towards it.
    pub vertical: Vec3,
}

impl Default for Camera {
    fn default() -> Self {
        Camera {
            target: Vec3::ZERO,
            distance: 50.0,
            yaw: 0.0,
            pitch: 0.0,
            fov_y: 35f32.to_radians(),
            projection: Projection::Perspective,
            scene_radius: 20.0,
            vertical: Vec3::Y,
        }
    }
}

const MAX_PITCH: f32 = 89.0 * std::f32::consts::PI / 180.0;

impl Camera {
    /// Centres the camera on the box `lo..hi` (Å) and backs off until the whole box is visible
    /// at any orbit angle, keeping the current direction and projection.
    pub fn fit(&mut self, lo: Vec3, hi: Vec3) {
        let centre = (lo + hi) * 0.5;
        let radius = ((hi - lo).length() * 0.5).max(1.0);
        self.target = centre;
        self.scene_radius = radius;
        // The bounding sphere touches the narrower of the two half-angles; assume a square-ish
        // view and leave 10 % margin.
        self.distance = radius / (self.fov_y * 0.5).sin() * 1.1;
    }

    /// Centres the camera on a sphere (centre and radius in Å) and backs off until it fills
    /// the view with a small margin, keeping the current direction and projection.
    pub fn fit_sphere(&mut self, centre: Vec3, radius: f32) {
        let radius = radius.max(1.0);
        self.target = centre;
        self.scene_radius = radius;
        self.distance = radius / (self.fov_y * 0.5).sin() * 1.05;
    }

    /// The rotation taking +y to [`Camera::vertical`] (yaw and pitch are measured in its frame).
    fn frame(&self) -> Quat {
        let v = self.vertical.normalize_or(Vec3::Y);
        Quat::from_rotation_arc(Vec3::Y, v)
    }

    /// Unit vector from the target towards the eye.
    pub fn back(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        self.frame() * Vec3::new(sy * cp, sp, cy * cp)
    }

    /// Looks at the scene from the side of a layer with normal `normal` (a membrane): the
    /// normal becomes the screen's vertical, the view horizontal (pitch 0), from the side
    /// `front` points to within the layer's plane (the protein's side; any side when `front`
    /// lies along the normal).
    pub fn side_view(&mut self, normal: Vec3, front: Vec3) {
        let Some(n) = normal.try_normalize() else {
            return;
        };
        self.vertical = n;
        self.pitch = 0.0;
        let local = self.frame().inverse() * (front - n * front.dot(n));
        self.yaw = if local.x.abs() + local.z.abs() > 1e-6 {
            local.x.atan2(local.z)
        } else {
            0.0
        };
    }

    /// Eye position in Å.
    pub fn eye(&self) -> Vec3 {
        self.target + self.back() * self.distance
    }

    /// Unit vector pointing right in the image.
    pub fn right(&self) -> Vec3 {
        let frame = self.frame();
        (frame * Vec3::Y)
            .cross(self.back())
            .normalize_or(frame * Vec3::X)
    }

    /// Unit vector pointing up in the image.
    pub fn up(&self) -> Vec3 {
        self.back().cross(self.right())
    }

    /// Rotates about the target: `dx` turns about the vertical axis, `dy` tilts (radians).
    pub fn orbit(&mut self, dx: f32, dy: f32) {
        self.yaw = (self.yaw - dx) % std::f32::consts::TAU;
        self.pitch = (self.pitch + dy).clamp(-MAX_PITCH, MAX_PITCH);
    }

    /// Moves target and eye in the view plane by a fraction of the visible height
    /// (`dx`, `dy` = pixels dragged / viewport height; right and up are positive).
    pub fn pan(&mut self, dx: f32, dy: f32) {
        let h = self.visible_height();
        self.target += (-self.right() * dx + self.up() * dy) * h;
    }

    /// Multiplies the distance by `factor` (< 1 moves closer), within sensible limits.
    pub fn zoom(&mut self, factor: f32) {
        if factor.is_finite() && factor > 0.0 {
            let min = (self.scene_radius * 0.05).max(0.5);
            let max = self.scene_radius * 50.0 + 100.0;
            self.distance = (self.distance * factor).clamp(min, max);
        }
    }

    /// Height of the view at the target's depth, in Å.
    pub fn visible_height(&self) -> f32 {
        2.0 * self.distance * (self.fov_y * 0.5).tan()
    }

    /// World-to-view matrix (right-handed, looking down -z).
    pub fn view_matrix(&self) -> Mat4 {
        let vertical = self.frame() * Vec3::Y;
        glam::camera::rh::view::look_at_mat4(self.eye(), self.target, vertical)
    }

    /// Near and far clip distances in Å, enclosing the scene's bounding sphere.
    pub fn clip_range(&self) -> (f32, f32) {
        let r = self.scene_radius.max(1.0) * 1.5;
        let far = self.distance + r;
        let near = (self.distance - r).max(far * 1e-3);
        (near, far)
    }

    /// View-to-clip matrix for an image of `aspect` = width / height (depth 0 near, 1 far).
    pub fn projection_matrix(&self, aspect: f32) -> Mat4 {
        let aspect = if aspect.is_finite() && aspect > 0.0 {
            aspect
        } else {
            1.0
        };
        let (near, far) = self.clip_range();
        match self.projection {
            Projection::Perspective => directx::perspective(self.fov_y, aspect, near, far),
            Projection::Orthographic => {
                let h = self.visible_height() * 0.5;
                let w = h * aspect;
                directx::orthographic(-w, w, -h, h, near, far)
            }
        }
    }

    /// View and projection matrices of the camera itself (no stereo) for an image of `aspect`.
    pub fn matrices(&self, aspect: f32) -> (Mat4, Mat4) {
        (self.view_matrix(), self.projection_matrix(aspect))
    }

    /// Distance from the camera to the stereo focal (zero-parallax) plane in Å: `focal` when it
    /// is finite and positive, else the distance to the target.
    pub fn focal_distance(&self, focal: Option<f32>) -> f32 {
        focal
            .filter(|f| f.is_finite() && *f > 0.0)
            .unwrap_or(self.distance)
    }

    /// View and projection matrices of one stereo eye for an image (or half image) of `aspect`.
    ///
    /// `separation` is the distance between the eyes as a fraction of the focal distance
    /// ([`Camera::focal_distance`] of `focal`). Perspective: the eyes sit `±separation / 2 *
    /// focal` along [`Camera::right`] with axes parallel to the camera's, and each frustum is
    /// shifted sideways (off-axis) so both frusta share the camera's window on the focal plane:
    /// points on that plane land on the same pixel in both eyes, nearer points have crossed
    /// parallax, farther ones uncrossed. Orthographic (where a sideways shift gives no
    /// parallax): each eye turns by `±separation / 2` radians about the camera's up axis through
    /// the focal point (toe-in), which gives the same parallax signs.
    pub fn eye_matrices(
        &self,
        eye: Eye,
        separation: f32,
        focal: Option<f32>,
        aspect: f32,
    ) -> (Mat4, Mat4) {
        let sep = if separation.is_finite() {
            separation.max(0.0)
        } else {
            0.0
        };
        let aspect = if aspect.is_finite() && aspect > 0.0 {
            aspect
        } else {
            1.0
        };
        let f = self.focal_distance(focal);
        let (back, right, up) = (self.back(), self.right(), self.up());
        let eye_pos = self.eye();
        match self.projection {
            Projection::Perspective => {
                let d = eye.side() * sep * 0.5 * f;
                let pos = eye_pos + right * d;
                let view = glam::camera::rh::view::look_to_mat4(pos, -back, up);
                // The camera's axis at the focal depth is at x = -d in this eye's view space;
                // shift the image so it lands in the centre (an off-axis frustum).
                let half_w = f * (self.fov_y * 0.5).tan() * aspect;
                let shift = Mat4::from_translation(Vec3::new(d / half_w, 0.0, 0.0));
                (view, shift * self.projection_matrix(aspect))
            }
            Projection::Orthographic => {
                let pivot = eye_pos - back * f;
                let turn = Quat::from_axis_angle(up, eye.side() * sep * 0.5);
                let pos = pivot + turn * (back * f);
                let view = glam::camera::rh::view::look_to_mat4(pos, -(turn * back), up);
                (view, self.projection_matrix(aspect))
            }
        }
    }

    /// Spins the camera about the vertical axis by `degrees` (turntable step).
    pub fn turn(&mut self, degrees: f32) {
        self.yaw = (self.yaw + degrees.to_radians()) % std::f32::consts::TAU;
    }
}

/// A sphere around `points` (Å): the centre of their bounding box and the largest distance from
/// it; tighter than the box for round molecules. `None` when there are no finite points.
pub fn bounding_sphere<'a>(
    points: impl IntoIterator<Item = &'a Vec3> + Clone,
) -> Option<(Vec3, f32)> {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for p in points.clone().into_iter().filter(|p| p.is_finite()) {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    if !(lo.is_finite() && hi.is_finite()) {
        return None;
    }
    let centre = (lo + hi) * 0.5;
    let r2 = points
        .into_iter()
        .filter(|p| p.is_finite())
        .map(|p| p.distance_squared(centre))
        .fold(0.0f32, f32::max);
    Some((centre, r2.sqrt()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fit_puts_box_centre_at_target_and_whole_box_in_view() {
        let mut c = Camera::default();
        c.fit(Vec3::new(-10.0, 0.0, 0.0), Vec3::new(30.0, 20.0, 10.0));
        assert_eq!(c.target, Vec3::new(10.0, 10.0, 5.0));
        let vp = c.projection_matrix(1.0) * c.view_matrix();
        for corner in [Vec3::new(-10.0, 0.0, 0.0), Vec3::new(30.0, 20.0, 10.0)] {
            let p = vp.project_point3(corner);
            assert!(
                p.x.abs() < 1.0 && p.y.abs() < 1.0 && (0.0..1.0).contains(&p.z),
                "{p}"
            );
        }
    }

    #[test]
    fn sphere_fit_keeps_every_point_in_view_from_any_side() {
        let pts: Vec<Vec3> = (0..200)
            .map(|i| {
                let t = i as f32 * 0.37;
                Vec3::new(t.cos(), (t * 1.3).sin(), (t * 0.7).cos()) * 10.0
                    + Vec3::new(5.0, -3.0, 2.0)
            })
            .collect();
        let (c, r) = bounding_sphere(&pts).expect("points");
        assert!(pts.iter().all(|p| p.distance(c) <= r + 1e-4));
        let mut cam = Camera::default();
        cam.fit_sphere(c, r);
        for yaw in [0.0f32, 1.0, 2.5, 4.0] {
            cam.yaw = yaw;
            let vp = cam.projection_matrix(1.0) * cam.view_matrix();
            for p in &pts {
                let q = vp.project_point3(*p);
                assert!(
                    q.x.abs() < 1.0 && q.y.abs() < 1.0 && (0.0..1.0).contains(&q.z),
                    "{q}"
                );
            }
        }
        assert!(bounding_sphere(&[]).is_none());
    }

    #[test]
    fn orbit_keeps_distance_and_clamps_pitch() {
        let mut c = Camera::default();
        let d0 = (c.eye() - c.target).length();
        c.orbit(0.7, 10.0);
        assert!(((c.eye() - c.target).length() - d0).abs() < 1e-3);
        assert!(c.pitch <= MAX_PITCH);
    }

    /// Pixel x of `p` (Å) in an image `width` pixels wide seen through `(view, proj)`.
    fn pixel_x(m: (Mat4, Mat4), p: Vec3, width: f32) -> f32 {
        let ndc = (m.1 * m.0).project_point3(p);
        (ndc.x + 1.0) * 0.5 * width
    }

    fn cameras() -> Vec<Camera> {
        let mut c = Camera::default();
        c.fit_sphere(Vec3::new(3.0, -2.0, 7.0), 25.0);
        c.orbit(0.8, 0.4);
        let mut o = c;
        o.projection = Projection::Orthographic;
        vec![c, o]
    }

    #[test]
    fn target_lands_on_the_same_pixel_in_both_eyes() {
        for c in cameras() {
            for focal in [None, Some(c.distance)] {
                let l = c.eye_matrices(Eye::Left, 1.0 / 30.0, focal, 4.0 / 3.0);
                let r = c.eye_matrices(Eye::Right, 1.0 / 30.0, focal, 4.0 / 3.0);
                let (xl, xr) = (pixel_x(l, c.target, 800.0), pixel_x(r, c.target, 800.0));
                assert!((xl - xr).abs() < 0.5, "{:?}: {xl} vs {xr}", c.projection);
                assert!((xl - 400.0).abs() < 0.5, "target in the centre: {xl}");
                let (pl, pr) = (
                    (l.1 * l.0).project_point3(c.target),
                    (r.1 * r.0).project_point3(c.target),
                );
                assert!((pl.y - pr.y).abs() < 1e-4, "no vertical parallax");
            }
        }
    }

    #[test]
    fn nearer_points_have_crossed_parallax_farther_ones_uncrossed() {
        for c in cameras() {
            let l = c.eye_matrices(Eye::Left, 1.0 / 30.0, None, 1.5);
            let r = c.eye_matrices(Eye::Right, 1.0 / 30.0, None, 1.5);
            let off = c.right() * 4.0 + c.up() * 3.0;
            let near = c.target + c.back() * c.scene_radius * 0.8 + off;
            let far = c.target - c.back() * c.scene_radius * 0.8 + off;
            let parallax = |p| pixel_x(r, p, 900.0) - pixel_x(l, p, 900.0);
            // Crossed: the left eye's image is right of the right eye's (negative parallax).
            assert!(
                parallax(near) < -2.0,
                "{:?} near: {}",
                c.projection,
                parallax(near)
            );
            assert!(
                parallax(far) > 2.0,
                "{:?} far: {}",
                c.projection,
                parallax(far)
            );
        }
    }

    #[test]
    fn focal_distance_moves_the_zero_parallax_plane() {
        let c = cameras()[0];
        let focal = c.distance - 10.0;
        let l = c.eye_matrices(Eye::Left, 0.05, Some(focal), 1.0);
        let r = c.eye_matrices(Eye::Right, 0.05, Some(focal), 1.0);
        let on_plane = c.eye() - c.back() * focal + c.right() * 5.0;
        assert!((pixel_x(l, on_plane, 600.0) - pixel_x(r, on_plane, 600.0)).abs() < 0.5);
        // The target is now behind the focal plane: uncrossed.
        assert!(pixel_x(r, c.target, 600.0) - pixel_x(l, c.target, 600.0) > 1.0);
        // Invalid focal distances fall back to the target.
        assert_eq!(c.focal_distance(Some(f32::NAN)), c.distance);
        assert_eq!(c.focal_distance(Some(-3.0)), c.distance);
    }

    #[test]
    fn eyes_are_separated_along_right_by_the_fraction_of_the_focal_distance() {
        let c = cameras()[0];
        let pos = |m: (Mat4, Mat4)| m.0.inverse().transform_point3(Vec3::ZERO);
        let l = pos(c.eye_matrices(Eye::Left, 0.06, None, 1.0));
        let r = pos(c.eye_matrices(Eye::Right, 0.06, None, 1.0));
        let d = r - l;
        assert!((d.length() - 0.06 * c.distance).abs() < 1e-2, "{d}");
        assert!(d.normalize().dot(c.right()) > 0.999);
        // Zero separation is the mono camera.
        let (v, p) = c.eye_matrices(Eye::Left, 0.0, None, 1.0);
        assert!(v.abs_diff_eq(c.view_matrix(), 1e-4));
        assert!(p.abs_diff_eq(c.projection_matrix(1.0), 1e-6));
    }
}
