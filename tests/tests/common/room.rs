//! The glowing room: a closed, flat-shaded sphere of radius 1 whose Lambertian walls of
//! albedo ρ emit Le everywhere, so that its radiance is Le / (1 − ρ) at every point and in
//! every direction (the Neumann series Le·Σρᵏ) — the analytic answer of the whole-system
//! tests (`analytic.rs`, `bdpt.rs`) and of the GPU's (`crates/gpu/tests/equivalence.rs`
//! includes this file).

use glam::Vec3;
use spectral::spectrum::Colour;
use tracer::camera::Camera;
use tracer::material::Material;
use tracer::mesh::uv_sphere;
use tracer::scene::Scene;

/// The room of albedo `albedo` emitting `le`, seen from inside by its camera.
pub fn glowing_room(albedo: f32, le: f32) -> Scene {
    let mut scene = Scene::default();
    let wall = Material::diffuse("wall", Colour::constant(albedo)).unwrap().with_emission(Colour::constant(le));
    // Flat-shaded: the analytic answer holds for the faceted room with its true normals.
    // (Interpolated shading normals do not conserve energy exactly; see the notes.)
    let mut room = uv_sphere(Vec3::ZERO, 1.0, 24, 48, true);
    room.normals.clear();
    scene.add(&room, wall);
    scene.camera =
        Some(Camera { eye: Vec3::new(0.1, 0.2, 0.3), center: Vec3::new(0.0, 0.0, -1.0), up: Vec3::Y, fov_y_deg: 90.0 });
    scene
}
