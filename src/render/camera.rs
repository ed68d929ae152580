//! The orbit camera the renderer looks through: it circles a target point, pans in the view
//! plane, zooms along the view direction, fits a bounding box, and offsets itself for stereo
//! eyes. The app turns mouse drags into calls here; headless renders set it up directly.

use glam::camera::rh::proj::directx;
use glam::{Mat4, Vec3};

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

    /// Unit vector from the target towards the eye.
    pub fn back(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        Vec3::new(sy * cp, sp, cy * cp)
    }

    /// Eye position in Å.
    pub fn eye(&self) -> Vec3 {
        self.target + self.back() * self.distance
    }

    /// Unit vector pointing right in the image.
    pub fn right(&self) -> Vec3 {
        Vec3::Y.cross(self.back()).normalize_or(Vec3::X)
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
        glam::camera::rh::view::look_at_mat4(self.eye(), self.target, Vec3::Y)
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

    /// The camera of one stereo eye: moved sideways by `side * separation / 2`, where
    /// `separation` is a fraction of the viewing distance and `side` is -1 (left) or +1 (right).
    /// Both eyes look parallel, so the target stays at the same depth.
    pub fn eye_camera(&self, side: f32, separation: f32) -> Camera {
        let mut c = *self;
        c.target += self.right() * side * separation * 0.5 * self.distance;
        c
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

    #[test]
    fn eyes_are_separated_along_right() {
        let c = Camera::default();
        let l = c.eye_camera(-1.0, 0.06);
        let r = c.eye_camera(1.0, 0.06);
        let d = r.eye() - l.eye();
        assert!((d.length() - 0.06 * c.distance).abs() < 1e-3);
        assert!(d.normalize().dot(c.right()) > 0.999);
    }
}
