//! A dependency-free mutation fuzzer for the glTF reader
//! ([`tracer::gltf_scene::load_gltf_bytes`], the `gltf` crate underneath), the TOML
//! scene-file reader ([`tracer::scene_file::parse_scene_file`], the `toml` crate
//! underneath), the SPEC reader ([`tracer::spec::parse_spec`], `serde_json`) and the
//! image decoding of textures and environment maps ([`tracer::texture::TextureImage::decode`],
//! [`tracer::envmap::EnvironmentMap::decode`], the `image` crate): glTF files — JSON with data URIs, JSON with an external `.bin`, binary
//! `.glb` — and scene files are mutated at random and loaded from memory; every input must
//! load or fail with an error, never panic (the glTF loader turns a panic of the `gltf`
//! crate into an error that says so, which this counts; the scene-file reader runs under
//! `catch_unwind` here), hang, or allocate out of proportion to its size.
//!
//! An example rather than a cargo-fuzz target for the reasons `fuzz_obj.rs` gives; its
//! short run (the default) executes under `cargo test -p tracer`. A long run:
//!
//! ```sh
//! CARGO_PROFILE_RELEASE_OVERFLOW_CHECKS=true CARGO_PROFILE_RELEASE_DEBUG_ASSERTIONS=true \
//!   CARGO_TARGET_DIR=target/fuzz cargo run --release -p tracer --example fuzz_scenes -- \
//!   --inputs 10000000 --seed 1
//! ```
//!
//! Options: `--inputs N` (default 20000), `--seed S` (default 1), `--shared DIR` (the
//! shared scenes, default `../shared` beside the checkout; without them only the
//! hand-written seeds are used), `--replay K` (run input K alone and write it to
//! `fuzz-gltf-K.*`). Input K is a function of the seed and K alone.

use rng::Pcg32;
use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;
use std::time::{Duration, Instant};
use tracer::gltf_scene::{GltfOptions, load_gltf_bytes};
use tracer::scene_file::parse_scene_file;
use tracer::spec::parse_spec;

#[path = "support/counting_alloc.rs"]
mod counting_alloc;
use counting_alloc::{LIVE, PEAK};

#[global_allocator]
static ALLOCATOR: counting_alloc::Counting = counting_alloc::Counting;

/// A seed: the main file and the files it may name, by file name.
#[derive(Clone)]
struct Seed {
    name: &'static str,
    main: Vec<u8>,
    files: Vec<(String, Vec<u8>)>,
}

/// Standard base64 (RFC 4648), for the hand-written seed's data URI.
fn base64(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for c in bytes.chunks(3) {
        let n = (c[0] as u32) << 16 | (*c.get(1).unwrap_or(&0) as u32) << 8 | *c.get(2).unwrap_or(&0) as u32;
        for k in 0..4 {
            out.push(if k <= c.len() { A[(n >> (18 - 6 * k) & 63) as usize] as char } else { '=' });
        }
    }
    out
}

/// A hand-written file using what the converter reads: a strip with normals and texture
/// coordinates, a node tree with every transform form, cameras, the three light kinds and
/// the material extensions.
fn handwritten() -> Seed {
    let mut bin = Vec::new();
    for v in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0] {
        bin.extend_from_slice(&v.to_le_bytes());
    }
    for _ in 0..4 {
        for v in [0.0f32, 0.0, 1.0] {
            bin.extend_from_slice(&v.to_le_bytes());
        }
    }
    for i in [0u16, 1, 2, 3] {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    for v in [0.0f32, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 1.0] {
        bin.extend_from_slice(&v.to_le_bytes());
    }
    // A 2×2 RGBA PNG for the textures.
    let mut png = Vec::new();
    image::RgbaImage::from_fn(2, 2, |x, y| image::Rgba([x as u8 * 255, y as u8 * 255, 128, 100 + x as u8 * 100]))
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .expect("a PNG in memory");
    let text = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0,3]}}],
"nodes":[{{"mesh":0,"children":[1,2],"scale":[1,2,-1]}},{{"camera":0,"translation":[0,0,3]}},
{{"matrix":[1,0,0,0,0,1,0,0,0,0,1,0,0,1,0,1],"extensions":{{"KHR_lights_punctual":{{"light":0}}}}}},
{{"rotation":[0,0.7071068,0,0.7071068],"mesh":1,"extensions":{{"KHR_lights_punctual":{{"light":1}}}}}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"NORMAL":1,"TEXCOORD_0":3}},"indices":2,"mode":5,"material":0}}]}},
{{"primitives":[{{"attributes":{{"POSITION":0}},"mode":6,"material":1}},{{"attributes":{{"POSITION":0}}}}]}}],
"materials":[{{"pbrMetallicRoughness":{{"baseColorFactor":[1,0.5,0.2,1],"metallicFactor":0,"roughnessFactor":0}},
"extensions":{{"KHR_materials_transmission":{{"transmissionFactor":1}},"KHR_materials_ior":{{"ior":1.4}},
"KHR_materials_volume":{{"attenuationDistance":1,"attenuationColor":[0.5,0.5,1]}}}}}},
{{"emissiveFactor":[1,1,0.5],"extensions":{{"KHR_materials_emissive_strength":{{"emissiveStrength":3}}}},
"pbrMetallicRoughness":{{"baseColorTexture":{{"index":0,"extensions":{{"KHR_texture_transform":{{"offset":[0.1,0],"rotation":0.3,"scale":[2,2]}}}}}},
"metallicRoughnessTexture":{{"index":0}}}},"normalTexture":{{"index":0,"scale":0.5}},"emissiveTexture":{{"index":0}},
"alphaMode":"MASK","alphaCutoff":0.3}}],
"textures":[{{"source":0,"sampler":0}}],"samplers":[{{"wrapS":33648,"wrapT":33071}}],
"images":[{{"uri":"data:image/png;base64,{}"}}],
"cameras":[{{"type":"perspective","perspective":{{"yfov":0.7,"znear":0.1}}}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
{{"bufferView":1,"componentType":5126,"count":4,"type":"VEC3"}},{{"bufferView":2,"componentType":5123,"count":4,"type":"SCALAR"}},
{{"bufferView":3,"componentType":5126,"count":4,"type":"VEC2"}}],
"bufferViews":[{{"buffer":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":48}},{{"buffer":0,"byteOffset":96,"byteLength":8}},
{{"buffer":0,"byteOffset":104,"byteLength":32}}],
"buffers":[{{"byteLength":136,"uri":"data:application/octet-stream;base64,{}"}}],
"extensionsUsed":["KHR_lights_punctual","KHR_materials_transmission","KHR_materials_ior","KHR_materials_volume","KHR_materials_emissive_strength","KHR_texture_transform"],
"extensions":{{"KHR_lights_punctual":{{"lights":[{{"type":"spot","intensity":5,"spot":{{"innerConeAngle":0.1,"outerConeAngle":0.5}}}},
{{"type":"directional","color":[1,0.9,0.8],"intensity":2}}]}}}}}}"#,
        base64(&png),
        base64(&bin)
    );
    Seed { name: "handwritten.gltf", main: text.into_bytes(), files: Vec::new() }
}

/// A SPEC file in the thesis's format (its listing 8.7, completed).
const SPEC_FILE: &str = r#"{
    "materials": { "Metal": { "diff": "golden", "spec": "golden" }, "Floor": { "diff": "grey" } },
    "sky": "CIE_D65",
    "spectra": {
        "CIE_D65": { "380": 0.444027773062, "385": 0.463859369164, "770": 0.552525209656, "775": 0.537999524666 },
        "golden": { "380": 0.36, "500": 0.45, "550": 0.78, "775": 0.98 },
        "grey": { "380.0": 0.5, "775.0": 0.5 }
    }
}"#;

/// A scene file with every kind of entry but meshes (which would read files).
const SCENE_FILE: &str = r#"
[camera]
eye = [0, 1, 5]
center = [0, 1, 0]
up = [0, 1, 0]
fov = 45

[materials.gold]
model = "roughconductor"
metal = "gold"
alpha = 0.2

[materials.lamp]
model = "lambert"
reflectance = { table = { "400" = 0.2, "700" = 0.6 }, scale = 0.5 }
emission = { blackbody = 3000, scale = 4 }

[materials.glass]
model = "dielectric"
ior = 1.33
dispersion = "bk7"

[[shape]]
type = "sphere"
center = [0, 3, 0]
radius = 0.25
material = "lamp"

[[shape]]
type = "box"
min = [-1, 0, -1]
max = [-0.5, 0.5, -0.5]
material = "gold"

[[shape]]
type = "polygon"
vertices = [[-4, 0, -4], [-4, 0, 4], [4, 0, 4], [4, 0, -4]]
material = "gold"

[[shape]]
type = "implicit"
expression = "x^4 + y^2 + z^2 - 0.25"
min = [-0.5, -0.5, -0.5]
max = [0.5, 0.5, 0.5]
material = "glass"

[[light]]
type = "spot"
position = [0, 4, 0]
direction = [0, -1, 0]
inner = 10
outer = 20
intensity = [1, 2, 3]

[[light]]
type = "sun"
direction = [-1, -2, -1]
irradiance = 3

[sky]
radiance = { spectrum = "D65", scale = 0.3 }

[render]
width = 64
spp = 4
spectral = "bins40"
"#;

fn seeds(shared: &Path) -> Vec<Seed> {
    let mut out = vec![
        handwritten(),
        Seed { name: "scene.toml", main: SCENE_FILE.as_bytes().to_vec(), files: Vec::new() },
        Seed { name: "metal.spec", main: SPEC_FILE.as_bytes().to_vec(), files: Vec::new() },
    ];
    // Images, as textures and environment maps: small PNG, JPEG and EXR files written here,
    // and the smallest of Sponza's JPEGs.
    let encode = |format: image::ImageFormat, image: image::DynamicImage| {
        let mut bytes = Vec::new();
        image.write_to(&mut std::io::Cursor::new(&mut bytes), format).map(|_| bytes).ok()
    };
    let gradient = image::RgbaImage::from_fn(7, 5, |x, y| image::Rgba([x as u8 * 30, y as u8 * 40, 128, 200]));
    let rgb = image::DynamicImage::ImageRgba8(gradient.clone()).to_rgb8();
    let hdr = image::Rgb32FImage::from_fn(8, 4, |x, y| image::Rgb([x as f32, y as f32 * 10.0, 0.5]));
    for (name, bytes) in [
        ("t.png", encode(image::ImageFormat::Png, image::DynamicImage::ImageRgba8(gradient))),
        ("t.jpg", encode(image::ImageFormat::Jpeg, image::DynamicImage::ImageRgb8(rgb))),
        ("t.exr", encode(image::ImageFormat::OpenExr, image::DynamicImage::ImageRgb32F(hdr))),
        ("s.jpg", std::fs::read(shared.join("scenes/sponza/01_s_ba.jpg")).ok()),
    ] {
        if let Some(main) = bytes {
            out.push(Seed { name, main, files: Vec::new() });
        }
    }
    let dir = shared.join("scenes/gltf-box");
    let read = |f: &str| std::fs::read(dir.join(f)).ok();
    if let (Some(gltf), Some(bin), Some(glb)) = (read("Box.gltf"), read("Box0.bin"), read("Box.glb")) {
        out.push(Seed { name: "Box.gltf", main: gltf, files: vec![("Box0.bin".into(), bin)] });
        out.push(Seed { name: "Box.glb", main: glb, files: Vec::new() });
    } else {
        eprintln!("note: {} is absent; fuzzing the hand-written seeds only", dir.display());
    }
    out
}

/// Values that break parsers: limits, zero, negatives, fractions where integers belong.
const NUMBERS: [&str; 14] = [
    "0",
    "-1",
    "1",
    "2",
    "3",
    "255",
    "65535",
    "4294967295",
    "2147483648",
    "1e38",
    "-1e38",
    "1e-45",
    "0.5",
    "18446744073709551616",
];

/// Applies 1–4 random mutations to `bytes`.
fn mutate(rng: &mut Pcg32, bytes: &mut Vec<u8>) {
    for _ in 0..1 + rng.next_u32() % 4 {
        let len = bytes.len();
        let at = if len == 0 { 0 } else { rng.next_u32() as usize % len };
        match rng.next_u32() % 8 {
            0 if len > 0 => bytes[at] ^= 1 << (rng.next_u32() % 8),
            1 if len > 0 => bytes[at] = rng.next_u32() as u8,
            2 if len > 0 => {
                let n = (1 + rng.next_u32() as usize % 16).min(len - at);
                bytes.drain(at..at + n);
            }
            3 if len > 0 => {
                let n = (1 + rng.next_u32() as usize % 64).min(len - at);
                let span: Vec<u8> = bytes[at..at + n].to_vec();
                let to = rng.next_u32() as usize % (len + 1);
                bytes.splice(to..to, span);
            }
            4 => bytes.truncate(at),
            5 | 6 => {
                // Replace the number (ASCII digits, signs, exponents) around `at`.
                let is_num = |b: u8| b.is_ascii_digit() || b == b'-' || b == b'.' || b == b'e' || b == b'+';
                if let Some(start) = (at..len).find(|&i| bytes[i].is_ascii_digit()) {
                    let end = (start..len).find(|&i| !is_num(bytes[i])).unwrap_or(len);
                    let value = NUMBERS[rng.next_u32() as usize % NUMBERS.len()].as_bytes();
                    bytes.splice(start..end, value.iter().copied());
                }
            }
            _ if len >= 4 => {
                // A little-endian u32 at a 4-aligned offset (GLB headers, chunk lengths,
                // binary indices).
                let at = at & !3;
                if at + 4 <= len {
                    let v = [0u32, 1, 3, 4, 0xffff, 0x7fff_ffff, 0xffff_ffff, len as u32][rng.next_u32() as usize % 8];
                    bytes[at..at + 4].copy_from_slice(&v.to_le_bytes());
                }
            }
            _ => {}
        }
    }
}

/// What a run found.
struct Run {
    tried: u64,
    loaded: u64,
    failures: Vec<String>,
}

/// Runs inputs 0..`inputs` of `seed`, stopping after 20 failures.
fn run(seeds: &[Seed], seed: u64, inputs: u64) -> Run {
    let mut r = Run { tried: 0, loaded: 0, failures: Vec::new() };
    for k in 0..inputs {
        r.tried += 1;
        let s = input(seeds, seed, k);
        match check(&s, k.is_multiple_of(5)) {
            Err(what) => r.failures.push(format!("input {k} ({}): {what}", s.name)),
            Ok(ok) => r.loaded += ok as u64,
        }
        if r.failures.len() >= 20 {
            break;
        }
    }
    r
}

/// Input `k`: the seed it mutates, and its main and named files.
fn input(seeds: &[Seed], seed: u64, k: u64) -> Seed {
    let mut rng = Pcg32::seed_from_u64(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ k);
    let mut s = seeds[rng.next_u32() as usize % seeds.len()].clone();
    if !s.files.is_empty() && rng.next_u32().is_multiple_of(8) {
        let i = rng.next_u32() as usize % s.files.len();
        mutate(&mut rng, &mut s.files[i].1);
    } else {
        mutate(&mut rng, &mut s.main);
    }
    s
}

/// Whether one input loaded, or what went wrong with it.
fn check(s: &Seed, camera: bool) -> Result<bool, String> {
    let path = PathBuf::from("fuzz").join(s.name);
    let read = |p: &Path| -> std::io::Result<Vec<u8>> {
        let name = p.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        match s.files.iter().find(|(n, _)| *n == name) {
            Some((_, bytes)) => Ok(bytes.clone()),
            None => Err(std::io::ErrorKind::NotFound.into()),
        }
    };
    let options = GltfOptions { camera: camera.then(|| "0".to_string()) };
    let size = s.main.len() + s.files.iter().map(|(_, b)| b.len()).sum::<usize>();
    PEAK.store(LIVE.load(Ordering::Relaxed), Ordering::Relaxed);
    let before = LIVE.load(Ordering::Relaxed);
    let start = Instant::now();
    let result = if s.name.ends_with(".spec") {
        // Parsed, then applied to a scene with the materials it names.
        let text = String::from_utf8_lossy(&s.main);
        let run = || -> tracer::Result<()> {
            let spec = parse_spec(&text, &path)?;
            let mut scene = tracer::Scene::default();
            for name in ["Metal", "Floor"] {
                scene
                    .materials
                    .push(tracer::material::Material::diffuse(name, spectral::spectrum::Colour::constant(0.5))?);
            }
            spec.apply(&mut scene).map(|_| ())
        };
        match std::panic::catch_unwind(run) {
            Ok(r) => r,
            Err(_) => return Err("panic in the SPEC reader".into()),
        }
    } else if [".png", ".jpg", ".exr"].iter().any(|e| s.name.ends_with(e)) {
        // Texture and environment-map decoding (`image` underneath, bounded by the file's
        // size): errors are fine, panics are caught and reported as such.
        let texture = tracer::texture::TextureImage::decode(&s.main);
        let map = tracer::envmap::EnvironmentMap::decode(&s.main, 10.0);
        for e in [texture.as_ref().err(), map.as_ref().err()].into_iter().flatten() {
            if e.contains("decoder failed") {
                return Err(format!("panic: {e}"));
            }
        }
        texture.map(drop).map_err(tracer::Error::Setting)
    } else if s.name.ends_with(".toml") {
        // The scene-file reader has no panic guard of its own (it needs none): a panic
        // here is counted as one.
        let text = String::from_utf8_lossy(&s.main);
        match std::panic::catch_unwind(|| parse_scene_file(&text, &path).map(|_| ())) {
            Ok(r) => r,
            Err(_) => return Err("panic in the scene-file reader".into()),
        }
    } else {
        load_gltf_bytes(&s.main, &path, &options, &read).map(|_| ())
    };
    let took = start.elapsed();
    let peak = PEAK.load(Ordering::Relaxed).saturating_sub(before);
    if let Err(e) = &result {
        let e = e.to_string();
        if e.contains("panicked") {
            return Err(format!("panic: {e}"));
        }
    }
    if took > Duration::from_secs(2) {
        return Err(format!("slow: {took:?}"));
    }
    // Everything the converter keeps is proportional to the input (scene arrays are at
    // most a few hundred bytes per input byte for these small seeds).
    // An image may decode to up to 1 M + 1024 pixels per byte of file (see
    // `texture::decode_image`), as f32 RGBA and then RGBA8 and f32 RGB.
    let image = [".png", ".jpg", ".exr"].iter().any(|e| s.name.ends_with(e));
    let allowed = if image { 3 * 16 * ((1 << 20) + 1024 * size) } else { (1 << 20) + 1000 * size };
    if peak > allowed {
        return Err(format!("allocated {peak} bytes for a {size}-byte input"));
    }
    Ok(result.is_ok())
}

fn main() {
    let mut args = std::env::args().skip(1);
    let (mut inputs, mut seed, mut replay) = (20_000u64, 1u64, None);
    let mut shared = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared");
    while let Some(a) = args.next() {
        let mut value = || args.next().unwrap_or_else(|| panic!("{a} needs a value"));
        match a.as_str() {
            "--inputs" => inputs = value().parse().expect("--inputs N"),
            "--seed" => seed = value().parse().expect("--seed S"),
            "--shared" => shared = PathBuf::from(value()),
            "--replay" => replay = Some(value().parse::<u64>().expect("--replay K")),
            // `cargo test` passes the harness's flags to examples run as tests.
            _ => {}
        }
    }
    let seeds = seeds(&shared);
    if let Some(k) = replay {
        let s = input(&seeds, seed, k);
        let file = format!("fuzz-gltf-{k}-{}", s.name);
        std::fs::write(&file, &s.main).expect("write the input");
        println!("input {k} ({} bytes) written to {file}: {:?}", s.main.len(), check(&s, k.is_multiple_of(5)));
        return;
    }
    // Panics are counted through the loader's error; their messages would flood the run
    // (a replay keeps them, with the backtrace RUST_BACKTRACE asks for).
    std::panic::set_hook(Box::new(|_| {}));
    let start = Instant::now();
    let Run { tried, loaded, failures } = run(&seeds, seed, inputs);
    let secs = start.elapsed().as_secs_f64();
    println!(
        "fuzz_scenes: {tried} inputs (seed {seed}, {} seeds) in {secs:.1} s ({:.0}/s); {loaded} inputs loaded; {} failures",
        seeds.len(),
        tried as f64 / secs,
        failures.len()
    );
    for f in &failures {
        println!("  {f}");
    }
    if !failures.is_empty() {
        std::process::exit(1);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_seed_loads_and_twenty_thousand_mutations_do_not_panic() {
        let seeds = seeds(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared"));
        for s in &seeds {
            assert_eq!(check(s, false), Ok(true), "seed {} does not load", s.name);
        }
        let r = run(&seeds, 1, 20_000);
        assert!(r.failures.is_empty(), "{:#?}", r.failures);
        // The mutations are not all fatal: some inputs still load.
        assert!(r.loaded > 200, "only {} of {} inputs loaded", r.loaded, r.tried);
    }
}
