#![allow(missing_docs)] // criterion_group! generates undocumented public items
//! ns per texture lookup at a hit, over 4096 random texture coordinates on a 1024² sRGB
//! image: the bilinear RGBA fetch alone (`texture/fetch`), the base colour as a hero-mode
//! spectrum of four wavelengths (`texture/base_colour_hero`: fetch, uplift-table lookup,
//! four sigmoids) and in RGB mode (`texture/base_colour_rgb`), and a normal map's bent
//! normal (`texture/normal_map`).

use criterion::{Criterion, criterion_group, criterion_main};
use glam::{Vec2, Vec3};
use rng::Pcg32;
use spectral::SampledWavelengths;
use std::hint::black_box;
use std::sync::Arc;
use std::time::Duration;
use tracer::texture::{Encoding, MaterialTextures, NormalMap, TextureImage, TextureMap};

fn image() -> Arc<TextureImage> {
    let mut rng = Pcg32::seed_from_u64(1);
    let texels = (0..1024 * 1024).map(|_| [0, 1, 2, 3].map(|_| (rng.next_u32() >> 24) as u8)).collect();
    Arc::new(TextureImage::from_rgba8(1024, 1024, texels).unwrap())
}

fn benches(c: &mut Criterion) {
    let image = image();
    let map = TextureMap::new(image.clone(), Encoding::Srgb);
    let textures = MaterialTextures {
        base_colour: Some(map.clone()),
        normal: Some(NormalMap { map: TextureMap::new(image, Encoding::Linear), scale: 1.0 }),
        ..Default::default()
    };
    let mut rng = Pcg32::seed_from_u64(2);
    let uvs: Vec<Vec2> = (0..4096).map(|_| Vec2::new(rng.next_f32() * 3.0, rng.next_f32() * 3.0)).collect();
    let hero = SampledWavelengths::<4>::sample_hero(0.3);
    let rgb = SampledWavelengths::<3>::rgb();
    spectral::uplift::uplift_table();
    let mut g = c.benchmark_group("texture");
    g.bench_function("fetch", |b| b.iter(|| uvs.iter().map(|&uv| map.sample(black_box(uv))[1]).sum::<f32>()));
    g.bench_function("base_colour_hero", |b| {
        b.iter(|| uvs.iter().map(|&uv| textures.texels(black_box(uv), &hero).base_colour.unwrap().0[0]).sum::<f32>())
    });
    g.bench_function("base_colour_rgb", |b| {
        b.iter(|| uvs.iter().map(|&uv| textures.texels(black_box(uv), &rgb).base_colour.unwrap().0[0]).sum::<f32>())
    });
    g.bench_function("normal_map", |b| {
        b.iter(|| uvs.iter().map(|&uv| textures.bent_normal(black_box(uv), Vec3::Y, Vec3::X, Vec3::Z).x).sum::<f32>())
    });
    g.finish();
}

criterion_group! {
    name = texture;
    config = Criterion::default().sample_size(10).warm_up_time(Duration::from_millis(300)).measurement_time(Duration::from_secs(2));
    targets = benches
}
criterion_main!(texture);
