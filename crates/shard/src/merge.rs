//! Putting partial renders back together.

use crate::manifest::{Manifest, same_job};
use crate::partial::Reader;
use crate::plan::{Split, Work};
use crate::{Error, Result};
use std::ops::Range;
use std::path::PathBuf;
use tracer::film::Film;
use tracer::render::PixelRect;

/// A merged render.
#[derive(Debug)]
pub struct Merged {
    /// The film: every pixel with every sample, as one render would have it.
    pub film: Film,
    /// The partials' manifests, in the order given.
    pub parts: Vec<(PathBuf, Manifest)>,
    /// Rays traced by all the parts.
    pub rays: u64,
}

/// Reads the partials' manifests, checks that they are one render's pieces covering
/// every pixel's samples exactly once ([`plan_coverage`]), and adds their films.
pub fn merge(paths: &[PathBuf]) -> Result<Merged> {
    let parts = read_manifests(paths)?;
    plan_coverage(&parts)?;
    let job = &parts[0].1.job;
    let mut film = Film::new(job.width, job.height);
    let mut rays = 0;
    // Each file is opened again here, one at a time: holding thousands of shards open
    // since the manifests were read could exceed the limit on open files.
    for (path, _) in &parts {
        let mut reader = Reader::open(path)?;
        reader.add_into(&mut film)?;
        rays += reader.manifest.rays;
    }
    Ok(Merged { film, parts, rays })
}

/// Each partial's manifest (checked for magic, format and length; the pixels are not
/// read), with its path.
pub fn read_manifests(paths: &[PathBuf]) -> Result<Vec<(PathBuf, Manifest)>> {
    paths.iter().map(|p| Ok((p.clone(), Reader::open(p)?.manifest))).collect()
}

/// Checks that the partials belong to one render (equal jobs) and that, together, they
/// hold samples `0 .. spp` of every pixel exactly once; otherwise lists every duplicate,
/// overlap and gap, with the shards to rerun where the manifests say which they were.
pub fn plan_coverage(parts: &[(PathBuf, Manifest)]) -> Result<()> {
    let Some((_, first)) = parts.first() else {
        return Err(Error::Coverage("no partials to merge".into()));
    };
    same_job(parts.iter().map(|(p, m)| (p.as_path(), m)))?;
    let (width, height, spp) = (first.job.width, first.job.height, first.job.spp);
    let mut problems = Vec::new();

    // Pieces of the same region, and regions that overlap without being equal.
    let mut regions: Vec<(PixelRect, Vec<usize>)> = Vec::new();
    for (i, (_, m)) in parts.iter().enumerate() {
        match regions.iter_mut().find(|(r, _)| *r == m.work.region) {
            Some((_, members)) => members.push(i),
            None => regions.push((m.work.region, vec![i])),
        }
    }
    for (a, (ra, ia)) in regions.iter().enumerate() {
        for (rb, ib) in &regions[a + 1..] {
            if ra.overlaps(rb) {
                problems.push(format!(
                    "{} ({ra}) and {} ({rb}) overlap: their common pixels would be counted twice",
                    name(parts, ia[0]),
                    name(parts, ib[0])
                ));
            }
        }
    }

    // Every pixel in some region.
    let uncovered = uncovered_rows(width, height, regions.iter().map(|(r, _)| r));
    if !uncovered.is_empty() {
        let rows: Vec<String> = uncovered.iter().map(|r| format!("{}..{}", r.start, r.end)).collect();
        let mut line = format!("no partial holds (all of) rows {}", rows.join(", "));
        if let Some(missing) = missing_shards(parts, Split::Tiles, |w| {
            uncovered.iter().any(|r| r.start < w.region.y + w.region.height && w.region.y < r.end)
        }) {
            line += &format!(" — missing {missing}");
        }
        problems.push(line);
    }

    // Every sample of every region exactly once.
    for (region, members) in &regions {
        let mut held: Vec<(Range<u32>, usize)> = members.iter().map(|&i| (parts[i].1.done_samples(), i)).collect();
        held.sort_by_key(|(r, _)| (r.start, r.end));
        for pair in held.windows(2) {
            let ((a, ia), (b, ib)) = (&pair[0], &pair[1]);
            if a == b {
                problems.push(format!(
                    "{} and {} both hold samples {}..{} of {region}: a duplicate (give each piece once)",
                    name(parts, *ia),
                    name(parts, *ib),
                    a.start,
                    a.end
                ));
            } else if b.start < a.end {
                problems.push(format!(
                    "{} (samples {}..{}) and {} (samples {}..{}) overlap on {region}",
                    name(parts, *ia),
                    a.start,
                    a.end,
                    name(parts, *ib),
                    b.start,
                    b.end
                ));
            }
        }
        let mut gaps = Vec::new();
        let mut next = 0;
        for (r, _) in &held {
            if r.start > next {
                gaps.push(next..r.start);
            }
            next = next.max(r.end);
        }
        if next < spp {
            gaps.push(next..spp);
        }
        for gap in gaps {
            let mut line = format!("samples {}..{} of {region} are missing", gap.start, gap.end);
            let interrupted: Vec<String> = members
                .iter()
                .filter(|&&i| !parts[i].1.complete() && parts[i].1.done == gap.start)
                .map(|&i| format!("{} stopped there (rerun its command to finish it)", name(parts, i)))
                .collect();
            if !interrupted.is_empty() {
                line += &format!(" — {}", interrupted.join(", "));
            } else if let Some(missing) = missing_shards(parts, Split::Samples, |w| {
                w.region == *region && w.samples.start < gap.end && gap.start < w.samples.end
            }) {
                line += &format!(" — missing {missing}");
            }
            problems.push(line);
        }
    }
    if problems.is_empty() {
        Ok(())
    } else {
        Err(Error::Coverage(format!(
            "the {} partials do not cover the {width}×{height} render at {spp} spp exactly once:\n  - {}",
            parts.len(),
            problems.join("\n  - ")
        )))
    }
}

fn name(parts: &[(PathBuf, Manifest)], i: usize) -> String {
    let (path, m) = &parts[i];
    format!("{} [{}]", path.display(), m.describe())
}

/// Rows (as ranges) where the regions do not cover every column.
fn uncovered_rows<'a>(
    width: u32,
    height: u32,
    regions: impl Iterator<Item = &'a PixelRect> + Clone,
) -> Vec<Range<u32>> {
    let mut out: Vec<Range<u32>> = Vec::new();
    for y in 0..height {
        let covered: u64 = regions.clone().filter(|r| y >= r.y && y - r.y < r.height).map(|r| r.width as u64).sum();
        if covered < width as u64 {
            match out.last_mut() {
                Some(last) if last.end == y => last.end = y + 1,
                _ => out.push(y..y + 1),
            }
        }
    }
    out
}

/// The shards of the plan the partials came from (if they all name the same split and
/// count) whose work `missing` selects and which no partial is: `shard 3/4 by tiles
/// (…)`, comma-separated.
fn missing_shards(parts: &[(PathBuf, Manifest)], split: Split, missing: impl Fn(&Work) -> bool) -> Option<String> {
    let specs: Vec<_> = parts.iter().map(|(_, m)| m.shard).collect();
    let first = specs.first().copied().flatten()?;
    if first.split != split || specs.iter().any(|s| s.is_none_or(|s| s.count != first.count || s.split != split)) {
        return None;
    }
    let (job, block) = (&parts[0].1.job, parts[0].1.sample_block);
    let names: Vec<String> = (1..=first.count)
        .filter(|&k| !specs.iter().any(|s| s.is_some_and(|s| s.index == k)))
        .filter_map(|k| {
            let spec = crate::ShardSpec { index: k, ..first };
            let work = spec.work(job.width, job.height, job.spp, block).ok()?;
            missing(&work).then(|| format!("{spec} ({work})"))
        })
        .collect();
    (!names.is_empty()).then(|| names.join(", "))
}
