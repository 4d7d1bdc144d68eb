#![allow(missing_docs)] // criterion_group! generates undocumented public items
//! ns per RGB → spectrum uplift: a Gauss–Newton fit (`uplift/fit`) against a lookup in the
//! precomputed table (`uplift/table`), over the same 256 colours; and, once each, outside
//! criterion (printed), the shipped table's decoding (`uplift/table_decode`) and the fit it
//! was written from (`uplift/table_fit`).

use criterion::{Criterion, criterion_group, criterion_main};
use rng::Pcg32;
use spectral::uplift::{UpliftTable, fit_reflectance, uplift_table};
use std::hint::black_box;
use std::time::{Duration, Instant};

fn colours() -> Vec<[f32; 3]> {
    let mut rng = Pcg32::seed_from_u64(0x5eed);
    (0..256).map(|_| [rng.next_f32(), rng.next_f32(), rng.next_f32()]).collect()
}

fn benches(c: &mut Criterion) {
    let start = Instant::now();
    let table = uplift_table();
    println!("uplift/table_decode: {:?} ({} kB)", start.elapsed(), table.size_bytes() / 1000);
    let start = Instant::now();
    black_box(UpliftTable::fit());
    println!("uplift/table_fit: {:?}", start.elapsed());
    let data = colours();
    let mut g = c.benchmark_group("uplift");
    g.bench_function("fit", |b| {
        b.iter(|| {
            for rgb in &data {
                black_box(fit_reflectance(black_box(*rgb)).ok());
            }
        })
    });
    g.bench_function("table", |b| {
        b.iter(|| {
            for rgb in &data {
                black_box(table.lookup(black_box(*rgb)));
            }
        })
    });
    g.finish();
}

criterion_group! {
    name = uplift;
    config = Criterion::default().sample_size(10).warm_up_time(Duration::from_millis(300)).measurement_time(Duration::from_secs(2));
    targets = benches
}
criterion_main!(uplift);
