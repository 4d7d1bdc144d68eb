//! Built-in scenes.

use crate::camera::Camera;
use crate::material::Material;
use crate::mesh::{quad, uv_sphere};
use crate::scene::{Environment, Scene};
use glam::Vec3;
use spectral::spectrum::Colour;

/// A material-preview scene (the thesis's figures 9.1–9.4): a sphere of `material`
/// (smooth normals, tangents along its parallels) on a grey checker-free floor, lit by a
/// warm area light above-left and a dim uniform sky, seen slightly from above.
pub fn material_sphere(material: Material) -> Scene {
    let mut scene = Scene::default();
    scene.add(&uv_sphere(Vec3::new(0.0, 1.0, 0.0), 1.0, 48, 96, false), material);
    scene.add(
        &quad(Vec3::ZERO, Vec3::Y, 6.0),
        Material::diffuse("floor", Colour::constant(0.4)).expect("albedo in [0, 1]"),
    );
    let lamp = Material::diffuse("lamp", Colour::constant(0.0))
        .expect("albedo in [0, 1]")
        .with_emission(Colour::illuminant_rgb([12.0, 11.0, 9.0]).expect("valid radiance"));
    let mut light = quad(Vec3::new(-2.0, 4.5, 2.0), -Vec3::Y, 0.8);
    light.normals.clear();
    scene.add(&light, lamp);
    scene.environment = Some(Environment { radiance: Colour::constant(0.15) });
    scene.camera =
        Some(Camera { eye: Vec3::new(0.0, 2.2, 4.8), center: Vec3::new(0.0, 0.9, 0.0), up: Vec3::Y, fov_y_deg: 32.0 });
    scene
}
