//! Built-in scenes.

use crate::camera::Camera;
use crate::geometry::ShapeKind;
use crate::material::Material;
use crate::mesh::{quad, smooth_normals, uv_sphere};
use crate::scene::{Environment, Scene};
use crate::{Error, Result};
use brdf::models::{ConductorParams, MetalPreset};
use glam::Vec3;
use shapes::ShapeError;
use shapes::implicit::Implicit;
use shapes::polygon::{InsideTest, Polygon};
use shapes::roots::RootSolver;
use shapes::sphere::{Sphere, SphereMethod};
use spectral::spectrum::Colour;
use std::f32::consts::TAU;
use std::path::Path;

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
    scene.environment = Some(Environment::uniform(Colour::constant(0.15)));
    scene.camera =
        Some(Camera { eye: Vec3::new(0.0, 2.2, 4.8), center: Vec3::new(0.0, 0.9, 0.0), up: Vec3::Y, fov_y_deg: 32.0 });
    scene
}

/// The sphere flake of Haines's Standard Procedural Databases (IEEE CG&A 7(11), 1987): a
/// sphere carrying nine spheres of a third of its radius — six around its equator and
/// three above — each carrying nine more, `level` times: (9^(level+1) − 1)/8 spheres
/// (level 4: 7381, the SPD's default "balls" size). Silver spheres on a grey polygon
/// floor, a warm spherical lamp and a dim sky.
pub fn sphere_flake(level: u32) -> Result<Scene> {
    if level > 6 {
        return Err(Error::Setting(format!(
            "sphere flake level {level} would make {} spheres; at most 6 (597 871)",
            (9u64.pow(level + 1) - 1) / 8
        )));
    }
    let mut scene = Scene::default();
    let silver = scene.materials.len() as u32;
    scene.materials.push(metal("silver", MetalPreset::Silver));
    let mut stack = vec![(Vec3::new(0.0, 0.5, 0.0), 0.5f32, Vec3::Y, 0u32)];
    while let Some((centre, radius, axis, depth)) = stack.pop() {
        scene.add_shape_with_material(ShapeKind::Sphere(sphere(centre, radius)?), silver);
        if depth == level {
            continue;
        }
        let (b1, b2) = axis.any_orthonormal_pair();
        let child = radius / 3.0;
        // Six around the equator, three above at 60° elevation, turned by 30° so that
        // they sit between the equatorial ones.
        let dirs = (0..6)
            .map(|k| (k as f32 * TAU / 6.0, 0.0f32))
            .chain((0..3).map(|k| (k as f32 * TAU / 3.0 + TAU / 12.0, 60f32.to_radians())));
        for (phi, elevation) in dirs {
            let dir = (elevation.cos() * (phi.cos() * b1 + phi.sin() * b2) + elevation.sin() * axis).normalize();
            stack.push((centre + dir * (radius + child), child, dir, depth + 1));
        }
    }
    add_floor(&mut scene, 0.0, 4.0)?;
    add_lamp(&mut scene, Vec3::new(-2.5, 3.5, 2.5), 0.5)?;
    scene.environment = Some(Environment::uniform(Colour::constant(0.1)));
    scene.camera =
        Some(Camera { eye: Vec3::new(2.1, 1.6, 2.6), center: Vec3::new(0.0, 0.55, 0.0), up: Vec3::Y, fov_y_deg: 35.0 });
    Ok(scene)
}

/// A glass torus (the implicit quartic (x² + y² + z² + R² − r²)² = 4R²(x² + y²), solved
/// by `solver`) standing on a grey polygon floor beside a spherical lamp: refraction
/// through a surface no triangle approximates.
pub fn glass_torus(solver: RootSolver) -> Result<Scene> {
    let mut scene = Scene::default();
    let torus = Implicit::torus(0.8, 0.3, solver).map_err(shape_error)?;
    // Stand it up: the torus's axis is z; a quarter turn about x would need a transform,
    // so the camera looks along y instead and the floor is the plane z = −1.1.
    scene.add_shape(ShapeKind::Implicit(torus), glass(1.5)?);
    add_floor_z(&mut scene, -1.1, 4.0)?;
    add_lamp(&mut scene, Vec3::new(-2.0, -2.0, 2.5), 0.4)?;
    scene.environment = Some(Environment::uniform(Colour::constant(0.2)));
    scene.camera = Some(Camera {
        eye: Vec3::new(0.0, -3.6, 1.6),
        center: Vec3::new(0.0, 0.0, -0.2),
        up: Vec3::Z,
        fov_y_deg: 40.0,
    });
    Ok(scene)
}

/// The Stanford bunny in glass with smooth (area-weighted) vertex normals, on a grey
/// floor beside a spherical lamp: the test of shading normals on refraction — black
/// silhouettes or lost exits show at once. `obj` is the bunny's OBJ (any mesh works);
/// it is scaled to unit height and stood on the floor.
pub fn glass_bunny(obj: &Path) -> Result<Scene> {
    let mesh_scene = crate::obj::load_obj(obj)?;
    if mesh_scene.triangles.is_empty() {
        return Err(Error::Setting(format!("{}: no triangles", obj.display())));
    }
    let b = mesh_scene.bounds();
    let scale = 1.0 / b.extent().y.max(1e-12);
    let offset = Vec3::new(-b.centre().x, -b.min.y, -b.centre().z);
    let positions: Vec<Vec3> = mesh_scene.positions.iter().map(|p| (Vec3::from_array(*p) + offset) * scale).collect();
    let normals = smooth_normals(&positions, &mesh_scene.triangles);
    let mesh = crate::mesh::Mesh { positions, normals, tangents: vec![], uvs: vec![], triangles: mesh_scene.triangles };
    let mut scene = Scene::default();
    scene.add(&mesh, glass(1.5)?);
    add_floor(&mut scene, 0.0, 4.0)?;
    add_lamp(&mut scene, Vec3::new(-1.5, 2.5, 1.5), 0.35)?;
    scene.environment = Some(Environment::uniform(Colour::constant(0.2)));
    scene.camera =
        Some(Camera { eye: Vec3::new(0.0, 0.7, 2.6), center: Vec3::new(0.0, 0.45, 0.0), up: Vec3::Y, fov_y_deg: 35.0 });
    Ok(scene)
}

/// A built-in scene by name: `sphereflake[:LEVEL]` (default level 3), `glass-torus`
/// (the quartic solved in closed form: 2.2× faster than Laguerre's method on this scene
/// and as accurate, see `docs/shapes.md`), `glass-torus-laguerre` (the same by
/// Laguerre's method), `glass-bunny[:OBJ]` (default `../shared/scenes/bunny/bunny.obj`).
pub fn builtin(spec: &str) -> Result<Scene> {
    let (name, arg) = spec.split_once(':').map_or((spec, None), |(n, a)| (n, Some(a)));
    match name {
        "sphereflake" => {
            let level = match arg {
                None => 3,
                Some(a) => {
                    a.parse().map_err(|_| Error::Setting(format!("sphere flake level '{a}' is not a whole number")))?
                }
            };
            sphere_flake(level)
        }
        "glass-torus" if arg.is_none() => glass_torus(RootSolver::ClosedForm),
        "glass-torus-laguerre" if arg.is_none() => glass_torus(RootSolver::Laguerre { polish: true }),
        "glass-bunny" => glass_bunny(Path::new(arg.unwrap_or("../shared/scenes/bunny/bunny.obj"))),
        _ => Err(Error::Setting(format!("unknown built-in scene '{spec}' (known: {})", BUILTIN_SCENES.join(", ")))),
    }
}

/// Names accepted by [`builtin`], for messages.
pub const BUILTIN_SCENES: [&str; 4] =
    ["sphereflake[:LEVEL]", "glass-torus", "glass-torus-laguerre", "glass-bunny[:OBJ]"];

fn shape_error(e: ShapeError) -> Error {
    Error::Setting(e.to_string())
}

fn sphere(centre: Vec3, radius: f32) -> Result<Sphere> {
    Sphere::new(centre, radius, SphereMethod::default()).map_err(shape_error)
}

fn metal(name: &str, preset: MetalPreset) -> Material {
    Material::from_params(name, ConductorParams { metal: preset, ..Default::default() }.into())
}

fn glass(ior: f32) -> Result<Material> {
    Material::dielectric("glass", ior).map_err(|e| Error::Setting(e.to_string()))
}

/// A square grey floor of half-size `half` at height `y`, as one polygon facing up.
fn add_floor(scene: &mut Scene, y: f32, half: f32) -> Result<()> {
    let h = half;
    let corners = vec![Vec3::new(-h, y, -h), Vec3::new(-h, y, h), Vec3::new(h, y, h), Vec3::new(h, y, -h)];
    let floor = Polygon::new(corners, InsideTest::default()).map_err(shape_error)?;
    scene.add_shape(
        ShapeKind::Polygon(floor),
        Material::diffuse("floor", Colour::constant(0.5)).expect("albedo in [0, 1]"),
    );
    Ok(())
}

/// As [`add_floor`], in the plane z = `z`, facing +z.
fn add_floor_z(scene: &mut Scene, z: f32, half: f32) -> Result<()> {
    let h = half;
    let corners = vec![Vec3::new(-h, -h, z), Vec3::new(h, -h, z), Vec3::new(h, h, z), Vec3::new(-h, h, z)];
    let floor = Polygon::new(corners, InsideTest::default()).map_err(shape_error)?;
    scene.add_shape(
        ShapeKind::Polygon(floor),
        Material::diffuse("floor", Colour::constant(0.5)).expect("albedo in [0, 1]"),
    );
    Ok(())
}

/// A warm spherical area light.
fn add_lamp(scene: &mut Scene, centre: Vec3, radius: f32) -> Result<()> {
    let lamp = Material::diffuse("lamp", Colour::constant(0.0))
        .expect("albedo in [0, 1]")
        .with_emission(Colour::illuminant_rgb([9.0, 8.0, 6.5]).expect("valid radiance"));
    scene.add_shape(ShapeKind::Sphere(sphere(centre, radius)?), lamp);
    Ok(())
}
