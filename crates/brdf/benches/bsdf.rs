#![allow(missing_docs)] // criterion_group! generates undocumented public items
//! ns per `eval` and per `sample` of every BSDF model, at hero wavelengths (N = 4), with
//! default parameters: `bsdf_eval/<model>` and `bsdf_sample/<model>`.

use brdf::Bsdf;
use brdf::models::*;
use brdf::params::ModelDef;
use criterion::{Criterion, criterion_group, criterion_main};
use glam::{Vec2, Vec3};
use spectral::SampledWavelengths;
use std::hint::black_box;
use std::time::Duration;

/// 256 fixed direction pairs and sample inputs, so every model sees the same work.
fn inputs() -> Vec<(Vec3, Vec3, f32, Vec2)> {
    let mut s = 0x2545_F491_4F6C_DD1Du64;
    let mut next = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 40) as f32 / (1u64 << 24) as f32
    };
    let mut dir = move || brdf::sampling::cosine_hemisphere(Vec2::new(next(), next()));
    let mut s2 = 0x9E37_79B9_7F4A_7C15u64;
    let mut u = move || {
        s2 ^= s2 << 13;
        s2 ^= s2 >> 7;
        s2 ^= s2 << 17;
        (s2 >> 40) as f32 / (1u64 << 24) as f32
    };
    (0..256).map(|_| (dir(), dir(), u(), Vec2::new(u(), u()))).collect()
}

fn bench_model<B: Bsdf<4>>(c: &mut Criterion, def: &ModelDef, bsdf: B) {
    let data = inputs();
    c.bench_function(&format!("bsdf_eval/{}", def.name), |b| {
        b.iter(|| {
            for &(wo, wi, _, _) in &data {
                black_box(bsdf.eval(black_box(wo), black_box(wi)));
            }
        })
    });
    c.bench_function(&format!("bsdf_sample/{}", def.name), |b| {
        b.iter(|| {
            for &(wo, _, uc, u) in &data {
                black_box(bsdf.sample(black_box(wo), uc, u));
            }
        })
    });
}

fn benches(c: &mut Criterion) {
    let wl = SampledWavelengths::<4>::sample_hero(0.37);
    macro_rules! model {
        ($def:expr, $ty:ident) => {
            bench_model(c, &$def, $ty::from_params(&$def.defaults(), &wl))
        };
    }
    model!(lambert::DEF, Lambert);
    model!(mirror::DEF, Mirror);
    model!(dielectric::DEF, Dielectric);
    model!(conductor::DEF, SmoothConductor);
    model!(microfacet::ROUGH_CONDUCTOR_DEF, RoughConductor);
    model!(microfacet::ROUGH_DIELECTRIC_DEF, RoughDielectric);
    model!(oren_nayar::DEF, OrenNayar);
    model!(schlick::DEF, Schlick);
    model!(ashikhmin::DEF, AshikhminShirley);
}

criterion_group! {
    name = bsdf;
    config = Criterion::default().sample_size(20).warm_up_time(Duration::from_millis(500)).measurement_time(Duration::from_secs(1));
    targets = benches
}
criterion_main!(bsdf);
