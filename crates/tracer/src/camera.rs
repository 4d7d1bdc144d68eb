//! The pinhole camera of the thesis (ch. 5.1): eye, centre, up and a vertical field of view.

use bvh::{Aabb, Ray};
use glam::{Vec2, Vec3};

/// A pinhole camera. Image rows run top (up) to bottom; image right is view × up.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub eye: Vec3,
    /// The point looked at.
    pub center: Vec3,
    /// Up direction (need not be orthogonal to the view direction).
    pub up: Vec3,
    /// Vertical field of view, degrees.
    pub fov_y_deg: f32,
}

/// The default vertical field of view, degrees (the Cornell box reference's).
pub const DEFAULT_FOV_Y_DEG: f32 = 39.3077;

impl Camera {
    /// Checks that the camera is usable: finite, eye ≠ centre, up not along the view, and
    /// 0 < fov < 180°.
    pub fn validate(&self) -> Result<(), String> {
        let all = [self.eye, self.center, self.up];
        if all.iter().any(|v| !v.is_finite()) || !self.fov_y_deg.is_finite() {
            return Err("camera values must be finite".into());
        }
        let dir = self.center - self.eye;
        if dir.length_squared() == 0.0 {
            return Err("camera eye and center coincide".into());
        }
        if dir.normalize().cross(self.up).length_squared() < 1e-12 {
            return Err("camera up is parallel to the view direction (or zero)".into());
        }
        if !(self.fov_y_deg > 0.0 && self.fov_y_deg < 180.0) {
            return Err(format!("field of view {}° is not in (0°, 180°)", self.fov_y_deg));
        }
        Ok(())
    }

    /// The documented default view of a scene without a camera: looking down −z at the
    /// bounding box's centre, with +y up and a 39.3077° vertical field of view, from just
    /// far enough (plus 2.5 %) that the box's front face (its +z face) fills the frame
    /// for the given aspect ratio. For the Cornell box this lands within a few per cent
    /// of the classic view (eye ≈ (0, 1, 3.9)).
    pub fn framing(bounds: &Aabb, aspect: f32) -> Self {
        let (centre, extent) = if bounds.is_empty() {
            (Vec3::ZERO, Vec3::ONE)
        } else {
            (bounds.centre(), bounds.extent().max(Vec3::splat(1e-6)))
        };
        let tan_y = (0.5 * DEFAULT_FOV_Y_DEG.to_radians()).tan();
        let tan_x = tan_y * aspect;
        let dist = (0.5 * extent.y / tan_y).max(0.5 * extent.x / tan_x) * 1.025 + 0.5 * extent.z;
        Self { eye: centre + Vec3::Z * dist, center: centre, up: Vec3::Y, fov_y_deg: DEFAULT_FOV_Y_DEG }
    }

    /// Precomputes the ray generator for an image size.
    pub fn rays(&self, width: u32, height: u32) -> RayGenerator {
        let forward = (self.center - self.eye).normalize();
        let right = forward.cross(self.up).normalize();
        let up = right.cross(forward);
        let tan_y = (0.5 * self.fov_y_deg.to_radians()).tan();
        let tan_x = tan_y * width as f32 / height as f32;
        RayGenerator {
            eye: self.eye,
            forward,
            right: right * tan_x,
            up: up * tan_y,
            inv_size: Vec2::new(1.0 / width as f32, 1.0 / height as f32),
        }
    }
}

/// Turns film positions into primary rays.
#[derive(Clone, Copy, Debug)]
pub struct RayGenerator {
    eye: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    inv_size: Vec2,
}

impl RayGenerator {
    /// The generator's parts, for backends that make the rays elsewhere (the GPU):
    /// `(eye, forward, right, up)` with `right` and `up` scaled by the tangents of the
    /// half fields of view; the ray through film position (x, y) leaves `eye` along
    /// normalize(forward + ndc_x·right + ndc_y·up), ndc = (2x/width − 1, 1 − 2y/height).
    pub fn basis(&self) -> (Vec3, Vec3, Vec3, Vec3) {
        (self.eye, self.forward, self.right, self.up)
    }

    /// The eye: where every camera ray starts.
    #[inline]
    pub fn eye(&self) -> Vec3 {
        self.eye
    }

    /// The film position (pixels from the top-left corner) whose ray passes through `p`,
    /// or `None` if `p` is not in front of the eye; the inverse of [`RayGenerator::ray`].
    /// Positions outside the image are returned as they are.
    #[inline]
    pub fn film_position(&self, p: Vec3) -> Option<Vec2> {
        let d = p - self.eye;
        let z = d.dot(self.forward);
        if z.is_nan() || z <= 0.0 {
            return None;
        }
        let ndc_x = d.dot(self.right) / (z * self.right.length_squared());
        let ndc_y = d.dot(self.up) / (z * self.up.length_squared());
        Some(Vec2::new(0.5 * (ndc_x + 1.0) / self.inv_size.x, 0.5 * (1.0 - ndc_y) / self.inv_size.y))
    }

    /// Film area per solid angle around the unit direction `dir`, in pixels per steradian:
    /// the solid-angle density of the ray through a point drawn uniformly in one pixel,
    /// and the pinhole's importance W(ω) per pixel. The film lies on the plane one unit
    /// along the view direction, where ω at angle θ from it spans dA = dω / cos³ θ, and a
    /// unit of that plane holds width·height / (4 tan_x tan_y) pixels; 0 behind the eye.
    /// (Integrated over the image's solid angle it gives width·height.)
    #[inline]
    pub fn pixels_per_steradian(&self, dir: Vec3) -> f32 {
        let cos = dir.dot(self.forward);
        if cos.is_nan() || cos <= 0.0 {
            return 0.0;
        }
        let plane = 4.0 * self.right.length() * self.up.length() * self.inv_size.x * self.inv_size.y;
        1.0 / (plane * cos * cos * cos)
    }

    /// The ray through film position (x, y) in pixels from the top-left corner; a pixel
    /// spans [x, x+1) × [y, y+1), so jittering within it is a box filter.
    #[inline]
    pub fn ray(&self, film: Vec2) -> Ray {
        let ndc = Vec2::new(2.0 * film.x * self.inv_size.x - 1.0, 1.0 - 2.0 * film.y * self.inv_size.y);
        let dir = (self.forward + ndc.x * self.right + ndc.y * self.up).normalize();
        Ray::new(self.eye, dir)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn centre_ray_looks_at_center_and_corners_span_the_fov() {
        let cam =
            Camera { eye: Vec3::new(0.0, 1.0, 3.9), center: Vec3::new(0.0, 1.0, 0.0), up: Vec3::Y, fov_y_deg: 40.0 };
        let g = cam.rays(200, 100);
        let mid = g.ray(Vec2::new(100.0, 50.0));
        assert!((mid.dir - -Vec3::Z).length() < 1e-6);
        let top = g.ray(Vec2::new(100.0, 0.0));
        let angle = top.dir.dot(-Vec3::Z).acos().to_degrees();
        assert!((angle - 20.0).abs() < 1e-3, "{angle}");
        assert!(top.dir.y > 0.0, "image top is up");
        let right = g.ray(Vec2::new(200.0, 50.0));
        assert!(right.dir.x > 0.0, "image right is view × up");
    }

    #[test]
    fn film_positions_invert_rays_and_the_pixel_density_is_their_jacobian() {
        let cam =
            Camera { eye: Vec3::new(0.3, 1.0, 3.9), center: Vec3::new(0.0, 0.8, 0.0), up: Vec3::Y, fov_y_deg: 50.0 };
        let (w, h) = (64, 48);
        let g = cam.rays(w, h);
        for film in [Vec2::new(0.0, 0.0), Vec2::new(17.25, 30.5), Vec2::new(63.9, 47.9), Vec2::new(-5.0, 60.0)] {
            let ray = g.ray(film);
            let back = g.film_position(ray.origin + 2.7 * ray.dir).unwrap();
            assert!((back - film).length() < 1e-3, "{film} -> {back}");
        }
        assert!(g.film_position(g.eye() - Vec3::new(0.0, 0.0, -1.0)).is_none(), "behind the eye");
        // The density is the Jacobian: a small square of film spans a solid angle of
        // its area over the density, at the centre as at the corners.
        let d = 1e-2;
        for film in [Vec2::new(32.0, 24.0), Vec2::new(50.0, 7.0), Vec2::new(0.5, 47.5)] {
            let [a, b, c] = [film, film + Vec2::new(d, 0.0), film + Vec2::new(0.0, d)].map(|f| g.ray(f).dir);
            let solid_angle = (b - a).cross(c - a).length();
            let ratio = g.pixels_per_steradian(a) * solid_angle / (d * d);
            assert!((ratio - 1.0).abs() < 2e-3, "{film}: {ratio}");
        }
        assert_eq!(g.pixels_per_steradian(-g.ray(Vec2::new(32.0, 24.0)).dir), 0.0);
    }

    #[test]
    fn default_framing_of_the_cornell_box_is_close_to_the_classic_view() {
        let b = Aabb { min: Vec3::new(-1.02, 0.0, -1.04), max: Vec3::new(1.0, 1.99, 0.99) };
        let cam = Camera::framing(&b, 1.0);
        assert!((cam.eye.z - 3.9).abs() < 0.1, "{}", cam.eye);
        assert!(cam.validate().is_ok());
    }

    #[test]
    fn invalid_cameras_are_rejected() {
        let ok = Camera { eye: Vec3::Z, center: Vec3::ZERO, up: Vec3::Y, fov_y_deg: 40.0 };
        assert!(ok.validate().is_ok());
        assert!(Camera { center: Vec3::Z, ..ok }.validate().is_err());
        assert!(Camera { up: Vec3::Z, ..ok }.validate().is_err());
        assert!(Camera { fov_y_deg: 180.0, ..ok }.validate().is_err());
        assert!(Camera { eye: Vec3::NAN, ..ok }.validate().is_err());
    }
}
