//! Criterion benchmarks of BVH construction and traversal on the shared scenes.
//!
//! * `bvh_build/<builder>/<scene>`: one full build (throughput in triangles);
//! * `bvh_traverse/<builder>/<ray kind>/<scene>`: one batch of rays from
//!   [`bvh::make_ray_sets`] for a 64×64 image (throughput in rays, so criterion prints
//!   rays/s), single-threaded; `shadow` rays use `occluded`, the others `intersect`;
//!   `bvh_traverse/bvh8_packets/<ray kind>/<scene>`: the same with the renderer's 8-wide
//!   tree, its rays in packets of 16 (`intersect_packet`, `occluded_packet`).
//!
//! Builders: ours (`sweep_sah`, `binned_sah`, `midpoint`, `hybrid` with the thesis's
//! threshold of 1000 faces; leaves of at most 4 triangles chosen by the SAH), the binned and
//! sweep SAH trees collapsed to our 4-wide BVH (`bvh4_binned_sah`, `bvh4_sweep_sah`) and obvhs's
//! BVH2 and CWBVH (`obvhs_bvh2`, `obvhs_cwbvh`, medium-quality preset; only with the default
//! cargo feature `obvhs`). Scenes: the Cornell box, the Stanford bunny and Crytek Sponza from
//! `../shared/scenes`; absent ones are skipped. `BVH_BENCH_SCENES=cornell,bunny` restricts the scenes loaded, e.g.
//!
//! ```sh
//! BVH_BENCH_SCENES=cornell,bunny cargo bench -p bvh --bench bvh -- --quick bvh_traverse
//! ```

use bvh::{Accelerator, BuildConfig, Bvh, Bvh4, Bvh8, Ray, SplitMethod, TriangleTest, make_ray_sets};
#[cfg(feature = "obvhs")]
use bvh::{ObvhsBvh2, ObvhsCwBvh, ObvhsQuality};
use criterion::{BenchmarkId, Criterion, Throughput};
use glam::Vec3;
use std::hint::black_box;
use std::time::Duration;

/// Scene name and OBJ path (relative to this crate, i.e. `../shared` beside the checkout).
const SCENES: [(&str, &str); 3] = [
    ("cornell", concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/scenes/cornell-box/CornellBox-Original.obj")),
    ("bunny", concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/scenes/bunny/bunny.obj")),
    ("sponza", concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/scenes/sponza/sponza.obj")),
];

/// Primary rays per traversal batch: a 64×64 image.
const IMAGE: u32 = 64;
/// Seed of the diffuse and shadow ray sets.
const SEED: u64 = 1;

/// The builders compared.
#[derive(Clone, Copy)]
enum Builder {
    Ours(SplitMethod),
    /// Our binary tree collapsed to 4-wide nodes (watertight triangle test).
    Wide(SplitMethod),
    /// The same with the Möller–Trumbore triangle test: the price of watertightness.
    WideMollerTrumbore,
    /// Binned SAH collapsed to 8-wide nodes (AVX2 where the CPU has it).
    Wide8,
    #[cfg(feature = "obvhs")]
    ObvhsBvh2,
    #[cfg(feature = "obvhs")]
    ObvhsCwBvh,
}

impl Builder {
    fn all() -> Vec<Builder> {
        let wide = [SplitMethod::BinnedSah, SplitMethod::SweepSah].map(Builder::Wide);
        #[cfg(feature = "obvhs")]
        let obvhs = [Builder::ObvhsBvh2, Builder::ObvhsCwBvh];
        #[cfg(not(feature = "obvhs"))]
        let obvhs = [];
        SplitMethod::ALL
            .into_iter()
            .map(Builder::Ours)
            .chain(wide)
            .chain([Builder::WideMollerTrumbore, Builder::Wide8])
            .chain(obvhs)
            .collect()
    }

    fn name(&self) -> &'static str {
        match self {
            Builder::Ours(m) => m.name(),
            Builder::Wide(SplitMethod::SweepSah) => "bvh4_sweep_sah",
            Builder::Wide(_) => "bvh4_binned_sah",
            Builder::WideMollerTrumbore => "bvh4_binned_sah_mt",
            Builder::Wide8 => "bvh8_binned_sah",
            #[cfg(feature = "obvhs")]
            Builder::ObvhsBvh2 => "obvhs_bvh2",
            #[cfg(feature = "obvhs")]
            Builder::ObvhsCwBvh => "obvhs_cwbvh",
        }
    }

    fn build(&self, tris: &[[Vec3; 3]]) -> Box<dyn Accelerator> {
        match *self {
            Builder::Ours(method) => {
                let config = BuildConfig { method, max_leaf_size: 4, leaf_by_sah: true, ..Default::default() };
                Box::new(Bvh::build(tris, config).expect("finite scene"))
            }
            Builder::Wide(method) => {
                let config = BuildConfig { method, max_leaf_size: 4, leaf_by_sah: true, ..Default::default() };
                Box::new(Bvh4::build(tris, config).expect("finite scene"))
            }
            Builder::WideMollerTrumbore => {
                let config = BuildConfig { max_leaf_size: 4, leaf_by_sah: true, ..Default::default() };
                Box::new(
                    Bvh4::build(tris, config).expect("finite scene").with_triangle_test(TriangleTest::MollerTrumbore),
                )
            }
            Builder::Wide8 => {
                let config = BuildConfig { max_leaf_size: 4, leaf_by_sah: true, ..Default::default() };
                Box::new(Bvh8::build(tris, config).expect("finite scene"))
            }
            #[cfg(feature = "obvhs")]
            Builder::ObvhsBvh2 => Box::new(ObvhsBvh2::build(tris, ObvhsQuality::Medium).expect("finite scene")),
            #[cfg(feature = "obvhs")]
            Builder::ObvhsCwBvh => Box::new(ObvhsCwBvh::build(tris, ObvhsQuality::Medium).expect("finite scene")),
        }
    }
}

/// All triangles of all models of an OBJ file, or `None` (with a message) if absent.
fn load(name: &str, path: &str) -> Option<Vec<[Vec3; 3]>> {
    if let Ok(only) = std::env::var("BVH_BENCH_SCENES")
        && !only.split(',').any(|s| s.trim() == name)
    {
        return None;
    }
    let options = tobj::LoadOptions { triangulate: true, single_index: true, ..Default::default() };
    let models = match tobj::load_obj(path, &options) {
        Ok((models, _materials)) => models,
        Err(e) => {
            eprintln!("skipping scene {name}: cannot load {path}: {e}");
            return None;
        }
    };
    let mut tris = Vec::new();
    for m in &models {
        let p = &m.mesh.positions;
        let v = |i: u32| Vec3::new(p[3 * i as usize], p[3 * i as usize + 1], p[3 * i as usize + 2]);
        tris.extend(m.mesh.indices.chunks_exact(3).map(|f| [v(f[0]), v(f[1]), v(f[2])]));
    }
    eprintln!("scene {name}: {} triangles", tris.len());
    Some(tris)
}

fn scenes() -> Vec<(&'static str, Vec<[Vec3; 3]>)> {
    SCENES.iter().filter_map(|&(name, path)| Some((name, load(name, path)?))).collect()
}

/// Traces a batch of rays through an accelerator; returns a count to keep it observable.
type Trace = fn(&dyn Accelerator, &[Ray]) -> usize;

/// Closest hits for a batch; returns the number of hits.
fn closest(accel: &dyn Accelerator, rays: &[Ray]) -> usize {
    rays.iter().filter(|r| black_box(accel.intersect(r)).is_some()).count()
}

/// Occlusion for a batch; returns the number of blocked rays.
fn occluded(accel: &dyn Accelerator, rays: &[Ray]) -> usize {
    rays.iter().filter(|r| accel.occluded(r)).count()
}

/// The 8-wide tree's packet walks ([`bvh::PACKET`] consecutive rays per walk): closest hits
/// or, with `shadow`, occlusion; returns the number of hits.
fn packets(bvh: &Bvh8, shadow: bool, rays: &[Ray]) -> usize {
    let mut count = 0;
    for chunk in rays.chunks(bvh::PACKET) {
        if shadow {
            let mut blocked = [false; bvh::PACKET];
            bvh.occluded_packet(chunk, &mut blocked[..chunk.len()]);
            count += blocked.iter().filter(|&&b| b).count();
        } else {
            let mut hits = [None; bvh::PACKET];
            bvh.intersect_packet(chunk, &mut hits[..chunk.len()]);
            count += black_box(hits).iter().filter(|h| h.is_some()).count();
        }
    }
    count
}

fn bvh_build(c: &mut Criterion) {
    let mut group = c.benchmark_group("bvh_build");
    group.sample_size(10).warm_up_time(Duration::from_secs(1)).measurement_time(Duration::from_secs(3));
    for (scene, tris) in scenes() {
        group.throughput(Throughput::Elements(tris.len() as u64));
        for builder in Builder::all() {
            group.bench_function(BenchmarkId::new(builder.name(), scene), |b| {
                b.iter(|| builder.build(black_box(&tris)))
            });
        }
    }
    group.finish();
}

fn bvh_traverse(c: &mut Criterion) {
    let mut group = c.benchmark_group("bvh_traverse");
    group.sample_size(10).warm_up_time(Duration::from_secs(1)).measurement_time(Duration::from_secs(2));
    for (scene, tris) in scenes() {
        let finder = Bvh::build(&tris, BuildConfig::default()).expect("finite scene");
        let sets = make_ray_sets(&tris, &finder, IMAGE, IMAGE, SEED);
        let kinds: [(&str, &[Ray], Trace); 3] = [
            ("primary", &sets.primary, closest),
            ("diffuse", &sets.diffuse, closest),
            ("shadow", &sets.shadow, occluded),
        ];
        for builder in Builder::all() {
            let accel = builder.build(&tris);
            for (kind, rays, trace) in kinds {
                if rays.is_empty() {
                    continue;
                }
                group.throughput(Throughput::Elements(rays.len() as u64));
                group.bench_function(BenchmarkId::new(format!("{}/{kind}", builder.name()), scene), |b| {
                    b.iter(|| trace(accel.as_ref(), black_box(rays)))
                });
            }
        }
        // The renderer's 8-wide tree, its rays in packets (docs/figures.md: faster on the
        // Cornell box's camera and shadow rays, slower elsewhere).
        let bvh8 = Bvh8::build(&tris, BuildConfig::default()).expect("finite scene");
        for (kind, rays) in [("primary", &sets.primary), ("diffuse", &sets.diffuse), ("shadow", &sets.shadow)] {
            if rays.is_empty() {
                continue;
            }
            group.throughput(Throughput::Elements(rays.len() as u64));
            group.bench_function(BenchmarkId::new(format!("bvh8_packets/{kind}"), scene), |b| {
                b.iter(|| packets(&bvh8, kind == "shadow", black_box(rays)))
            });
        }
    }
    group.finish();
}

/// What `criterion_group!`/`criterion_main!` would generate, minus an undocumented `pub fn`.
fn main() {
    let mut c = Criterion::default().configure_from_args();
    bvh_build(&mut c);
    bvh_traverse(&mut c);
    c.final_summary();
}
