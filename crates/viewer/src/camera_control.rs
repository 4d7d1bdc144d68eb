//! The viewer's camera moves as pure functions on a [`Camera`]: orbit around the centre,
//! pan, dolly, fly and turn. Each move keeps the camera valid (eye ≠ centre, view not
//! along up), so the renderer never sees a degenerate camera.

use glam::{Quat, Vec3};
use tracer::Camera;

/// Smallest angle, radians, kept between the view direction and the up axis (orbit and
/// turn stop there instead of flipping over the pole).
pub const POLE_MARGIN: f32 = 0.01;

/// How much one dolly step (a wheel notch, or `+`) shortens the eye–centre distance.
pub const DOLLY_FACTOR: f32 = 0.9;

/// A camera being moved by the user, with the view it started from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraControl {
    camera: Camera,
    initial: Camera,
    step: f32,
    min_distance: f32,
}

impl CameraControl {
    /// Starts from `camera`; `scene_size` (the scene's bounding-box diagonal, or any
    /// length that sets the scale) fixes the length of one fly step (2 % of it) and the
    /// closest the eye may dolly to the centre (10⁻⁴ of it).
    pub fn new(camera: Camera, scene_size: f32) -> Self {
        let size = if scene_size.is_finite() && scene_size > 0.0 { scene_size } else { 1.0 };
        Self { camera, initial: camera, step: 0.02 * size, min_distance: 1e-4 * size }
    }

    /// The current camera.
    pub fn camera(&self) -> Camera {
        self.camera
    }

    /// The length of one fly step in scene units.
    pub fn step(&self) -> f32 {
        self.step
    }

    /// Goes back to the camera this control started from.
    pub fn reset(&mut self) {
        self.camera = self.initial;
    }

    fn up(&self) -> Vec3 {
        self.camera.up.normalize()
    }

    /// Unit view direction, right and (orthogonal) up vectors of the image plane.
    fn frame(&self) -> (Vec3, Vec3, Vec3) {
        let forward = (self.camera.center - self.camera.eye).normalize();
        let right = forward.cross(self.camera.up).normalize();
        (forward, right, right.cross(forward))
    }

    /// Rotates `v` by `yaw` about the up axis and then tilts it by `tilt` away from
    /// the up axis (positive: towards −up), keeping its angle to up within
    /// [`POLE_MARGIN`, π − [`POLE_MARGIN`]].
    fn rotate(&self, v: Vec3, yaw: f32, tilt: f32) -> Vec3 {
        let up = self.up();
        let v = Quat::from_axis_angle(up, yaw) * v;
        let axis = up.cross(v);
        if axis.length_squared() < 1e-20 || tilt == 0.0 {
            return v;
        }
        let theta = (v.dot(up) / v.length()).clamp(-1.0, 1.0).acos();
        let target = (theta + tilt).clamp(POLE_MARGIN, std::f32::consts::PI - POLE_MARGIN);
        Quat::from_axis_angle(axis.normalize(), target - theta) * v
    }

    /// Orbits the eye around the centre: `yaw` radians about the up axis (positive turns
    /// the eye to its left, so the scene appears to turn right) and `pitch` radians
    /// over the top (positive raises the eye). The distance to the centre is kept.
    pub fn orbit(&mut self, yaw: f32, pitch: f32) {
        let offset = self.camera.eye - self.camera.center;
        let rotated = self.rotate(offset, -yaw, -pitch);
        self.camera.eye = self.camera.center + rotated.normalize() * offset.length();
    }

    /// Turns the view from a fixed eye: `yaw` radians to the left (positive) about the up
    /// axis and `pitch` radians upwards (positive). The centre moves; its distance to the
    /// eye is kept.
    pub fn turn(&mut self, yaw: f32, pitch: f32) {
        let offset = self.camera.center - self.camera.eye;
        let rotated = self.rotate(offset, yaw, -pitch);
        self.camera.center = self.camera.eye + rotated.normalize() * offset.length();
    }

    /// Pans: moves eye and centre together in the image plane so that the centre's depth
    /// follows a drag of (`dx`, `dy`) image heights (x to the right, y down, as the
    /// cursor moves): the scene moves with the cursor.
    pub fn pan(&mut self, dx: f32, dy: f32) {
        let (_, right, up) = self.frame();
        let distance = (self.camera.center - self.camera.eye).length();
        let height = 2.0 * distance * (0.5 * self.camera.fov_y_deg.to_radians()).tan();
        let shift = (-dx * right + dy * up) * height;
        self.camera.eye += shift;
        self.camera.center += shift;
    }

    /// Dollies: `steps` > 0 moves the eye towards the centre, each step multiplying the
    /// distance by [`DOLLY_FACTOR`]; `steps` < 0 moves it away. The eye never reaches or
    /// passes the centre (it stops at a small fraction of the scene size from it).
    pub fn dolly(&mut self, steps: f32) {
        let offset = self.camera.eye - self.camera.center;
        let distance = offset.length();
        let mut target = distance * DOLLY_FACTOR.powf(steps);
        if steps > 0.0 {
            target = target.max(self.min_distance.min(distance));
        }
        if target.is_finite() && target > 0.0 {
            self.camera.eye = self.camera.center + offset / distance * target;
        }
    }

    /// Flies: moves eye and centre together by `forward` steps along the view direction,
    /// `right` steps to the image's right and `up` steps along the up axis (one step is
    /// [`CameraControl::step`]).
    pub fn fly(&mut self, forward: f32, right: f32, up: f32) {
        let (f, r, _) = self.frame();
        let shift = (forward * f + right * r + up * self.up()) * self.step;
        self.camera.eye += shift;
        self.camera.center += shift;
    }
}

#[cfg(test)]
mod tests;
