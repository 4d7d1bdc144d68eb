//! Rendering a piece in passes: within a time budget, with checkpoints, resumable.

use crate::Result;
use crate::partial::Partial;
use std::time::{Duration, Instant};
use tracer::render::{Capabilities, PreparedScene, RenderSettings};

/// When a piece stops and how often it saves itself.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Budget {
    /// Stop before this much wall time has passed (the samples done so far are kept);
    /// `None`: render every sample. At least one pass is always rendered.
    pub time: Option<Duration>,
    /// Call the checkpoint at least this often while rendering; `None`: only the caller
    /// writes, at the end.
    pub checkpoint_every: Option<Duration>,
}

/// Figures from [`run_work`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct WorkStats {
    /// Wall time of the sampling.
    pub wall: Duration,
    /// Pixel samples taken in this run (not counting resumed ones).
    pub samples: u64,
    /// Rays traced in this run.
    pub rays: u64,
    /// Paths cut short by the backend's bounce cap in this run.
    pub truncated: u64,
    /// Passes rendered.
    pub passes: u32,
    /// Checkpoints written.
    pub checkpoints: u32,
}

/// Refuses ([`crate::Error::Plan`]) to render a band of the image's rows on its own with
/// a backend whose integrator splats light paths onto other pixels
/// (`Capabilities::splats`): they would land outside the band, and the band's own pixels
/// would miss the light that other bands' paths splat onto them. [`run_work`] checks it;
/// a caller may check it before preparing a scene, to fail early.
pub fn check_band(caps: &Capabilities) -> Result<()> {
    if caps.splats {
        return Err(crate::Error::Plan(format!(
            "--integrator {} splats each light path wherever it lands on the image, so a band of rows \
             cannot be rendered on its own: shard it by samples (--shard-by samples, the default)",
            caps.integrator
        )));
    }
    Ok(())
}

/// The longest pass when neither a time budget nor checkpoints ask for shorter ones:
/// everything that is left, in one pass.
const UNBOUNDED: Duration = Duration::MAX;

/// Renders the samples of `partial`'s work that it does not hold yet (from
/// `manifest.done` to the end of its range) into its film, in passes: one pass when the
/// budget is unbounded; otherwise passes sized from the speed of the previous one so
/// that the next checkpoint and the end of the time budget fall between passes. Passes
/// start at multiples of the backend's `sample_block`, so the film's bytes do not depend
/// on where the passes fell: a piece rendered in one go, in many passes, or stopped and
/// resumed from its checkpoint ends with the same bytes.
///
/// `checkpoint` is called with the partial whenever `budget.checkpoint_every` has passed
/// since the last call (never after the last pass: the caller writes the result).
///
/// A piece that is a band of rows ([`crate::Split::Tiles`]) is refused as [`check_band`]
/// says.
pub fn run_work(
    prepared: &dyn PreparedScene,
    settings: &RenderSettings,
    partial: &mut Partial,
    budget: &Budget,
    checkpoint: &mut dyn FnMut(&Partial) -> Result<()>,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<WorkStats> {
    let work = partial.manifest.work.clone();
    let whole = work.region == tracer::render::PixelRect::full(settings.width, settings.height);
    let caps = prepared.capabilities();
    if !whole {
        check_band(&caps)?;
    }
    let settings = RenderSettings { crop: (!whole).then_some(work.region), ..settings.clone() };
    let block = caps.sample_block.max(1);
    let start = Instant::now();
    let mut last_checkpoint = start;
    let mut stats = WorkStats::default();
    // Seconds per sample per pixel, from the last pass.
    let mut per_spp: Option<f64> = None;
    let end = work.samples.end as u64;
    while partial.manifest.done < work.samples.end {
        let done = partial.manifest.done;
        let until_budget = budget.time.map_or(UNBOUNDED, |t| t.saturating_sub(start.elapsed()));
        let until_checkpoint =
            budget.checkpoint_every.map_or(UNBOUNDED, |c| c.saturating_sub(last_checkpoint.elapsed()));
        // Passes end on a multiple of the block (or at the end of the work), at the
        // earliest on the next one; the first is that one, and its speed sizes the rest.
        let next_boundary = ((done / block + 1) * block) as u64;
        let pass_end = match per_spp {
            None if until_budget == UNBOUNDED && until_checkpoint == UNBOUNDED => end,
            None => next_boundary,
            Some(per) => {
                let fits = |d: Duration| if d == UNBOUNDED { u64::MAX } else { (d.as_secs_f64() / per) as u64 };
                let by_budget = (done as u64).saturating_add(fits(until_budget));
                if by_budget < next_boundary.min(end) {
                    break; // the next pass would overrun the budget
                }
                let wanted = by_budget.min((done as u64).saturating_add(fits(until_checkpoint).max(1)));
                (wanted / block as u64 * block as u64).max(next_boundary)
            }
        };
        let n = (pass_end.min(end) - done as u64) as u32;
        let pass_start = Instant::now();
        let counters = prepared.render_pass(&settings, &mut partial.film, done, n, progress)?;
        let secs = pass_start.elapsed().as_secs_f64();
        per_spp = Some((secs / n as f64).max(1e-9));
        partial.manifest.done += n;
        partial.manifest.rays += counters.rays;
        stats.passes += 1;
        stats.samples += work.region.pixel_count() * n as u64;
        stats.rays += counters.rays;
        stats.truncated += counters.truncated;
        let more = partial.manifest.done < work.samples.end;
        if more && budget.checkpoint_every.is_some_and(|c| last_checkpoint.elapsed() >= c) {
            checkpoint(partial)?;
            stats.checkpoints += 1;
            last_checkpoint = Instant::now();
        }
        if more && budget.time.is_some_and(|t| start.elapsed() >= t) {
            break;
        }
    }
    stats.wall = start.elapsed();
    Ok(stats)
}
