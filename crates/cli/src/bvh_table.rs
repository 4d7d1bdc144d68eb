//! `spt bvh SCENE`: the thesis's table 9.6 — BVH builders against the maximum number of
//! faces per leaf — extended with tree statistics, traversal work per ray, throughput for
//! primary, diffuse and shadow rays, each tree also collapsed to our 4-wide [`Bvh4`]
//! (`<builder>+bvh4` rows), and obvhs's BVH2 and CWBVH as a yardstick.

use anyhow::{Result, bail, ensure};
use bvh::{
    Accelerator, BuildConfig, Bvh, Bvh4, BvhStats, ObvhsBvh2, ObvhsCwBvh, ObvhsQuality, Ray, RaySets, RayStats,
    SplitMethod, make_ray_sets_from,
};
use glam::Vec3;
use std::io::Write;
use std::time::{Duration, Instant};

/// Builder names [`run`] accepts (our [`SplitMethod`]s; `hybrid` uses the thesis's
/// threshold of 1000 faces).
pub const BUILDERS: [&str; 4] = ["sweep_sah", "binned_sah", "midpoint", "hybrid"];

/// The thesis's maximum leaf sizes.
pub const LEAF_SIZES: [usize; 5] = [1, 2, 3, 4, 8];

/// Seed of the diffuse and shadow ray sets.
const SEED: u64 = 1;

/// Each ray set is timed in this many passes; the fastest counts.
const PASSES: usize = 3;

/// A pass traces its ray set as many times as it takes to last at least this long.
const MIN_PASS: Duration = Duration::from_millis(30);

/// One line of the table.
struct Row {
    builder: String,
    leaf: String,
    build: Duration,
    stats: BvhStats,
    /// Work per primary ray (nodes visited, triangles tested).
    work: (f64, f64),
    /// Mrays/s for primary, diffuse and shadow rays.
    mrays: [f64; 3],
}

/// Traces each set single-threaded, best of [`PASSES`] passes of at least [`MIN_PASS`],
/// and counts the primary rays' work.
impl Row {
    /// A row for `accel`, timing its traversal of `sets`.
    fn measured(
        builder: String,
        leaf: String,
        build: Duration,
        stats: BvhStats,
        accel: &dyn Accelerator,
        sets: &RaySets,
        min_pass: Duration,
    ) -> Self {
        let (work, mrays) = measure(accel, sets, min_pass);
        Self { builder, leaf, build, stats, work, mrays }
    }
}

fn measure(accel: &dyn Accelerator, sets: &RaySets, min_pass: Duration) -> ((f64, f64), [f64; 3]) {
    let mut stats = RayStats::default();
    for r in &sets.primary {
        accel.intersect_counted(r, &mut stats);
    }
    let per_ray = |x: u64| x as f64 / stats.rays.max(1) as f64;
    let work = (per_ray(stats.nodes_visited), per_ray(stats.triangles_tested));
    let closest = |rays: &[Ray]| rays.iter().filter(|r| std::hint::black_box(accel.intersect(r)).is_some()).count();
    let blocked = |rays: &[Ray]| rays.iter().filter(|r| accel.occluded(r)).count();
    let mrays = |rays: &[Ray], trace: &dyn Fn(&[Ray]) -> usize| {
        if rays.is_empty() {
            return f64::NAN;
        }
        // Warm up, then repeat the set within a pass until the pass lasts `min_pass`, so
        // that small sets are not timed at the scheduler's granularity.
        let start = Instant::now();
        std::hint::black_box(trace(rays));
        let once = start.elapsed().max(Duration::from_nanos(1));
        let repeats = (min_pass.as_secs_f64() / once.as_secs_f64()).ceil().clamp(1.0, 1e6) as usize;
        let best = (0..PASSES)
            .map(|_| {
                let start = Instant::now();
                for _ in 0..repeats {
                    std::hint::black_box(trace(rays));
                }
                start.elapsed()
            })
            .min()
            .unwrap_or_default();
        (rays.len() * repeats) as f64 / best.as_secs_f64().max(1e-9) / 1e6
    };
    (work, [mrays(&sets.primary, &closest), mrays(&sets.diffuse, &closest), mrays(&sets.shadow, &blocked)])
}

fn method(name: &str) -> Result<SplitMethod> {
    match SplitMethod::ALL.into_iter().find(|m| m.name() == name) {
        Some(m) => Ok(m),
        None => bail!("unknown BVH builder {name:?}; expected one of {}", BUILDERS.join(", ")),
    }
}

const HEADER: [&str; 13] = [
    "builder",
    "leaf ≤",
    "build ms",
    "depth",
    "nodes",
    "leaves",
    "SAH cost",
    "nodes/ray",
    "tris/ray",
    "primary Mrays/s",
    "diffuse Mrays/s",
    "shadow Mrays/s",
    "vs obvhs",
];

fn print_row(out: &mut impl Write, cells: &[String]) -> std::io::Result<()> {
    let width = |i: usize| if i == 0 { 20 } else { HEADER[i].chars().count().max(9) };
    let padded: Vec<String> = cells
        .iter()
        .enumerate()
        .map(|(i, c)| if i == 0 { format!("{c:<w$}", w = width(i)) } else { format!("{c:>w$}", w = width(i)) })
        .collect();
    writeln!(out, "| {} |", padded.join(" | "))
}

fn row_cells(row: &Row, cw_diffuse: f64) -> Vec<String> {
    let s = &row.stats;
    vec![
        row.builder.clone(),
        row.leaf.clone(),
        match row.build.as_secs_f64() * 1e3 {
            ms if ms < 10.0 => format!("{ms:.3}"),
            ms => format!("{ms:.1}"),
        },
        s.depth.to_string(),
        s.nodes.to_string(),
        s.leaves.to_string(),
        format!("{:.2}", s.sah_cost),
        format!("{:.1}", row.work.0),
        format!("{:.1}", row.work.1),
        format!("{:.2}", row.mrays[0]),
        format!("{:.2}", row.mrays[1]),
        format!("{:.2}", row.mrays[2]),
        format!("{:.2}", row.mrays[1] / cw_diffuse),
    ]
}

/// Prints, for the scene's triangles, two rows per builder × maximum leaf size (the binary
/// tree, then the same tree collapsed to a [`Bvh4`]: `<builder>+bvh4`, whose build time
/// includes the binary build, nodes count 4-wide nodes and depth the leaf level, as for
/// obvhs's CWBVH) and two rows for obvhs (BVH2 and CWBVH, medium-quality preset): build
/// time, depth, nodes, leaves, SAH cost, mean nodes visited and triangles tested per
/// primary ray, and single-threaded throughput (best of 3) for the primary, diffuse and
/// shadow rays of [`bvh::make_ray_sets`] at `width` × `height`; "vs obvhs" is a row's
/// diffuse throughput over obvhs's CWBVH's.
///
/// Our trees split down to `leaf_sizes` faces regardless of the SAH (the thesis's "max
/// faces per leaf", `leaf_by_sah: false`). `builders` are names from [`BUILDERS`]; an
/// empty `builders` means all of them, an empty `leaf_sizes` the thesis's [`LEAF_SIZES`].
pub fn run(
    tris: &[[Vec3; 3]],
    scene_name: &str,
    width: u32,
    height: u32,
    builders: &[&str],
    leaf_sizes: &[usize],
    camera: Option<(Vec3, Vec3)>,
) -> Result<()> {
    let stdout = std::io::stdout();
    write_table(&mut stdout.lock(), tris, scene_name, width, height, builders, leaf_sizes, camera, MIN_PASS)
}

/// [`run`] into `out`, with passes of at least `min_pass` (tests use zero).
#[allow(clippy::too_many_arguments)] // run's arguments, the output and the pass length
fn write_table(
    out: &mut impl Write,
    tris: &[[Vec3; 3]],
    scene_name: &str,
    width: u32,
    height: u32,
    builders: &[&str],
    leaf_sizes: &[usize],
    camera: Option<(Vec3, Vec3)>,
    min_pass: Duration,
) -> Result<()> {
    ensure!(!tris.is_empty(), "{scene_name} has no triangles");
    ensure!(width > 0 && height > 0, "the image must have at least one pixel");
    let builders = if builders.is_empty() { &BUILDERS[..] } else { builders };
    let leaf_sizes = if leaf_sizes.is_empty() { &LEAF_SIZES[..] } else { leaf_sizes };
    let methods = builders.iter().map(|b| method(b)).collect::<Result<Vec<_>>>()?;
    if let Some(bad) = leaf_sizes.iter().find(|&&n| !(1..=255).contains(&n)) {
        bail!("maximum leaf size {bad} is outside 1..=255");
    }

    let finder = Bvh::build(tris, BuildConfig::default())?;
    let sets = make_ray_sets_from(tris, &finder, camera, width, height, SEED);
    drop(finder);
    let costs = BuildConfig::default();
    writeln!(
        out,
        "{scene_name}: {} triangles; {}×{}: {} primary, {} diffuse, {} shadow rays",
        tris.len(),
        width,
        height,
        sets.primary.len(),
        sets.diffuse.len(),
        sets.shadow.len()
    )?;
    writeln!(
        out,
        "SAH cost = Σ_interior C_t·A/A_root + Σ_leaves C_i·n·A/A_root with C_t = {}, C_i = {}; build: wall \
         clock (binned SAH builds subtrees in parallel, obvhs single-threaded); nodes/tris per primary ray \
         (+bvh4: 4-wide nodes; obvhs CWBVH: 8-wide nodes); Mrays/s: one thread, best of {PASSES} passes of ≥ {} \
         ms; vs obvhs: diffuse Mrays/s ÷ obvhs CWBVH's",
        costs.traversal_cost,
        costs.intersection_cost,
        min_pass.as_millis()
    )?;
    writeln!(out)?;

    // obvhs first: every row is compared with its CWBVH.
    let quality = ObvhsQuality::Medium;
    let params = quality.params();
    let bvh2 = ObvhsBvh2::build(tris, quality)?;
    let bvh2_row = Row::measured(
        format!("obvhs_bvh2 ({})", quality.name()),
        params.max_prims_per_leaf.clamp(1, 255).to_string(),
        bvh2.build_time(),
        bvh2.stats_with_costs(costs.traversal_cost, costs.intersection_cost),
        &bvh2,
        &sets,
        min_pass,
    );
    drop(bvh2);
    let cw = ObvhsCwBvh::build(tris, quality)?;
    let cw_row = Row::measured(
        format!("obvhs_cwbvh ({})", quality.name()),
        params.max_prims_per_leaf.clamp(1, 3).to_string(),
        cw.build_time(),
        cw.stats_with_costs(costs.traversal_cost, costs.intersection_cost),
        &cw,
        &sets,
        min_pass,
    );
    drop(cw);
    let cw_diffuse = cw_row.mrays[1];

    print_row(out, &HEADER.map(String::from))?;
    print_row(out, &HEADER.map(|_| "---:".to_string()))?;
    for (name, method) in builders.iter().zip(methods) {
        for &leaf in leaf_sizes {
            let config = BuildConfig { method, max_leaf_size: leaf, leaf_by_sah: false, ..costs };
            let start = Instant::now();
            let bvh = Bvh::build(tris, config)?;
            let build = start.elapsed();
            let row = Row::measured(name.to_string(), leaf.to_string(), build, bvh.stats(), &bvh, &sets, min_pass);
            print_row(out, &row_cells(&row, cw_diffuse))?;
            // The same tree collapsed to 4-wide nodes; its build time includes the binary build.
            let start = Instant::now();
            let wide = Bvh4::from_bvh(&bvh);
            let build = build + start.elapsed();
            drop(bvh);
            let s = wide.stats();
            let stats = BvhStats { nodes: s.nodes, leaves: s.leaves, depth: s.depth, sah_cost: s.sah_cost };
            let row = Row::measured(format!("{name}+bvh4"), leaf.to_string(), build, stats, &wide, &sets, min_pass);
            print_row(out, &row_cells(&row, cw_diffuse))?;
            out.flush()?;
        }
    }
    for row in [&bvh2_row, &cw_row] {
        print_row(out, &row_cells(row, cw_diffuse))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A closed box of 12 triangles around a grid of small floating quads.
    fn scene() -> Vec<[Vec3; 3]> {
        let quad = |a: Vec3, b: Vec3, c: Vec3, d: Vec3| [[a, b, c], [a, c, d]];
        let v = Vec3::new;
        let mut t = Vec::new();
        t.extend(quad(v(-1., 0., -1.), v(1., 0., -1.), v(1., 0., 1.), v(-1., 0., 1.)));
        t.extend(quad(v(-1., 2., -1.), v(-1., 2., 1.), v(1., 2., 1.), v(1., 2., -1.)));
        t.extend(quad(v(-1., 0., -1.), v(-1., 2., -1.), v(1., 2., -1.), v(1., 0., -1.)));
        for i in 0..10 {
            for j in 0..10 {
                let c = v(-0.9 + 0.18 * i as f32, 0.1 + 0.18 * j as f32, -0.5 + 0.05 * ((i + j) % 3) as f32);
                t.extend(quad(c, c + v(0.1, 0., 0.), c + v(0.1, 0.1, 0.), c + v(0., 0.1, 0.)));
            }
        }
        t
    }

    #[test]
    fn prints_two_rows_per_builder_and_leaf_size_plus_obvhs() {
        let mut out = Vec::new();
        write_table(&mut out, &scene(), "test", 24, 16, &["sweep_sah", "hybrid"], &[1, 4], None, Duration::ZERO)
            .unwrap();
        let text = String::from_utf8(out).unwrap();
        let rows: Vec<&str> = text.lines().filter(|l| l.starts_with('|')).collect();
        assert_eq!(rows.len(), 2 + 2 * 2 * 2 + 2, "{text}");
        assert!(rows.iter().any(|r| r.contains("sweep_sah+bvh4")), "{text}");
        assert!(rows[0].contains("vs obvhs") && rows.iter().any(|r| r.contains("obvhs_cwbvh")), "{text}");
        assert!(text.contains("384 primary"), "{text}");
        assert!(!text.contains("NaN") && !text.contains("inf"), "{text}");
    }

    #[test]
    fn rejects_unknown_builders_bad_leaf_sizes_and_empty_scenes() {
        let tris = scene();
        let mut out = Vec::new();
        assert!(write_table(&mut out, &tris, "t", 8, 8, &["octree"], &[4], None, Duration::ZERO).is_err());
        assert!(write_table(&mut out, &tris, "t", 8, 8, &["midpoint"], &[0], None, Duration::ZERO).is_err());
        assert!(write_table(&mut out, &[], "t", 8, 8, &["midpoint"], &[4], None, Duration::ZERO).is_err());
    }

    #[test]
    fn empty_lists_mean_every_builder_and_the_thesis_leaf_sizes() {
        let mut out = Vec::new();
        write_table(&mut out, &scene(), "test", 8, 8, &[], &[], None, Duration::ZERO).unwrap();
        let text = String::from_utf8(out).unwrap();
        let rows = text.lines().filter(|l| l.starts_with('|')).count();
        assert_eq!(rows, 2 + 2 * BUILDERS.len() * LEAF_SIZES.len() + 2, "{text}");
    }
}
