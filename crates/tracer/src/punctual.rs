//! Lights without area: points, spots and directional (sun-like) lights, as glTF's
//! `KHR_lights_punctual` and pbrt-v4's `point`, `spot` and `distant` lights define them.
//!
//! Points, spots and the default directional light are delta lights: no ray can hit
//! them, so they reach an image only through next-event estimation (a shadow ray towards
//! them), never through a BSDF-sampled ray, and their light samples need no multiple
//! importance sampling (weight 1). A directional light given an angular diameter (a sun
//! disk, [`PunctualLight::sun`]) is not: it is a disk of uniform radiance at infinity,
//! sampled uniformly within its cone and found by escaping rays too, weighted by MIS; its
//! shadows have penumbrae and it lights caustics a path tracer can find.

use glam::Vec3;
use spectral::spectrum::Colour;
use std::f32::consts::{PI, TAU};

/// A point, spot or directional light.
#[derive(Clone, Debug, PartialEq)]
pub enum PunctualLight {
    /// Light from one point, the same in every direction.
    Point {
        /// Where it is.
        position: Vec3,
        /// Radiant intensity I (radiance units × m² per steradian): a surface at distance
        /// d facing the light receives irradiance I/d².
        intensity: Colour,
    },
    /// A point light restricted to a cone, full intensity within `cos_inner` of its axis,
    /// falling off to zero at `cos_outer`.
    Spot {
        /// Where it is.
        position: Vec3,
        /// The cone's axis: the unit direction it shines in.
        direction: Vec3,
        /// Intensity on the axis (as [`PunctualLight::Point`]'s).
        intensity: Colour,
        /// Cosine of the angle within which the intensity is full.
        cos_inner: f32,
        /// Cosine of the angle beyond which it is zero (≤ `cos_inner`).
        cos_outer: f32,
    },
    /// Light from infinitely far away: parallel (a delta direction) or, with an angular
    /// size, a disk of uniform radiance (the sun as it is).
    Directional {
        /// The unit direction the light travels in (`0,-1,0`: straight down).
        direction: Vec3,
        /// Irradiance E on a surface facing the light.
        irradiance: Colour,
        /// Cosine of the disk's angular radius: 1 for a delta direction.
        cos_radius: f32,
    },
}

impl PunctualLight {
    /// A point light.
    pub fn point(position: Vec3, intensity: Colour) -> Self {
        Self::Point { position, intensity }
    }

    /// A spot light shining along `direction` (normalised here) with full intensity out
    /// to `inner` radians from its axis and none beyond `outer` (clamped to ≥ `inner`).
    pub fn spot(position: Vec3, direction: Vec3, intensity: Colour, inner: f32, outer: f32) -> Self {
        let outer = outer.max(inner);
        Self::Spot {
            position,
            direction: direction.normalize_or_zero(),
            intensity,
            cos_inner: inner.cos(),
            cos_outer: outer.cos(),
        }
    }

    /// A directional light travelling along `direction` (normalised here): a delta.
    pub fn directional(direction: Vec3, irradiance: Colour) -> Self {
        Self::Directional { direction: direction.normalize_or_zero(), irradiance, cos_radius: 1.0 }
    }

    /// A sun disk of angular diameter `diameter` (radians; the real sun's is 0.0093, 0.53°)
    /// delivering irradiance E to a surface facing it; 0 is [`Self::directional`].
    pub fn sun(direction: Vec3, irradiance: Colour, diameter: f32) -> Self {
        Self::Directional { direction: direction.normalize_or_zero(), irradiance, cos_radius: (0.5 * diameter).cos() }
    }

    /// For a sun disk: the unit direction towards its centre, the cosine of its angular
    /// radius and its solid angle 2π(1 − cos r); `None` for delta lights.
    #[inline]
    pub fn disk(&self) -> Option<(Vec3, f32, f32)> {
        match *self {
            Self::Directional { direction, cos_radius, .. } if cos_radius < 1.0 => {
                Some((-direction, cos_radius, TAU * (1.0 - cos_radius)))
            }
            _ => None,
        }
    }

    /// What next-event estimation multiplies a directional light's irradiance by: for a
    /// sun disk 1/(π sin² r), its radiance (the projected solid angle of a cap of angular
    /// radius r is π sin² r, so that a surface facing the disk receives E); 1 for a delta
    /// direction, whose estimate uses the irradiance itself.
    #[inline]
    pub fn disk_radiance_scale(&self) -> f32 {
        match self.disk() {
            Some((_, c, _)) => 1.0 / (PI * (1.0 - c * c)),
            None => 1.0,
        }
    }

    /// The light moved by `t` (positions as points, directions as vectors, renormalised);
    /// its intensity or irradiance is kept.
    pub fn transformed(self, t: &glam::Mat4) -> Self {
        let dir = |d: Vec3| t.transform_vector3(d).normalize_or(d);
        match self {
            Self::Point { position, intensity } => Self::Point { position: t.transform_point3(position), intensity },
            Self::Spot { position, direction, intensity, cos_inner, cos_outer } => Self::Spot {
                position: t.transform_point3(position),
                direction: dir(direction),
                intensity,
                cos_inner,
                cos_outer,
            },
            Self::Directional { direction, irradiance, cos_radius } => {
                Self::Directional { direction: dir(direction), irradiance, cos_radius }
            }
        }
    }

    /// Where a light sample points: a point or spot light's position, or the unit
    /// direction towards a directional light (as [`crate::lights::LightSample::point`]).
    pub fn towards(&self) -> Vec3 {
        match self {
            Self::Point { position, .. } | Self::Spot { position, .. } => *position,
            Self::Directional { direction, .. } => -*direction,
        }
    }

    /// The light's name in messages and `spt info`.
    pub fn kind(&self) -> &'static str {
        match self {
            Self::Point { .. } => "point",
            Self::Spot { .. } => "spot",
            Self::Directional { cos_radius, .. } if *cos_radius < 1.0 => "sun disk",
            Self::Directional { .. } => "directional",
        }
    }

    /// The colour it emits (intensity or irradiance).
    pub fn colour(&self) -> &Colour {
        match self {
            Self::Point { intensity, .. } | Self::Spot { intensity, .. } => intensity,
            Self::Directional { irradiance, .. } => irradiance,
        }
    }

    /// The spot's angular falloff at cos θ from its axis: 1 inside the inner cone, 0
    /// outside the outer one, and between them the square of the linear ramp in cos θ
    /// (glTF 2.0 `KHR_lights_punctual`'s recommended attenuation).
    #[inline]
    pub fn spot_falloff(cos_theta: f32, cos_inner: f32, cos_outer: f32) -> f32 {
        if cos_theta >= cos_inner {
            return 1.0;
        }
        let width = cos_inner - cos_outer;
        if width <= 0.0 {
            return 0.0;
        }
        let t = ((cos_theta - cos_outer) / width).clamp(0.0, 1.0);
        t * t
    }

    /// Emitted power, as luminance, for choosing among lights: 4π·I for a point, I times
    /// the falloff's solid angle 2π·((1 − cos_inner) + (cos_inner − cos_outer)/3) for a
    /// spot (exact for the squared linear ramp), and E·π·r² for a directional light
    /// crossing a scene of bounding radius `scene_radius` (pbrt-v4's `DistantLight::Phi`).
    pub fn power(&self, scene_radius: f32) -> f32 {
        let y = self.colour().luminance().max(0.0);
        match *self {
            Self::Point { .. } => 4.0 * PI * y,
            Self::Spot { cos_inner, cos_outer, .. } => {
                TAU * ((1.0 - cos_inner) + (cos_inner - cos_outer).max(0.0) / 3.0) * y
            }
            Self::Directional { .. } => PI * scene_radius * scene_radius * y,
        }
    }

    /// Checks positions, directions and cone angles; the message names what is wrong.
    pub fn validate(&self) -> Result<(), String> {
        let finite = |v: Vec3, what: &str| {
            if v.is_finite() { Ok(()) } else { Err(format!("{} light: {what} {v} is not finite", self.kind())) }
        };
        let unit = |v: Vec3| {
            if (v.length() - 1.0).abs() < 1e-3 {
                Ok(())
            } else {
                Err(format!("{} light: the direction must be a non-zero vector, got {v}", self.kind()))
            }
        };
        match *self {
            Self::Point { position, .. } => finite(position, "position")?,
            Self::Spot { position, direction, cos_inner, cos_outer, .. } => {
                finite(position, "position")?;
                unit(direction)?;
                if !(cos_outer.is_finite() && cos_inner.is_finite() && cos_outer <= cos_inner) {
                    return Err(format!(
                        "spot light: the outer cone (cos {cos_outer}) must be at least as wide as the inner (cos {cos_inner})"
                    ));
                }
            }
            Self::Directional { direction, cos_radius, .. } => {
                unit(direction)?;
                // Up to 90° across (a wider cap would reach past the horizon of every
                // surface facing it; nothing in a sky is that large).
                if !(cos_radius.is_finite() && cos_radius > std::f32::consts::FRAC_1_SQRT_2 && cos_radius <= 1.0) {
                    return Err(format!(
                        "sun: the angular diameter {:.3}° must lie in [0°, 90°)",
                        2.0 * cos_radius.clamp(-1.0, 1.0).acos().to_degrees()
                    ));
                }
            }
        }
        if self.colour().rgb.iter().any(|c| !(c.is_finite() && *c >= 0.0)) {
            return Err(format!(
                "{} light: colour {:?} must be finite and non-negative",
                self.kind(),
                self.colour().rgb
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_spot_falloff_is_one_inside_zero_outside_and_a_squared_ramp_between() {
        let (ci, co) = (0.9f32, 0.7f32);
        assert_eq!(PunctualLight::spot_falloff(1.0, ci, co), 1.0);
        assert_eq!(PunctualLight::spot_falloff(0.9, ci, co), 1.0);
        assert_eq!(PunctualLight::spot_falloff(0.6, ci, co), 0.0);
        assert!((PunctualLight::spot_falloff(0.8, ci, co) - 0.25).abs() < 1e-6);
        // A hard-edged cone (equal angles) has no ramp.
        assert_eq!(PunctualLight::spot_falloff(0.89, 0.9, 0.9), 0.0);
    }

    #[test]
    fn the_spot_power_is_the_integral_of_its_falloff() {
        let light = PunctualLight::spot(Vec3::ZERO, Vec3::Y, Colour::constant(1.0), 0.3, 0.8);
        let PunctualLight::Spot { cos_inner, cos_outer, .. } = light else { unreachable!() };
        // ∫ falloff dω = 2π ∫ falloff(c) dc over c ∈ [−1, 1], by the midpoint rule.
        let n = 200_000;
        let integral: f64 = (0..n)
            .map(|i| {
                let c = -1.0 + 2.0 * (i as f64 + 0.5) / n as f64;
                PunctualLight::spot_falloff(c as f32, cos_inner, cos_outer) as f64
            })
            .sum::<f64>()
            * 2.0
            / n as f64
            * std::f64::consts::TAU;
        let power = light.power(1.0) as f64;
        assert!((power - integral).abs() < 1e-4 * integral, "{power} vs {integral}");
        let point = PunctualLight::point(Vec3::ZERO, Colour::constant(1.0));
        assert!((point.power(1.0) - 4.0 * PI).abs() < 1e-3);
    }

    #[test]
    fn bad_lights_are_named() {
        let nan = PunctualLight::point(Vec3::new(f32::NAN, 0.0, 0.0), Colour::constant(1.0));
        assert!(nan.validate().unwrap_err().contains("point light: position"));
        let zero = PunctualLight::directional(Vec3::ZERO, Colour::constant(1.0));
        assert!(zero.validate().unwrap_err().contains("non-zero"));
        let negative = PunctualLight::point(Vec3::ZERO, Colour { rgb: [-1.0, 0.0, 0.0], ..Colour::constant(0.0) });
        assert!(negative.validate().unwrap_err().contains("non-negative"));
        assert!(PunctualLight::spot(Vec3::ZERO, Vec3::X, Colour::constant(1.0), 0.2, 0.4).validate().is_ok());
    }
}
