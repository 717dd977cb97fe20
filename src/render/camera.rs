//! An orbit camera: a target point, a distance and two angles. The
//! viewer's mouse turns, pans and zooms it; a scene's camera seeds it.

use glam::{DVec3, Mat4, Vec3};

use crate::scene::file::Camera;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrbitCamera {
    pub target: DVec3,
    pub distance: f64,
    /// Radians about +Y (up, as in glTF).
    pub yaw: f64,
    /// Radians above the horizontal.
    pub pitch: f64,
    /// Vertical field of view, degrees.
    pub fov: f64,
    /// The scene's size, for the depth range.
    pub radius: f64,
}

impl OrbitCamera {
    /// Looking at bounds `lo..hi` from the front, slightly above and to
    /// the side, the whole box in view.
    pub fn fit(lo: DVec3, hi: DVec3) -> OrbitCamera {
        let radius = ((hi - lo).length() / 2.0).max(1e-9);
        let fov: f64 = 40.0;
        OrbitCamera {
            target: (lo + hi) / 2.0,
            distance: radius / (fov.to_radians() / 2.0).sin() * 1.1,
            yaw: 0.35,
            pitch: 0.3,
            fov,
            radius,
        }
    }

    /// The camera a scene opens with: its first camera, else a view of
    /// the whole of `bounds`.
    pub fn for_scene(cameras: &[Camera], bounds: Option<(DVec3, DVec3)>) -> OrbitCamera {
        let (lo, hi) = bounds.unwrap_or((DVec3::splat(-1.0), DVec3::splat(1.0)));
        match cameras.first() {
            Some(c) => OrbitCamera::from_scene(c, (hi - lo).length() / 2.0),
            None => OrbitCamera::fit(lo, hi),
        }
    }

    /// The scene file's camera, `radius` the scene's size.
    pub fn from_scene(camera: &Camera, radius: f64) -> OrbitCamera {
        let eye = DVec3::from_array(camera.position);
        let target = DVec3::from_array(camera.look_at);
        let d = eye - target;
        let distance = d.length().max(1e-9);
        OrbitCamera {
            target,
            distance,
            yaw: d.x.atan2(d.z),
            pitch: (d.y / distance).clamp(-1.0, 1.0).asin(),
            fov: camera.fov,
            radius: radius.max(distance * 1e-3),
        }
    }

    pub fn eye(&self) -> DVec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        self.target + DVec3::new(sy * cp, sp, cy * cp) * self.distance
    }

    /// Unit vectors to the right of and up from the view direction.
    pub fn right_up(&self) -> (DVec3, DVec3) {
        let forward = (self.target - self.eye()).normalize();
        let right = forward.cross(DVec3::Y).normalize_or(DVec3::X);
        (right, right.cross(forward))
    }

    /// Object units a pixel spans at the target, on a viewport `height`
    /// pixels tall.
    pub fn units_per_pixel(&self, height: f64) -> f64 {
        2.0 * self.distance * (self.fov.to_radians() / 2.0).tan() / height.max(1.0)
    }

    pub fn view_proj(&self, aspect: f64) -> Mat4 {
        let eye = self.eye().as_vec3();
        let view = glam::camera::rh::view::look_at_mat4(eye, self.target.as_vec3(), Vec3::Y);
        let far = (self.distance + 2.0 * self.radius) as f32;
        let near = (self.distance - 2.0 * self.radius).max(far as f64 * 1e-4) as f32;
        // WebGPU's clip space: depth 0..1, y up (glam's "directx").
        glam::camera::rh::proj::directx::perspective(
            self.fov.to_radians() as f32,
            aspect as f32,
            near,
            far,
        ) * view
    }

    /// From clip space (x, y from -1 at the left and bottom to 1, depth
    /// from 0 at the near plane to 1 at the far one) back to the scene, on
    /// a view `aspect` wide to high: `project_point3` of its result.
    pub fn unprojection(&self, aspect: f64) -> glam::DMat4 {
        self.view_proj(aspect).as_dmat4().inverse()
    }

    /// The ray from the eye through a point of the view: `x` and `y` from
    /// -1 (left, bottom) to 1 (right, top), on a view `aspect` wide to
    /// high. Origin and unit direction.
    pub fn ray(&self, x: f64, y: f64, aspect: f64) -> (DVec3, DVec3) {
        let inverse = self.unprojection(aspect);
        let near = inverse.project_point3(DVec3::new(x, y, 0.0));
        let far = inverse.project_point3(DVec3::new(x, y, 1.0));
        let eye = self.eye();
        (
            eye,
            (far - near).normalize_or((self.target - eye).normalize()),
        )
    }

    /// Turn by a drag of `dx`, `dy` radians.
    pub fn orbit(&mut self, dx: f64, dy: f64) {
        self.yaw -= dx;
        self.pitch = (self.pitch + dy).clamp(-1.55, 1.55);
    }

    /// Move the target by a drag of `dx`, `dy` pixels on a viewport
    /// `height` pixels tall, so the point under the mouse follows it.
    pub fn pan(&mut self, dx: f64, dy: f64, height: f64) {
        let (right, up) = self.right_up();
        let k = self.units_per_pixel(height);
        self.target += (-right * dx + up * dy) * k;
    }

    /// Move closer (`factor` < 1) or further.
    pub fn zoom(&mut self, factor: f64) {
        self.distance = (self.distance * factor).clamp(self.radius * 1e-3, self.radius * 100.0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scene_camera_round_trips() {
        let c = Camera {
            position: [1.0, 2.0, 5.0],
            look_at: [0.5, 0.0, 0.0],
            fov: 50.0,
        };
        let o = OrbitCamera::from_scene(&c, 1.0);
        assert!((o.eye() - DVec3::from_array(c.position)).length() < 1e-12);
    }

    #[test]
    fn the_centre_ray_hits_the_target() {
        let o = OrbitCamera::fit(DVec3::splat(-1.0), DVec3::new(3.0, 1.0, 2.0));
        let (eye, dir) = o.ray(0.0, 0.0, 1.5);
        let to_target = (o.target - eye).normalize();
        assert!(dir.dot(to_target) > 1.0 - 1e-9, "{dir} {to_target}");
        // A ray through a corner leans the way the picture does.
        let (right, up) = o.right_up();
        let (_, corner) = o.ray(1.0, 1.0, 1.5);
        assert!(corner.dot(right) > 0.0 && corner.dot(up) > 0.0);
    }

    #[test]
    fn the_target_projects_to_the_centre() {
        let o = OrbitCamera::fit(DVec3::splat(-1.0), DVec3::new(3.0, 1.0, 2.0));
        let p = o.view_proj(1.5).project_point3(o.target.as_vec3());
        assert!(p.x.abs() < 1e-5 && p.y.abs() < 1e-5 && (0.0..1.0).contains(&p.z));
    }
}
