//! The library end to end on a small scene: shards, time budgets, checkpoints and
//! resumption give the film of one uninterrupted render, bit for bit; merges check
//! coverage.

use glam::Vec3;
use shard::{Budget, Job, Manifest, Partial, ShardSpec, Split, Work};
use spectral::spectrum::Colour;
use std::path::PathBuf;
use std::time::Duration;
use tracer::material::Material;
use tracer::mesh::quad;
use tracer::render::{PreparedScene, RenderSettings, SceneOptions};
use tracer::{CpuBackend, Scene};

/// A floor under a small lamp, viewed by the default framing.
fn prepared() -> Box<dyn PreparedScene> {
    prepared_on(&CpuBackend::new(2).unwrap())
}

/// [`prepared`] on `backend`.
fn prepared_on(backend: &dyn tracer::Backend) -> Box<dyn PreparedScene> {
    let mut scene = Scene::default();
    let floor = Material::diffuse("floor", Colour::reflectance_rgb([0.7, 0.5, 0.3]).unwrap()).unwrap();
    scene.add(&quad(Vec3::ZERO, Vec3::Y, 1.0), floor);
    let lamp = Material::diffuse("lamp", Colour::constant(0.0)).unwrap().with_emission(Colour::constant(4.0));
    scene.add(&quad(Vec3::new(0.0, 1.0, 0.0), -Vec3::Y, 0.3), lamp);
    backend.prepare(scene, &SceneOptions::default()).unwrap()
}

fn settings() -> RenderSettings {
    RenderSettings { width: 20, height: 14, spp: 24, seed: 3, ..RenderSettings::default() }
}

fn piece(prepared: &dyn PreparedScene, s: &RenderSettings, shard: Option<ShardSpec>) -> Partial {
    let caps = prepared.capabilities();
    let work = Work::plan(shard, s.width, s.height, s.spp, caps.sample_block).unwrap();
    let job = Job::new("test", prepared.scene(), s, &SceneOptions::default(), &caps, prepared.camera(s));
    Partial::fresh("floor", job, shard, work, caps.sample_block)
}

fn run(prepared: &dyn PreparedScene, s: &RenderSettings, p: &mut Partial, budget: Budget) -> shard::WorkStats {
    shard::run_work(prepared, s, p, &budget, &mut |_| Ok(()), &|_| {}).unwrap()
}

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("spt-shard-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

#[test]
fn shards_merge_to_the_film_of_one_render() {
    let prepared = prepared();
    let s = settings();
    let (whole, _) = tracer::render(prepared.as_ref(), &s, &|_| {}).unwrap();
    for split in Split::ALL {
        for n in [1, 3, 7] {
            let paths: Vec<PathBuf> = (1..=n)
                .map(|k| {
                    let mut p = piece(prepared.as_ref(), &s, Some(ShardSpec { index: k, count: n, split }));
                    run(prepared.as_ref(), &s, &mut p, Budget::default());
                    assert!(p.manifest.complete());
                    // Dropped samples travel with the sums (none occur here: pretend).
                    p.film.non_finite = k as u64;
                    let path = temp(&format!("{}-{k}-{n}.partial", split.name()));
                    p.write(&path).unwrap();
                    let back = Partial::read(&path).unwrap();
                    assert_eq!(back.film, p.film, "a partial reads back as written");
                    assert_eq!(back.manifest.non_finite, k as u64, "the manifest counts the film's drops");
                    assert_eq!(Manifest { non_finite: 0, ..back.manifest }, p.manifest);
                    path
                })
                .collect();
            let merged = shard::merge(&paths).unwrap();
            assert!(merged.film.pixels() == whole.pixels(), "{n} shards by {}", split.name());
            assert_eq!(merged.film.non_finite, (n * (n + 1) / 2) as u64);
        }
    }
}

#[test]
fn passes_checkpoints_and_resumption_do_not_change_a_bit() {
    let prepared = prepared();
    let s = settings();
    let (whole, _) = tracer::render(prepared.as_ref(), &s, &|_| {}).unwrap();
    // Checkpoints every instant: one pass per sample after the first.
    let mut p = piece(prepared.as_ref(), &s, None);
    let mut written = 0;
    let budget = Budget { time: None, checkpoint_every: Some(Duration::from_nanos(1)) };
    let stats = shard::run_work(
        prepared.as_ref(),
        &s,
        &mut p,
        &budget,
        &mut |_| {
            written += 1;
            Ok(())
        },
        &|_| {},
    )
    .unwrap();
    assert!(stats.passes > 2 && written == stats.checkpoints && written + 1 >= stats.passes, "{stats:?}");
    assert_eq!(p.film, whole);
    // Stopped after its first pass by a budget already spent, then resumed from disk.
    let mut p = piece(prepared.as_ref(), &s, None);
    run(prepared.as_ref(), &s, &mut p, Budget { time: Some(Duration::from_nanos(1)), checkpoint_every: None });
    assert_eq!(p.manifest.done, 1, "the first pass is one sample; the budget ends the render after it");
    let path = temp("stopped.partial");
    p.write(&path).unwrap();
    let mut resumed = Partial::read(&path).unwrap();
    run(prepared.as_ref(), &s, &mut resumed, Budget::default());
    assert_eq!(resumed.film, whole);
    assert_eq!(resumed.manifest.done, s.spp);
}

#[test]
fn coverage_names_what_is_missing_duplicated_or_foreign() {
    let prepared = prepared();
    let s = settings();
    let spec = |k| Some(ShardSpec { index: k, count: 3, split: Split::Samples });
    let parts: Vec<(PathBuf, Manifest)> = (1..=3)
        .map(|k| {
            let mut p = piece(prepared.as_ref(), &s, spec(k)).manifest;
            p.done = p.work.samples.end;
            (PathBuf::from(format!("p{k}.partial")), p)
        })
        .collect();
    shard::plan_coverage(&parts).unwrap();
    let err = |parts: &[(PathBuf, Manifest)]| shard::plan_coverage(parts).unwrap_err().to_string();
    let msg = err(&[parts[0].clone(), parts[2].clone()]);
    assert!(msg.contains("samples 8..16") && msg.contains("missing shard 2/3"), "{msg}");
    let msg = err(&[parts[0].clone(), parts[1].clone(), parts[1].clone(), parts[2].clone()]);
    assert!(msg.contains("duplicate"), "{msg}");
    let mut stopped = parts[1].clone();
    stopped.1.done = 12;
    let msg = err(&[parts[0].clone(), stopped, parts[2].clone()]);
    assert!(msg.contains("samples 12..16") && msg.contains("p2.partial") && msg.contains("rerun"), "{msg}");
    let mut foreign = parts[2].clone();
    foreign.1.job.spectral = "rgb".into();
    let msg = err(&[parts[0].clone(), parts[1].clone(), foreign]);
    assert!(msg.contains("different renders") && msg.contains("spectral"), "{msg}");
    let mut overlapping = parts[1].clone();
    overlapping.1.work.samples = 6..16;
    overlapping.1.done = 16;
    let msg = err(&[parts[0].clone(), overlapping, parts[2].clone()]);
    assert!(msg.contains("overlap"), "{msg}");
    assert!(err(&[]).contains("no partials"));
}

/// An integrator whose light paths splat anywhere on the image renders pieces split by
/// samples, and refuses a band of rows (its splats would leave the band).
#[test]
fn a_splatting_integrator_takes_samples_not_bands_of_rows() {
    let prepared = prepared_on(&CpuBackend::with_integrator(2, tracer::Bdpt).unwrap());
    let s = RenderSettings { spp: 2, ..settings() };
    let mut by_samples = piece(prepared.as_ref(), &s, Some(ShardSpec { index: 1, count: 2, split: Split::Samples }));
    run(prepared.as_ref(), &s, &mut by_samples, Budget::default());
    assert!(by_samples.manifest.complete());
    let mut band = piece(prepared.as_ref(), &s, Some(ShardSpec { index: 1, count: 2, split: Split::Tiles }));
    let err = shard::run_work(prepared.as_ref(), &s, &mut band, &Budget::default(), &mut |_| Ok(()), &|_| {})
        .unwrap_err()
        .to_string();
    assert!(err.contains("--integrator bdpt splats") && err.contains("shard it by samples"), "{err}");
    assert_eq!(band.manifest.done, band.manifest.work.samples.start, "nothing rendered");
}
