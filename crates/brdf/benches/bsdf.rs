#![allow(missing_docs)] // criterion_group! generates undocumented public items
//! ns per `eval` and per `sample` of every BSDF model, at hero wavelengths (N = 4), with
//! default parameters: `bsdf_eval/<model>` and `bsdf_sample/<model>`.

use brdf::{Bsdf, ModelId};
use criterion::{Criterion, criterion_group, criterion_main};
use glam::{Vec2, Vec3};
use rng::Pcg32;
use spectral::SampledWavelengths;
use std::hint::black_box;
use std::time::Duration;

/// 256 fixed direction pairs and sample inputs, so every model sees the same work.
fn inputs() -> Vec<(Vec3, Vec3, f32, Vec2)> {
    let mut rng = Pcg32::seed_from_u64(0x2545_F491_4F6C_DD1D);
    let mut u2 = move || Vec2::new(rng.next_f32(), rng.next_f32());
    (0..256)
        .map(|_| {
            let wo = brdf::sampling::cosine_hemisphere(u2());
            let wi = brdf::sampling::cosine_hemisphere(u2());
            (wo, wi, u2().x, u2())
        })
        .collect()
}

/// Every registered model at its defaults, through the registry's dispatch (as the
/// renderer calls it).
fn benches(c: &mut Criterion) {
    let wl = SampledWavelengths::<4>::sample_hero(0.37);
    let data = inputs();
    for &model in ModelId::ALL {
        let bsdf = model.defaults().bsdf(&wl);
        c.bench_function(&format!("bsdf_eval/{}", model.name()), |b| {
            b.iter(|| {
                for &(wo, wi, _, _) in &data {
                    black_box(bsdf.eval(black_box(wo), black_box(wi)));
                }
            })
        });
        c.bench_function(&format!("bsdf_sample/{}", model.name()), |b| {
            b.iter(|| {
                for &(wo, _, uc, u) in &data {
                    black_box(bsdf.sample(black_box(wo), uc, u));
                }
            })
        });
    }
}

criterion_group! {
    name = bsdf;
    config = Criterion::default().sample_size(20).warm_up_time(Duration::from_millis(500)).measurement_time(Duration::from_secs(1));
    targets = benches
}
criterion_main!(bsdf);
