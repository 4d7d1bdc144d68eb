//! Point, spot and directional lights against their closed forms.
//!
//! A Lambertian floor of albedo ρ lit by a point light of intensity I at height h has, at
//! horizontal distance x from the light's foot, the radiance ρ/π · I · cos θ / d² with
//! d² = x² + h² and cos θ = h/d; a spot light multiplies that by its falloff at the angle
//! the point makes with its axis; a directional light of irradiance E arriving at angle θ
//! gives ρ/π · E · cos θ. With the light the only emitter and nothing above the floor,
//! the path tracer's estimate in RGB mode is exact: one light to choose, one shadow ray,
//! every BSDF-sampled ray escapes. The same holds for the direct-lighting integrator, and
//! an occluder between the floor and the light must leave the floor black.

use glam::Vec3;
use spectral::SampledWavelengths;
use spectral::spectrum::Colour;
use std::f32::consts::FRAC_1_PI;
use tracer::integrator::{Integrator, PathCounters, PathSettings};
use tracer::material::Material;
use tracer::mesh::quad;
use tracer::{CpuBackend, CpuScene, DirectLighting, PathTracer, PunctualLight, Scene, SceneOptions};

const ALBEDO: f32 = 0.5;

fn floor_with(lights: Vec<PunctualLight>, occluder: bool) -> CpuScene {
    let mut scene = Scene::default();
    scene.add(&quad(Vec3::ZERO, Vec3::Y, 20.0), Material::diffuse("floor", Colour::constant(ALBEDO)).unwrap());
    if occluder {
        scene.add(
            &quad(Vec3::new(0.0, 1.0, 0.0), -Vec3::Y, 0.5),
            Material::diffuse("card", Colour::constant(0.0)).unwrap(),
        );
    }
    scene.punctual_lights = lights;
    CpuBackend::new(1).unwrap().prepare_cpu(scene, &SceneOptions::default()).unwrap()
}

/// The RGB radiance the integrator sees looking straight down at floor point (x, 0, z).
fn radiance_at(prepared: &CpuScene, integrator: &impl Integrator, x: f32, z: f32) -> [f32; 3] {
    let view = prepared.view();
    let ray = bvh::Ray::new(Vec3::new(x, 0.5, z), -Vec3::Y);
    let mut wl = SampledWavelengths::<3>::rgb();
    let mut sampler = rng::Pcg32::seed_from_u64(7);
    let settings = PathSettings::default();
    let l = integrator.radiance(&view, ray, &mut wl, &settings, &mut sampler, &mut PathCounters::default());
    l.0
}

fn assert_close(got: [f32; 3], expect: [f32; 3], what: &str) {
    for c in 0..3 {
        // f32 rounding, amplified by the spot's ramp (its cone width divides cos θ's error).
        let tolerance = 1e-4 * expect[c].abs().max(1e-3);
        assert!((got[c] - expect[c]).abs() <= tolerance, "{what}: channel {c}: {got:?} vs {expect:?}");
    }
}

#[test]
fn a_point_light_gives_the_inverse_square_cosine_law() {
    let h = 2.0;
    let intensity = [3.0f32, 2.0, 1.0];
    let light = PunctualLight::point(Vec3::new(0.0, h, 0.0), Colour::illuminant_rgb(intensity).unwrap());
    let prepared = floor_with(vec![light], false);
    for (x, z) in [(0.0f32, 0.0f32), (1.0, 0.0), (0.0, -3.0), (2.5, 1.5)] {
        let d2 = x * x + z * z + h * h;
        let cos = h / d2.sqrt();
        let expect = intensity.map(|i| ALBEDO * FRAC_1_PI * i * cos / d2);
        assert_close(radiance_at(&prepared, &PathTracer, x, z), expect, &format!("path at ({x}, {z})"));
        assert_close(radiance_at(&prepared, &DirectLighting, x, z), expect, &format!("direct at ({x}, {z})"));
    }
}

#[test]
fn a_spot_light_falls_off_between_its_cones() {
    let h = 1.0;
    let (inner, outer) = (20f32.to_radians(), 40f32.to_radians());
    let light = PunctualLight::spot(Vec3::new(0.0, h, 0.0), -Vec3::Y, Colour::constant(4.0), inner, outer);
    let prepared = floor_with(vec![light], false);
    let mut seen_ramp = false;
    for x in [0.0f32, 0.3, 0.5, 0.7, 0.9, 1.2] {
        let d2 = x * x + h * h;
        let cos = h / d2.sqrt();
        // glTF's attenuation, written out here rather than taken from the renderer.
        let ramp = ((cos - outer.cos()) / (inner.cos() - outer.cos())).clamp(0.0, 1.0);
        let falloff = ramp * ramp;
        seen_ramp |= falloff > 0.0 && falloff < 1.0;
        let expect = ALBEDO * FRAC_1_PI * 4.0 * falloff * cos / d2;
        assert_close(radiance_at(&prepared, &PathTracer, x, 0.0), [expect; 3], &format!("spot at x = {x}"));
    }
    assert!(seen_ramp, "no point between the cones was checked");
    // Outside the outer cone: black; and the falloff is the squared ramp in cos θ.
    assert_eq!(radiance_at(&prepared, &PathTracer, 1.2, 0.0), [0.0; 3]);
    let mid = 0.5 * (inner.cos() + outer.cos());
    assert!((PunctualLight::spot_falloff(mid, inner.cos(), outer.cos()) - 0.25).abs() < 1e-5);
}

#[test]
fn a_directional_light_gives_irradiance_times_cosine() {
    let theta = 30f32.to_radians();
    let travel = Vec3::new(theta.sin(), -theta.cos(), 0.0);
    let light = PunctualLight::directional(travel, Colour::constant(2.0));
    let prepared = floor_with(vec![light], false);
    let expect = ALBEDO * FRAC_1_PI * 2.0 * theta.cos();
    for x in [0.0f32, 4.0, -7.0] {
        assert_close(radiance_at(&prepared, &PathTracer, x, 1.0), [expect; 3], &format!("sun at x = {x}"));
    }
}

#[test]
fn two_lights_add_up_whichever_is_chosen() {
    // Two point lights: each sample picks one by power and divides by its probability, so
    // the mean over many samples is the sum of both closed forms.
    let (a, b) = (Vec3::new(0.0, 2.0, 0.0), Vec3::new(1.0, 1.0, 0.0));
    let lights = vec![PunctualLight::point(a, Colour::constant(1.0)), PunctualLight::point(b, Colour::constant(3.0))];
    let prepared = floor_with(lights, false);
    let p = Vec3::new(0.5, 0.0, 0.0);
    let law = |light: Vec3, i: f32| {
        let d = light - p;
        ALBEDO * FRAC_1_PI * i * (d.y / d.length()) / d.length_squared()
    };
    let expect = law(a, 1.0) + law(b, 3.0);
    let (mean, se) = mean_radiance(&prepared, &PathTracer, p, 20_000, 11);
    let z = (mean - expect as f64) / se;
    assert!(z.abs() < 4.5, "mean {mean} ± {se}, expected {expect} (z = {z:.2})");
}

#[test]
fn an_occluder_casts_a_hard_shadow() {
    let light = PunctualLight::point(Vec3::new(0.0, 2.0, 0.0), Colour::constant(1.0));
    let prepared = floor_with(vec![light], true);
    // The card (half size 0.5 at height 1) shades the floor out to x = 1 below a light at 2.
    assert_eq!(radiance_at(&prepared, &PathTracer, 0.0, 0.0), [0.0; 3]);
    assert_eq!(radiance_at(&prepared, &PathTracer, 0.9, 0.0), [0.0; 3]);
    assert!(radiance_at(&prepared, &PathTracer, 1.1, 0.0)[0] > 0.0);
}

/// The mean and standard error of `n` estimates of the red radiance looking straight down
/// at floor point `p` (RGB mode), one path each.
fn mean_radiance(prepared: &CpuScene, integrator: &impl Integrator, p: Vec3, n: usize, seed: u64) -> (f64, f64) {
    let view = prepared.view();
    let mut sampler = rng::Pcg32::seed_from_u64(seed);
    let (mut sum, mut sum_sq) = (0.0f64, 0.0f64);
    for _ in 0..n {
        let mut wl = SampledWavelengths::<3>::rgb();
        let ray = bvh::Ray::new(p + Vec3::new(0.0, 0.5, 0.0), -Vec3::Y);
        let settings = PathSettings::default();
        let l = integrator.radiance(&view, ray, &mut wl, &settings, &mut sampler, &mut PathCounters::default());
        sum += l.0[0] as f64;
        sum_sq += (l.0[0] as f64).powi(2);
    }
    let mean = sum / n as f64;
    (mean, ((sum_sq / n as f64 - mean * mean) / n as f64).sqrt())
}

#[test]
fn a_sun_disk_gives_the_same_irradiance_as_a_delta_sun_and_shows_its_radiance() {
    // A disk of angular radius r centred at zenith angle θ, entirely above the horizon,
    // delivers E cos θ to a horizontal surface (its projected solid angle is π sin²r cos θ
    // and its radiance E/(π sin²r)): the floor's radiance is ρ/π · E cos θ, as under a
    // delta sun. The path tracer finds it by light sampling and by BSDF-sampled rays
    // escaping into the disk (MIS); the direct and Whitted integrators by light sampling
    // alone (Whitted draws one direction in the disk per hit, as it takes every light). A disk
    // 40° across makes the BSDF-sampled share large enough to matter.
    let theta = 30f32.to_radians();
    let travel = Vec3::new(theta.sin(), -theta.cos(), 0.0);
    let e = 2.0f32;
    let diameter = 40f32.to_radians();
    let prepared = floor_with(vec![PunctualLight::sun(travel, Colour::constant(e), diameter)], false);
    let expect = (ALBEDO * FRAC_1_PI * e * theta.cos()) as f64;
    for (name, (mean, se)) in [
        ("path", mean_radiance(&prepared, &PathTracer, Vec3::new(0.3, 0.0, 0.2), 40_000, 5)),
        ("direct", mean_radiance(&prepared, &DirectLighting, Vec3::new(-1.0, 0.0, 0.4), 40_000, 6)),
        ("whitted", mean_radiance(&prepared, &tracer::Whitted, Vec3::new(0.8, 0.0, -0.5), 40_000, 8)),
    ] {
        let z = (mean - expect) / se;
        assert!(z.abs() < 4.5 && se < 0.02 * expect, "{name}: {mean} ± {se}, expected {expect} (z = {z:.2})");
    }
    // Looking into the disk: its radiance E/(π sin²r), exactly.
    let view = prepared.view();
    let mut wl = SampledWavelengths::<3>::rgb();
    let ray = bvh::Ray::new(Vec3::new(0.0, 1.0, 0.0), -travel);
    let l = DirectLighting.radiance(
        &view,
        ray,
        &mut wl,
        &PathSettings::default(),
        &mut rng::Pcg32::seed_from_u64(1),
        &mut PathCounters::default(),
    );
    let radiance = e / (std::f32::consts::PI * (0.5 * diameter).sin().powi(2));
    assert!((l.0[0] - radiance).abs() < 1e-4 * radiance, "{} vs {radiance}", l.0[0]);
    // An occluder casts a penumbra: a point whose view of the disk is partly blocked gets
    // part of the light (a delta sun gives all or nothing).
    let card = floor_with(vec![PunctualLight::sun(travel, Colour::constant(e), diameter)], true);
    // The card (half-size 0.5 at height 1) shades the floor around x = tan θ.
    let (edge, _) = mean_radiance(&card, &DirectLighting, Vec3::new(theta.tan() + 0.45, 0.0, 0.0), 4_000, 7);
    assert!(edge > 0.1 * expect && edge < 0.9 * expect, "penumbra: {edge} of {expect}");
}
