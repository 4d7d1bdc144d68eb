//! `spt render`'s pieces (`--shard`, `--time`, `--write-partial`) and `spt merge`.

use anyhow::{Context, Result, bail};
use clap::Args;
use shard::{Budget, Job, Manifest, Partial, ShardSpec, Split, Work};
use std::path::{Path, PathBuf};
use std::time::Duration;
use tracer::film::Film;
use tracer::output::{ImageFormat, write_image};
use tracer::render::{PreparedScene, RenderSettings, SceneOptions};

/// The program and build that render, as written in every partial's job.
pub const TOOL: &str = concat!("spt ", env!("CARGO_PKG_VERSION"), " (", env!("SPT_COMMIT"), ")");

/// `spt render`'s options for renders split across machines or time.
#[derive(Args, Clone, Debug, Default)]
pub struct PieceArgs {
    /// Render only piece K of N (1-based, e.g. 2/8) and write it as a partial (`-o
    /// NAME.partial`) for `spt merge`. Same seed and settings on every machine; the
    /// merged image equals the unsharded render byte for byte.
    #[arg(long, value_name = "K/N")]
    pub shard: Option<String>,
    /// How --shard cuts the render: samples (every pixel, a range of sample indices per
    /// shard: equal work) or tiles (a band of rows per shard, every sample).
    #[arg(long, default_value = "samples", value_name = "SPLIT")]
    pub shard_by: Split,
    /// Stop before this much wall time (e.g. 90s, 20m, 1h30m; a bare number is seconds),
    /// keeping what is done: the image has fewer samples, and the partial (--partial)
    /// lets the same command continue where it stopped.
    #[arg(long, value_parser = parse_duration, value_name = "DURATION")]
    pub time: Option<Duration>,
    /// Save a checkpoint partial every SECONDS; rerunning the same command after a crash
    /// continues from it and ends with the same bytes as an uninterrupted render.
    #[arg(long, value_name = "SECONDS", value_parser = parse_seconds)]
    pub write_partial: Option<Duration>,
    /// Where the partial goes (default: the output's name plus `.partial`; with --shard,
    /// the output itself).
    #[arg(long, value_name = "FILE")]
    pub partial: Option<PathBuf>,
    /// Replace an existing partial that belongs to another render (without it, such a
    /// file is never overwritten).
    #[arg(long)]
    pub force: bool,
}

fn parse_duration(s: &str) -> Result<Duration, String> {
    let d = match s.trim().parse::<f64>() {
        Ok(secs) => seconds(s, secs)?,
        Err(_) => humantime::parse_duration(s).map_err(|e| format!("'{s}': {e} (e.g. 90s, 20m, 1h30m)"))?,
    };
    if d.is_zero() {
        return Err(format!("'{s}': the time budget must be positive"));
    }
    Ok(d)
}

fn parse_seconds(s: &str) -> Result<Duration, String> {
    seconds(s, s.trim().parse().map_err(|_| format!("'{s}' is not a number of seconds"))?)
}

/// `secs` (read from the argument `s`) as a duration, if positive and at most 10⁹.
fn seconds(s: &str, secs: f64) -> Result<Duration, String> {
    if !(secs > 0.0 && secs <= 1e9) {
        return Err(format!("'{s}': expected a positive number of seconds (at most 10⁹)"));
    }
    Ok(Duration::from_secs_f64(secs))
}

/// What a render writes: an image and maybe a partial (with --time/--write-partial), or
/// only a partial (--shard).
pub struct Outputs {
    /// The image, unless this is a shard.
    pub image: Option<PathBuf>,
    /// The partial, if any.
    pub partial: Option<PathBuf>,
    /// The shard, if any.
    pub shard: Option<ShardSpec>,
}

impl PieceArgs {
    /// Checks the options against the output path, before anything is loaded.
    pub fn outputs(&self, output: &Path) -> Result<Outputs> {
        let is_partial = |p: &Path| p.extension().is_some_and(|e| e == "partial");
        if let Some(spec) = &self.shard {
            let spec = ShardSpec::parse(spec, self.shard_by)?;
            if !is_partial(output) {
                bail!("{}: a shard writes a partial render; name it NAME.partial (then `spt merge`)", output.display());
            }
            if self.partial.is_some() {
                bail!("--partial is for image renders; a shard's partial is its -o");
            }
            return Ok(Outputs { image: None, partial: Some(output.to_path_buf()), shard: Some(spec) });
        }
        if is_partial(output) {
            bail!("{}: a .partial output needs --shard K/N (an image render writes .png or .exr)", output.display());
        }
        ImageFormat::from_path(output)?;
        let partial = match (&self.partial, self.time.is_some() || self.write_partial.is_some()) {
            (Some(p), _) => Some(p.clone()),
            (None, true) => Some(PathBuf::from(format!("{}.partial", output.display()))),
            (None, false) => None,
        };
        if let Some(p) = &partial
            && !is_partial(p)
        {
            bail!("{}: name the partial NAME.partial", p.display());
        }
        Ok(Outputs { image: Some(output.to_path_buf()), partial, shard: None })
    }
}

/// What [`render_piece`] did.
pub struct PieceResult {
    /// The film (every sample of the piece that is done, resumed ones included).
    pub film: Film,
    /// Its manifest.
    pub manifest: Manifest,
    /// Figures from this run.
    pub stats: shard::WorkStats,
}

/// Renders the piece the options ask for into a partial: resumes from an existing
/// partial of the same piece, refuses (without --force) one of anything else, writes
/// checkpoints and the final partial atomically.
pub fn render_piece(
    args: &PieceArgs,
    outputs: &Outputs,
    scene_name: &str,
    prepared: &dyn PreparedScene,
    settings: &RenderSettings,
    options: &SceneOptions,
    bar: &indicatif::ProgressBar,
) -> Result<PieceResult> {
    let caps = prepared.capabilities();
    let job = Job::new(TOOL, prepared.scene(), settings, options, &caps, prepared.camera(settings));
    let work = Work::plan(outputs.shard, settings.width, settings.height, settings.spp, caps.sample_block)?;
    let fresh = Partial::fresh(scene_name, job, outputs.shard, work, caps.sample_block);
    let mut partial = match &outputs.partial {
        Some(path) if path.exists() => resume_or_refuse(path, &fresh.manifest, args.force)?,
        _ => None,
    }
    .unwrap_or(fresh);
    let m = &partial.manifest;
    bar.set_length(m.work.region.pixel_count() * (m.work.samples.end - m.done) as u64);
    let progress = |n| bar.inc(n);
    let budget = Budget { time: args.time, checkpoint_every: args.write_partial };
    // Called only with --write-partial, which implies a partial path.
    let mut checkpoint = |p: &Partial| outputs.partial.as_ref().map_or(Ok(()), |path| p.write(path));
    let stats = shard::run_work(prepared, settings, &mut partial, &budget, &mut checkpoint, &progress)?;
    if let Some(path) = &outputs.partial {
        partial.write(path)?;
    }
    Ok(PieceResult { film: partial.film, manifest: partial.manifest, stats })
}

/// An existing partial at `path`: the same piece is resumed; anything else is an error
/// unless `force` (then it is replaced).
fn resume_or_refuse(path: &Path, fresh: &Manifest, force: bool) -> Result<Option<Partial>> {
    let refuse = |why: String| -> Result<Option<Partial>> {
        if force {
            eprintln!("replacing {} ({why})", path.display());
            Ok(None)
        } else {
            bail!("{} exists and {why}: pass --force to replace it", path.display())
        }
    };
    let old = match Partial::read(path) {
        Ok(p) => p,
        Err(e) => return refuse(format!("cannot be resumed: {e}")),
    };
    let m = &old.manifest;
    let diff = m.job.differences(&fresh.job);
    if !diff.is_empty() {
        return refuse(format!("holds another render ({})", diff.join("; ")));
    }
    if m.work != fresh.work || m.shard != fresh.shard {
        return refuse(format!("holds another piece of this render ({})", m.describe()));
    }
    eprintln!("resuming from {}: {}", path.display(), m.progress());
    Ok(Some(old))
}

/// Writes an image atomically (temporary file, rename).
pub fn write_image_atomically(path: &Path, film: &Film, rgb: &[f32]) -> Result<()> {
    shard::partial::atomically(path, |tmp| Ok(write_image(tmp, film.width(), film.height(), rgb)?))?;
    Ok(())
}

/// `spt merge`'s arguments.
#[derive(Args)]
pub struct MergeArgs {
    /// The partial renders (`spt render --shard K/N -o NAME.partial`, or the checkpoints of
    /// --time/--write-partial).
    #[arg(required = true)]
    partials: Vec<PathBuf>,
    /// The merged image (.png or .exr).
    #[arg(short, long, required_unless_present = "check")]
    output: Option<PathBuf>,
    /// Also write the per-pixel standard error of the mean (linear EXR).
    #[arg(long)]
    stderr: Option<PathBuf>,
    /// Overwrite existing outputs.
    #[arg(long)]
    force: bool,
    /// Only check the partials (one render, every sample exactly once) and print their
    /// manifests as JSON lines; write nothing.
    #[arg(long, conflicts_with_all = ["output", "stderr"])]
    check: bool,
}

/// `spt merge`.
pub fn run_merge(args: MergeArgs) -> Result<()> {
    if args.check {
        let parts = shard::read_manifests(&args.partials)?;
        for (path, m) in &parts {
            println!("{}", serde_json::json!({ "file": path, "manifest": m }));
        }
        shard::plan_coverage(&parts)?;
        eprintln!("{} partials: one render, every sample exactly once", parts.len());
        return Ok(());
    }
    let output = args.output.as_ref().context("-o is required")?;
    ImageFormat::from_path(output)?;
    if let Some(p) = &args.stderr
        && ImageFormat::from_path(p)? != ImageFormat::Exr
    {
        bail!("{}: the standard-error image must be an .exr (it is linear)", p.display());
    }
    for p in std::iter::once(output).chain(&args.stderr) {
        if p.exists() && !args.force {
            return Err(shard::Error::Exists(p.clone()).into());
        }
    }
    let merged = shard::merge(&args.partials)?;
    let film = &merged.film;
    write_image_atomically(output, film, &film.mean_rgb())?;
    if let Some(p) = &args.stderr {
        write_image_atomically(p, film, &film.std_error_rgb())?;
    }
    let job = &merged.parts[0].1.job;
    let shards: Vec<String> = merged.parts.iter().filter_map(|(_, m)| m.shard.map(|s| s.to_string())).collect();
    eprintln!(
        "merged {} partials{}: {}×{} at {} spp, {} rays, {} NaN/Inf samples dropped; wrote {}",
        merged.parts.len(),
        if shards.is_empty() { String::new() } else { format!(" ({})", shards.join(", ")) },
        job.width,
        job.height,
        job.spp,
        merged.rays,
        film.non_finite,
        output.display()
    );
    Ok(())
}
