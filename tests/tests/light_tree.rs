//! Choosing lights by a light tree (`LightSampler::Tree`) is unbiased and pays where
//! there are many: the path tracer (MIS against BSDF sampling, which needs the tree's
//! probability of a light hit by chance) and the direct-light integrator (no MIS) give
//! the same images with the tree as with power sampling, pixel by pixel, in a hall of
//! small lamps with an emissive sphere (an analytic shape in the tree), a point light (in
//! the tree too) and a sky (which keeps its share of the choice beside the tree), and in a
//! hall of point and spot lights beside a sun — and the tree's images there are less noisy
//! at the same sample count.

use crate::common;

use common::batched::{Batched, assert_agree, batched_with, lamp};
use glam::Vec3;
use shapes::sphere::{Sphere, SphereMethod};
use spectral::SpectralMode;
use spectral::spectrum::Colour;
use tracer::camera::Camera;
use tracer::lights::Lights;
use tracer::material::Material;
use tracer::mesh::quad;
use tracer::{
    DirectLighting, Environment, Integrator, LightSampler, PathTracer, PunctualLight, RenderSettings, Scene,
    SceneOptions, ShapeKind,
};

/// Half the side of a lamp: large and low enough that BSDF sampling finds the lamps
/// often, so that a wrong MIS weight for those hits shows.
const LAMP_HALF: f32 = 0.4;

/// A floor and a back wall under a dim sky, and the camera.
fn room() -> Scene {
    let mut scene = Scene::default();
    let grey = Material::diffuse("grey", Colour::constant(0.6)).unwrap();
    scene.add(&quad(Vec3::ZERO, Vec3::Y, 6.0), grey.clone());
    scene.add(&quad(Vec3::new(0.0, 2.0, -6.0), Vec3::Z, 6.0), grey);
    // A dim sky: the tree's stretch of the choice starts after its share.
    scene.environment = Some(Environment::uniform(Colour::illuminant_rgb([0.01, 0.014, 0.02]).unwrap()));
    scene.camera =
        Some(Camera { eye: Vec3::new(0.0, 2.5, 7.0), center: Vec3::new(0.0, 0.3, 0.0), up: Vec3::Y, fov_y_deg: 60.0 });
    scene
}

/// A 5 × 5 grid of lights: each one's row, column and linear-sRGB colour (four colours,
/// brightness varying fourfold).
fn grid() -> impl Iterator<Item = (usize, usize, [f32; 3])> {
    let colours = [[1.0, 0.75, 0.45], [0.55, 0.7, 1.0], [1.0, 0.45, 0.35], [0.6, 1.0, 0.6]];
    (0..25).map(move |k| {
        let (i, j) = (k / 5, k % 5);
        let s = 2.0 * (1 + (i * 3 + j) % 4) as f32;
        (i, j, colours[(i + 2 * j) % 4].map(|c| c * s))
    })
}

/// The [`room`] under a [`grid`] of small lamps facing down, a glowing ball and a dim
/// point light.
fn hall() -> Scene {
    let mut scene = room();
    for (i, j, rgb) in grid() {
        let centre = Vec3::new(-4.8 + 2.4 * i as f32, 0.8, -4.8 + 2.4 * j as f32);
        scene.add(&quad(centre, -Vec3::Y, LAMP_HALF), lamp(&format!("lamp{i}{j}"), rgb));
    }
    let ball = Sphere::new(Vec3::new(1.3, 0.3, 1.0), 0.3, SphereMethod::default()).unwrap();
    scene.add_shape(ShapeKind::Sphere(ball), lamp("ball", [2.0, 1.5, 1.0]));
    scene
        .punctual_lights
        .push(PunctualLight::point(Vec3::new(-2.0, 3.0, 2.0), Colour::illuminant_rgb([3.0; 3]).unwrap()));
    scene
}

fn settings(mode: SpectralMode, spp: u32) -> RenderSettings {
    RenderSettings { width: 24, height: 18, spp, seed: 9, mode, ..Default::default() }
}

/// The [`room`] under a [`grid`] of point lights and spots aimed down (alternating),
/// beside a dim sun, which keeps its power share as the sky does.
fn punctual_hall() -> Scene {
    let mut scene = room();
    for (i, j, rgb) in grid() {
        let colour = Colour::illuminant_rgb(rgb).unwrap();
        let at = Vec3::new(-4.8 + 2.4 * i as f32, 1.6, -3.6 + 2.4 * j as f32);
        scene.punctual_lights.push(match (i + j) % 2 {
            0 => PunctualLight::point(at, colour),
            _ => PunctualLight::spot(at, -Vec3::Y, colour, 0.5, 0.9),
        });
    }
    let sun = Colour::illuminant_rgb([0.05, 0.045, 0.04]).unwrap();
    scene.punctual_lights.push(PunctualLight::directional(Vec3::new(0.3, -1.0, -0.4), sun));
    scene
}

/// The hall rendered by `integrator()` with the tree and by power (16 batches of 64
/// spp), the two asserted to agree pixel by pixel; (tree, power).
fn tree_and_power<I: Integrator>(integrator: impl Fn() -> I, mode: SpectralMode) -> (Batched, Batched) {
    tree_and_power_in(hall(), integrator, mode, 16)
}

/// [`tree_and_power`] in `scene`, with `batches` batches.
fn tree_and_power_in<I: Integrator>(
    scene: Scene,
    integrator: impl Fn() -> I,
    mode: SpectralMode,
    batches: u32,
) -> (Batched, Batched) {
    let [tree, power] = [LightSampler::Tree, LightSampler::Power].map(|light_sampler| {
        let options = SceneOptions { light_sampler, ..SceneOptions::default() };
        batched_with(integrator(), &scene, &options, &settings(mode, 64), batches)
    });
    assert_agree(&tree, &power, 0.99);
    (tree, power)
}

/// The mean over pixel-channels of the squared standard error.
fn mean_variance(b: &Batched) -> f64 {
    b.se.iter().map(|&s| (s as f64).powi(2)).sum::<f64>() / b.se.len() as f64
}

#[test]
fn the_path_tracer_with_a_light_tree_agrees_with_power_sampling_and_is_less_noisy() {
    let (tree, power) = tree_and_power(|| PathTracer, SpectralMode::Hero);
    // Measured: 0.39 of power sampling's variance (8.9e-5 against 2.3e-4).
    let (vt, vp) = (mean_variance(&tree), mean_variance(&power));
    assert!(vt < 0.5 * vp, "variance with the tree {vt:.3e}, by power {vp:.3e}");
}

#[test]
fn direct_light_with_a_light_tree_agrees_with_power_sampling() {
    tree_and_power(|| DirectLighting, SpectralMode::Rgb);
}

/// Point and spot lights in the tree: the same image as by power, pixel by pixel, for the
/// path tracer (hero wavelengths) and direct light, and less noise. (32 batches: power
/// sampling's estimate is skewed here — a narrow spot's share of the power is a tenth of
/// a point light's of equal intensity, so the rare samples on a spot weigh much — and
/// with 16 its image mean lay 4.8 standard errors from the tree's at one seed of three,
/// from 4096-spp renders of the same scene 0.1 % apart.)
#[test]
fn point_and_spot_lights_in_the_tree_agree_with_power_sampling_and_are_less_noisy() {
    let scene = punctual_hall();
    let lights = Lights::with_sampler(&scene, LightSampler::Tree);
    assert!(lights.has_tree() && lights.emitter_count() == 0);
    let (tree, power) = tree_and_power_in(scene.clone(), || PathTracer, SpectralMode::Hero, 32);
    let (vt, vp) = (mean_variance(&tree), mean_variance(&power));
    assert!(vt < 0.5 * vp, "variance with the tree {vt:.3e}, by power {vp:.3e}");
    tree_and_power_in(scene, || DirectLighting, SpectralMode::Rgb, 32);
}

/// `Auto` takes the tree from `TREE_FROM` emitters (the hall's 50 triangles and a ball),
/// not for a single quad lamp. (That `sample_at` draws each emitter with `prim_pmf_at`,
/// over its area, is `tracer::lights`' unit test beside a sky and a point light.)
#[test]
fn auto_takes_the_tree_for_many_emitters_only() {
    let scene = hall();
    assert!(Lights::with_sampler(&scene, LightSampler::Auto).has_tree());
    let mut one_lamp = Scene::default();
    one_lamp.add(&quad(Vec3::ZERO, -Vec3::Y, 0.5), lamp("lamp", [1.0; 3]));
    assert!(!Lights::with_sampler(&one_lamp, LightSampler::Auto).has_tree());
    assert!(!Lights::with_sampler(&scene, LightSampler::Power).has_tree());
    // Point and spot lights count (the sun does not).
    assert!(Lights::with_sampler(&punctual_hall(), LightSampler::Auto).has_tree());
    let mut few = punctual_hall();
    few.punctual_lights.drain(..few.punctual_lights.len() - LightSampler::TREE_FROM);
    assert!(!Lights::with_sampler(&few, LightSampler::Auto).has_tree(), "7 point and spot lights and a sun");
    // The threshold itself: one emitter short of it and at it (quad lamps of two
    // triangles, then glowing balls of one emitter each).
    for (emitters, tree) in [(LightSampler::TREE_FROM - 1, false), (LightSampler::TREE_FROM, true)] {
        let mut row = Scene::default();
        for i in 0..emitters / 2 {
            row.add(&quad(Vec3::new(i as f32, 0.0, 0.0), -Vec3::Y, 0.4), lamp("lamp", [1.0; 3]));
        }
        for i in 2 * (emitters / 2)..emitters {
            let ball = Sphere::new(Vec3::new(i as f32, 1.0, 0.0), 0.2, SphereMethod::default()).unwrap();
            row.add_shape(ShapeKind::Sphere(ball), lamp("ball", [1.0; 3]));
        }
        assert_eq!(Lights::new(&row).emitter_count(), emitters);
        assert_eq!(Lights::with_sampler(&row, LightSampler::Auto).has_tree(), tree, "{emitters} emitters");
    }
}
