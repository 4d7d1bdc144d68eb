//! Textures end to end: a checkerboard read back through a render, alpha cut-outs and
//! stochastic transparency in shadow and camera rays, MTL and glTF files with textures.
//!
//! The measuring set-up is `punctual.rs`'s: a Lambertian floor under a sun straight
//! overhead of irradiance E has radiance ρ/π · E, exactly, in RGB mode (one light, one
//! shadow ray, every BSDF-sampled ray escapes), so a texture's value is read back exactly.

use glam::{Vec2, Vec3};
use spectral::SampledWavelengths;
use spectral::spectrum::Colour;
use std::path::Path;
use std::sync::Arc;
use tracer::integrator::{Integrator, PathCounters, PathSettings};
use tracer::material::Material;
use tracer::mesh::Mesh;
use tracer::texture::{Alpha, AlphaMode, Encoding, MaterialTextures, TextureImage, TextureMap};
use tracer::{CpuBackend, CpuScene, PathTracer, PunctualLight, Scene, SceneOptions};

/// E = π: the floor's radiance is its albedo.
const SUN: f32 = std::f32::consts::PI;

/// The square [−1, 1]² at height `y`, facing up, u = (x + 1)/2 and v = (z + 1)/2.
fn square(y: f32) -> Mesh {
    let p = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
    Mesh {
        positions: p.iter().map(|&(x, z)| Vec3::new(x, y, z)).collect(),
        normals: vec![Vec3::Y; 4],
        tangents: Vec::new(),
        uvs: p.iter().map(|&(x, z)| Vec2::new((x + 1.0) / 2.0, (z + 1.0) / 2.0)).collect(),
        triangles: vec![[0, 3, 2], [0, 2, 1]],
    }
}

fn image(width: u32, height: u32, texel: impl Fn(u32, u32) -> [u8; 4]) -> Arc<TextureImage> {
    let texels = (0..height).flat_map(|y| (0..width).map(move |x| (x, y))).map(|(x, y)| texel(x, y)).collect();
    Arc::new(TextureImage::from_rgba8(width, height, texels).unwrap())
}

fn prepare(scene: Scene) -> CpuScene {
    CpuBackend::new(1).unwrap().prepare_cpu(scene, &SceneOptions::default()).unwrap()
}

fn sun_overhead() -> PunctualLight {
    PunctualLight::directional(-Vec3::Y, Colour::constant(SUN))
}

/// The RGB radiance seen looking straight down at (x, ·, z) from `height`.
fn radiance_at(prepared: &CpuScene, x: f32, z: f32, height: f32) -> [f32; 3] {
    let view = prepared.view();
    let ray = bvh::Ray::new(Vec3::new(x, height, z), -Vec3::Y);
    let mut wl = SampledWavelengths::<3>::rgb();
    let mut sampler = rng::Pcg32::seed_from_u64(3);
    let settings = PathSettings::default();
    PathTracer.radiance(&view, ray, &mut wl, &settings, &mut sampler, &mut PathCounters::default()).0
}

/// The decoded value of an sRGB byte (IEC 61966-2-1), written out here.
fn srgb(byte: u8) -> f32 {
    let c = byte as f32 / 255.0;
    if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) }
}

#[test]
fn a_checkerboard_is_read_back_texel_for_texel() {
    // 4×4 texels: red-ish and blue-ish squares, each with its own shade by position.
    let texel = |x: u32, y: u32| {
        let k = (x + 4 * y) as u8;
        if (x + y).is_multiple_of(2) { [200, 40 + k, 10, 255] } else { [20, 90, 180 + k, 255] }
    };
    let board = image(4, 4, texel);
    let textures = MaterialTextures { base_colour: Some(TextureMap::new(board, Encoding::Srgb)), ..Default::default() };
    let floor = Material::diffuse("board", Colour::constant(1.0)).unwrap().with_textures(textures);
    let mut scene = Scene::default();
    scene.add(&square(0.0), floor);
    scene.punctual_lights.push(sun_overhead());
    let prepared = prepare(scene);
    for ty in 0..4 {
        for tx in 0..4 {
            // The texel's centre: u = (tx + ½)/4 ⇒ x = 2u − 1.
            let (x, z) = ((tx as f32 + 0.5) / 2.0 - 1.0, (ty as f32 + 0.5) / 2.0 - 1.0);
            let got = radiance_at(&prepared, x, z, 1.0);
            let want = texel(tx, ty).map(srgb);
            for c in 0..3 {
                assert!((got[c] - want[c]).abs() < 2e-5, "texel ({tx}, {ty}) channel {c}: {got:?} vs {want:?}");
            }
        }
    }
}

/// A black card at height 1 over a white floor, its alpha a horizontal ramp from 0 at
/// u = ¼ to 1 at u = ¾ (two texels, bilinear), so alpha = ½ exactly at u = ½ (x = 0).
fn card_over_floor(alpha: Alpha) -> CpuScene {
    let mut scene = Scene::default();
    scene.add(&square(0.0), Material::diffuse("floor", Colour::constant(1.0)).unwrap());
    let card = Material::diffuse("card", Colour::constant(0.0))
        .unwrap()
        .with_textures(MaterialTextures { alpha: Some(alpha), ..Default::default() });
    scene.add(&square(1.0), card);
    scene.punctual_lights.push(sun_overhead());
    prepare(scene)
}

fn ramp() -> TextureMap {
    let mut map = TextureMap::new(image(2, 1, |x, _| [0, 0, 0, if x == 0 { 0 } else { 255 }]), Encoding::Linear);
    map.wrap = [tracer::texture::Wrap::Clamp; 2];
    map
}

#[test]
fn an_alpha_masked_card_lets_light_through_exactly_where_alpha_is_below_the_cutoff() {
    for cutoff in [0.5f32, 0.25] {
        let prepared = card_over_floor(Alpha { mode: AlphaMode::Mask { cutoff }, factor: 1.0, map: Some(ramp()) });
        // alpha(u) = 2u − ½ on [¼, ¾] ⇒ the cut edge is at u = (cutoff + ½)/2, x = 2u − 1.
        let edge = cutoff + 0.5 - 1.0;
        for dx in [-0.3f32, -0.02, -0.002, 0.002, 0.02, 0.3] {
            let x = edge + dx;
            for z in [-0.7f32, 0.1, 0.6] {
                // Shadow rays from the floor: lit where the card is cut away.
                let floor = radiance_at(&prepared, x, z, 0.5)[0];
                let lit = dx < 0.0;
                assert!(
                    if lit { (floor - 1.0).abs() < 1e-5 } else { floor == 0.0 },
                    "cutoff {cutoff}: floor at x = {x} (edge {edge}) has radiance {floor}"
                );
                // Camera rays from above: through the hole they see the lit floor, else the black card.
                let seen = radiance_at(&prepared, x, z, 2.0)[0];
                assert!(
                    if lit { (seen - 1.0).abs() < 1e-5 } else { seen == 0.0 },
                    "cutoff {cutoff}: seen from above at x = {x}: {seen}"
                );
            }
        }
    }
}

#[test]
fn a_blended_card_passes_one_minus_alpha_of_the_light_on_average() {
    let alpha = 0.3;
    let prepared = card_over_floor(Alpha { mode: AlphaMode::Blend, factor: alpha, map: None });
    // Each floor point's shadow ray is its own coin: the mean over many is 1 − α.
    let n = 20_000;
    let lit: f32 = (0..n)
        .map(|i| {
            let (x, z) = ((i % 141) as f32 / 141.0 * 1.8 - 0.9, (i / 141) as f32 / 142.0 * 1.8 - 0.9);
            radiance_at(&prepared, x, z, 0.5)[0]
        })
        .sum::<f32>()
        / n as f32;
    // Binomial σ = √(0.21/20000) = 0.0032: 5σ.
    assert!((lit - (1.0 - alpha)).abs() < 0.016, "mean floor radiance {lit}, expected {}", 1.0 - alpha);
}

fn shared(path: &str) -> Option<std::path::PathBuf> {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/scenes").join(path);
    if p.exists() {
        Some(p)
    } else {
        eprintln!("skipping: {} is absent", p.display());
        None
    }
}

/// Renders a few samples of a scene at 32×32 and returns the film's NaN/Inf count.
fn render_small(mut scene: Scene) -> u64 {
    if !scene.has_lights() {
        scene.environment = Some(tracer::Environment::white_sky(1.0));
    }
    let camera = scene.camera.unwrap_or_else(|| tracer::Camera::framing(&scene.bounds(), 1.0));
    let settings = tracer::RenderSettings { width: 32, height: 32, spp: 4, camera: Some(camera), ..Default::default() };
    let prepared = prepare(scene);
    let (film, stats) = tracer::render(&prepared, &settings, &|_| {}).unwrap();
    let mean = film.mean_rgb();
    assert!(mean.iter().all(|c| c.is_finite()) && mean.iter().sum::<f32>() > 0.0);
    stats.non_finite + film.non_finite
}

#[test]
fn textured_gltf_models_load_their_textures_and_render_finite() {
    for (path, textured) in
        [("gltf-damaged-helmet/DamagedHelmet.glb", 1), ("gltf-suzanne/Suzanne.gltf", 1), ("gltf-box/Box.gltf", 0)]
    {
        let Some(p) = shared(path) else { continue };
        let loaded = tracer::gltf_scene::load_gltf(&p, &Default::default()).unwrap();
        let with = loaded.scene.materials.iter().filter(|m| m.textures.is_some()).count();
        assert_eq!(with, textured, "{path}: {with} textured materials");
        if let Some(t) = loaded.scene.materials.iter().find_map(|m| m.textures.as_ref()) {
            assert!(t.base_colour.is_some() && t.metallic_roughness.is_some(), "{path}: {t:?}");
        }
        assert!(
            !loaded
                .notes
                .iter()
                .any(|n| n.contains("texture") && n.contains("not applied") && !n.contains("occlusion")),
            "{:?}",
            loaded.notes
        );
        assert_eq!(render_small(loaded.scene), 0, "{path}: NaN/Inf samples");
    }
}

#[test]
fn textured_sponza_loads_its_maps_and_renders_finite() {
    let Some(p) = shared("sponza/sponza.obj") else { return };
    let scene = tracer::obj::load_obj(&p).unwrap();
    let textured: Vec<_> = scene.materials.iter().filter_map(|m| m.textures.as_ref()).collect();
    assert!(textured.len() >= 15, "{} textured materials", textured.len());
    assert!(textured.iter().filter(|t| t.bump.is_some()).count() >= 10);
    assert_eq!(render_small(scene), 0, "NaN/Inf samples");
}
