//! `spt rays`: ray sets on disk, so that our traversal can be compared ray for ray with
//! another ray tracer (Embree: `bench/embree_rays.py`).
//!
//! `spt rays export SCENE --out DIR` writes a scene's triangles and its three benchmark
//! ray sets ([`bvh::RaySets`]: coherent primary rays, incoherent diffuse bounces, shadow
//! segments); `spt rays trace DIR` builds our accelerator over the triangles, traces
//! every set (closest hit for primary and diffuse, occlusion for shadow), prints one JSON
//! line of build time and rays per second, and writes the hits. The format, little
//! endian, no headers:
//!
//! * `triangles.f32` — 9 × f32 per triangle: v0.xyz, v1.xyz, v2.xyz.
//! * `primary.rays`, `diffuse.rays`, `shadow.rays` — 8 × f32 per ray: origin.xyz,
//!   direction.xyz (shadow directions span the segment, not normalised), t_min, t_max.
//! * `<set>.<tracer>.hits` — 16 bytes per ray: u32 triangle (`u32::MAX` = miss), f32 t,
//!   u, v (the barycentric weights of vertices 1 and 2). For the shadow set the triangle
//!   is 0 if the segment is blocked, else `u32::MAX`; t, u and v are NaN.

use anyhow::{Context, Result, bail, ensure};
use bvh::{Accelerator, BuildConfig, Bvh4, BvhWidth, Hit, Ray, TriangleTest, WideBvh, make_ray_sets_from};
use clap::{Args, Subcommand};
use glam::Vec3;
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// `spt rays` subcommands.
#[derive(Subcommand)]
pub enum RaysCommand {
    /// Write a scene's triangles and its primary, diffuse and shadow ray sets to a folder.
    Export(ExportArgs),
    /// Build our BVH over a folder's triangles, trace its ray sets, print one JSON line
    /// (build ms, Mrays/s per set) and write the hits.
    Trace(TraceArgs),
}

/// Options of `spt rays export`.
#[derive(Args)]
pub struct ExportArgs {
    /// The scene file (.obj with its .mtl, or builtin:NAME).
    pub scene: PathBuf,
    /// The folder to write (created if missing).
    #[arg(long)]
    pub out: PathBuf,
    /// Image width of the primary rays (one ray per pixel).
    #[arg(long, default_value_t = 1024)]
    pub width: u32,
    /// Image height of the primary rays.
    #[arg(long, default_value_t = 1024)]
    pub height: u32,
    /// Camera position x,y,z for the primary rays (default: frame the bounding box from +z).
    #[arg(long, value_parser = crate::parse_vec3, allow_hyphen_values = true, requires = "center")]
    pub eye: Option<Vec3>,
    /// Point the camera looks at, x,y,z.
    #[arg(long, value_parser = crate::parse_vec3, allow_hyphen_values = true, requires = "eye")]
    pub center: Option<Vec3>,
    /// Split every triangle into four (at its edge midpoints) this many times: a large
    /// mesh from a small one (the bunny twice: 1.1 M triangles).
    #[arg(long, default_value_t = 0, value_parser = clap::value_parser!(u32).range(0..=5))]
    pub subdivide: u32,
    /// Seed of the diffuse and shadow rays.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

/// Options of `spt rays trace`.
#[derive(Args)]
pub struct TraceArgs {
    /// A folder written by `spt rays export`.
    pub dir: PathBuf,
    /// Threads (rayon; rays are handed out in chunks of 1024).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub threads: u32,
    /// Timed passes over each set; the fastest counts.
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub passes: u32,
    /// Children per node of our BVH, as `spt render --bvh-width`: auto (what the renderer
    /// uses on this CPU), 4 or 8.
    #[arg(long, default_value = "auto", value_parser = crate::parse_bvh_width)]
    pub bvh_width: BvhWidth,
    /// Ray–triangle test: watertight or moller-trumbore.
    #[arg(long, default_value = "watertight", value_parser = crate::parse_triangle_test)]
    pub triangle_test: TriangleTest,
    /// Largest leaf of the binary tree before the collapse (default: the renderer's).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=64))]
    pub max_leaf: Option<u32>,
    /// Triangles the binned SAH counts as one block (`BuildConfig::sah_block`; default:
    /// the renderer's 4, the leaf test's width; 1: the plain SAH).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=64))]
    pub sah_block: Option<u32>,
    /// Extra references triangle pre-splitting may add, as a fraction of the triangles
    /// (`BuildConfig::presplit`; default: the renderer's).
    #[arg(long, value_parser = crate::parse_fraction)]
    pub presplit: Option<f32>,
    /// Keep the f32 triangle test's own t instead of recomputing every closest hit's t in
    /// f64 from its triangle's plane (`BuildConfig::exact_t`): a little faster to build and
    /// to trace, and off by more than 10⁻⁶ relative on about one hit in 10⁴–10⁵ (grazing
    /// hits, hits near the origin beside large triangles, slivers).
    #[arg(long)]
    pub raw_t: bool,
    /// Rays in packets of 16 consecutive rays (one walk down the tree per packet,
    /// `WideBvh::occluded_packet` and `WideBvh::intersect_packet`; the same answers), as
    /// Embree's `rtcOccluded16`/`rtcIntersect16` (`embree_trace --packet 16`).
    #[arg(long)]
    pub packet: bool,
    /// Do not write the hits files.
    #[arg(long)]
    pub no_write: bool,
    /// After the timed passes, one more that counts per ray the wide nodes whose children
    /// are box-tested and the triangles tested (for the shadow set, by the shadow rays'
    /// own walk, which stops at the first hit), added to each set's JSON.
    #[arg(long)]
    pub count: bool,
}

/// The three sets, in the order they are written and traced, with their query.
const SETS: [(&str, Query); 3] =
    [("primary", Query::Closest), ("diffuse", Query::Closest), ("shadow", Query::Occluded)];

#[derive(Clone, Copy, PartialEq, Eq)]
enum Query {
    Closest,
    Occluded,
}

/// Rays a thread takes at a time.
const CHUNK: usize = 1024;

/// Runs `spt rays`.
pub fn run(command: RaysCommand) -> Result<()> {
    match command {
        RaysCommand::Export(a) => export(a),
        RaysCommand::Trace(a) => trace(a),
    }
}

fn export(args: ExportArgs) -> Result<()> {
    let mut scene = crate::load_scene(&args.scene)?;
    // Exported as one triangle soup: instances are copied into it.
    scene.flatten_instances();
    let mut triangles = scene.triangle_soup();
    if triangles.is_empty() {
        bail!("{}: the scene has no triangles", args.scene.display());
    }
    for _ in 0..args.subdivide {
        triangles = subdivide(&triangles);
    }
    let bvh = Bvh4::build(&triangles, BuildConfig::default())?;
    let sets = make_ray_sets_from(&triangles, &bvh, args.eye.zip(args.center), args.width, args.height, args.seed);
    std::fs::create_dir_all(&args.out).with_context(|| format!("creating {}", args.out.display()))?;
    write_f32(&args.out.join("triangles.f32"), triangles.iter().flat_map(|t| t.iter().flat_map(|v| v.to_array())))?;
    for ((name, _), rays) in SETS.iter().zip([&sets.primary, &sets.diffuse, &sets.shadow]) {
        let values = rays.iter().flat_map(|r| {
            let [ox, oy, oz] = r.origin.to_array();
            let [dx, dy, dz] = r.dir.to_array();
            [ox, oy, oz, dx, dy, dz, r.t_min, r.t_max]
        });
        write_f32(&args.out.join(format!("{name}.rays")), values)?;
    }
    eprintln!(
        "wrote {}: {} triangles, {} primary, {} diffuse, {} shadow rays",
        args.out.display(),
        triangles.len(),
        sets.primary.len(),
        sets.diffuse.len(),
        sets.shadow.len()
    );
    Ok(())
}

/// Every triangle split into four at its edge midpoints (same winding).
fn subdivide(triangles: &[[Vec3; 3]]) -> Vec<[Vec3; 3]> {
    let mut out = Vec::with_capacity(4 * triangles.len());
    for &[a, b, c] in triangles {
        let (ab, bc, ca) = ((a + b) * 0.5, (b + c) * 0.5, (c + a) * 0.5);
        out.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
    }
    out
}

fn write_f32(path: &Path, values: impl Iterator<Item = f32>) -> Result<()> {
    let bytes: Vec<u8> = values.flat_map(f32::to_le_bytes).collect();
    std::fs::write(path, bytes).with_context(|| format!("writing {}", path.display()))
}

/// Reads a file of little-endian f32 records of `width` values each.
fn read_records(path: &Path, width: usize) -> Result<Vec<f32>> {
    let bytes = std::fs::read(path).with_context(|| format!("reading {}", path.display()))?;
    ensure!(
        bytes.len() % (4 * width) == 0,
        "{}: {} bytes is not a whole number of {}-byte records",
        path.display(),
        bytes.len(),
        4 * width
    );
    Ok(bytes.chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect())
}

fn trace(args: TraceArgs) -> Result<()> {
    let soup = read_records(&args.dir.join("triangles.f32"), 9)?;
    let triangles: Vec<[Vec3; 3]> = soup
        .chunks_exact(9)
        .map(|t| [Vec3::new(t[0], t[1], t[2]), Vec3::new(t[3], t[4], t[5]), Vec3::new(t[6], t[7], t[8])])
        .collect();
    ensure!(!triangles.is_empty(), "{}: no triangles", args.dir.join("triangles.f32").display());
    ensure!(
        BvhWidth::CPU.contains(&args.bvh_width),
        "--bvh-width {}: the CPU traces 4- or 8-wide trees (auto, 4 or 8)",
        args.bvh_width.name()
    );
    let pool = rayon::ThreadPoolBuilder::new().num_threads(args.threads as usize).build()?;
    let start = Instant::now();
    let mut config = tracer::geometry::Geometry::triangle_build_config();
    if let Some(n) = args.max_leaf {
        config.max_leaf_size = n as usize;
    }
    if let Some(n) = args.sah_block {
        config.sah_block = n as usize;
    }
    if let Some(f) = args.presplit {
        config.presplit = f;
    }
    config.exact_t = !args.raw_t;
    let bvh = pool.install(|| WideBvh::build(&triangles, config, args.bvh_width))?;
    let build = start.elapsed();
    let tracer = format!("bvh{}", bvh.width());
    let bvh = bvh.with_triangle_test(args.triangle_test);
    let sets = trace_sets(&bvh, args.packet.then_some(&bvh), &pool, &args, &tracer)?;
    println!(
        r#"{{"tracer": "{tracer}", "threads": {}, "triangles": {}, "references": {}, "nodes": {}, "build_ms": {:.3}, "sets": {{{}}}}}"#,
        args.threads,
        triangles.len(),
        bvh.references(),
        bvh.stats().nodes,
        build.as_secs_f64() * 1e3,
        sets.join(", ")
    );
    Ok(())
}

/// The tree whose packet walks answer (see `--packet`).
type PacketQuery<'a> = &'a WideBvh;

/// Traces every set of `args.dir` with `accel` (in packets by `packets` where given): a
/// JSON member per set.
fn trace_sets<A: Accelerator + Sync>(
    accel: &A,
    packets: Option<PacketQuery>,
    pool: &rayon::ThreadPool,
    args: &TraceArgs,
    tracer: &str,
) -> Result<Vec<String>> {
    let mut sets = Vec::new();
    for (name, query) in SETS {
        let path = args.dir.join(format!("{name}.rays"));
        let rays: Vec<Ray> = read_records(&path, 8)?
            .chunks_exact(8)
            .map(|r| Ray::segment(Vec3::new(r[0], r[1], r[2]), Vec3::new(r[3], r[4], r[5]), r[6], r[7]))
            .collect();
        let mut hits = vec![None; rays.len()];
        let mut best = Duration::MAX;
        for _ in 0..args.passes {
            let start = Instant::now();
            pool.install(|| trace_set(accel, packets, query, &rays, &mut hits));
            best = best.min(start.elapsed());
        }
        let count = hits.iter().filter(|h| h.is_some()).count();
        if !args.no_write {
            write_hits(&args.dir.join(format!("{name}.{tracer}.hits")), &hits)?;
        }
        let mrays = rays.len() as f64 / best.as_secs_f64().max(1e-9) / 1e6;
        let counted = if args.count {
            let mut stats = bvh::RayStats::default();
            for r in &rays {
                match query {
                    Query::Closest => _ = accel.intersect_counted(r, &mut stats),
                    Query::Occluded => _ = accel.occluded_counted(r, &mut stats),
                }
            }
            let per_ray = |x: u64| x as f64 / rays.len().max(1) as f64;
            format!(
                r#", "nodes_per_ray": {:.3}, "triangles_per_ray": {:.3}"#,
                per_ray(stats.nodes_visited),
                per_ray(stats.triangles_tested)
            )
        } else {
            String::new()
        };
        sets.push(format!(
            r#""{name}": {{"rays": {}, "mrays_per_s": {mrays:.4}, "hits": {count}{counted}}}"#,
            rays.len()
        ));
    }
    Ok(sets)
}

/// Traces `rays` into `hits` (for occlusion queries, a hit with NaN t, u, v when blocked;
/// by `packets` of [`bvh::PACKET`] rays where given).
fn trace_set<A: Accelerator + Sync>(
    accel: &A,
    packets: Option<PacketQuery>,
    query: Query,
    rays: &[Ray],
    hits: &mut [Option<Hit>],
) {
    let blocked = Hit { prim: 0, t: f32::NAN, u: f32::NAN, v: f32::NAN };
    hits.par_chunks_mut(CHUNK).zip(rays.par_chunks(CHUNK)).for_each(|(out, rays)| match (query, packets) {
        (Query::Closest, Some(packets)) => {
            for (out, rays) in out.chunks_mut(bvh::PACKET).zip(rays.chunks(bvh::PACKET)) {
                packets.intersect_packet(rays, out);
            }
        }
        (Query::Occluded, Some(packets)) => {
            let mut answers = [false; bvh::PACKET];
            for (out, rays) in out.chunks_mut(bvh::PACKET).zip(rays.chunks(bvh::PACKET)) {
                packets.occluded_packet(rays, &mut answers[..rays.len()]);
                for (h, &b) in out.iter_mut().zip(&answers) {
                    *h = b.then_some(blocked);
                }
            }
        }
        _ => {
            for (h, r) in out.iter_mut().zip(rays) {
                *h = match query {
                    Query::Closest => accel.intersect(r),
                    Query::Occluded => accel.occluded(r).then_some(blocked),
                };
            }
        }
    });
}

fn write_hits(path: &Path, hits: &[Option<Hit>]) -> Result<()> {
    let mut bytes = Vec::with_capacity(16 * hits.len());
    for h in hits {
        let h = h.unwrap_or(Hit { prim: u32::MAX, t: f32::NAN, u: f32::NAN, v: f32::NAN });
        bytes.extend(h.prim.to_le_bytes());
        for x in [h.t, h.u, h.v] {
            bytes.extend(x.to_le_bytes());
        }
    }
    std::fs::write(path, bytes).with_context(|| format!("writing {}", path.display()))
}
