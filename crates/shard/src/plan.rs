//! Which pixel samples a shard renders.

use crate::{Error, Result};
use serde::{Deserialize, Serialize};
use std::ops::Range;
use tracer::render::PixelRect;

/// How a render is cut into shards.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Split {
    /// Every pixel, a contiguous range of sample indices per shard: the shards' work is
    /// equal whatever the image looks like (the default).
    #[default]
    Samples,
    /// A band of whole rows per shard, every sample: a shard's partial holds only its
    /// rows (smaller files), but bands of the image may cost unequal time.
    Tiles,
}

impl Split {
    /// Every split, for messages and parsing.
    pub const ALL: [Split; 2] = [Split::Samples, Split::Tiles];

    /// The CLI's name (`samples`, `tiles`).
    pub fn name(self) -> &'static str {
        match self {
            Split::Samples => "samples",
            Split::Tiles => "tiles",
        }
    }
}

impl std::str::FromStr for Split {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Split::ALL
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| format!("unknown split '{s}' (known: samples, tiles)"))
    }
}

/// Shard `index` of `count` (1-based, as schedulers' array indices mostly are: `--shard
/// 1/4` … `--shard 4/4`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct ShardSpec {
    /// Which shard, 1 ..= count.
    pub index: u32,
    /// How many shards.
    pub count: u32,
    /// How the render is cut.
    pub split: Split,
}

impl ShardSpec {
    /// Parses `K/N` (1 ≤ K ≤ N).
    pub fn parse(s: &str, split: Split) -> Result<Self> {
        let bad = || Error::Plan(format!("--shard '{s}': expected K/N with 1 ≤ K ≤ N, e.g. 2/8"));
        let (k, n) = s.split_once('/').ok_or_else(bad)?;
        let index: u32 = k.trim().parse().map_err(|_| bad())?;
        let count: u32 = n.trim().parse().map_err(|_| bad())?;
        if count == 0 || index == 0 || index > count {
            return Err(bad());
        }
        Ok(Self { index, count, split })
    }

    /// The pixels and samples this shard renders, for a `width` × `height` image at
    /// `spp` samples per pixel. `sample_block` is the backend's
    /// [`tracer::render::Capabilities::sample_block`]: sample ranges start at multiples of
    /// it, so that the shards merge to the same bytes as one render on that backend.
    pub fn work(&self, width: u32, height: u32, spp: u32, sample_block: u32) -> Result<Work> {
        let (k, n) = (self.index as u64, self.count as u64);
        match self.split {
            Split::Samples => {
                let block = sample_block.max(1) as u64;
                let blocks = (spp as u64).div_ceil(block);
                if blocks < n {
                    return Err(Error::Plan(format!(
                        "{} shards by samples need at least {n} blocks of {block} samples per pixel (--spp {spp} \
                         gives {blocks}{}): use fewer shards, more samples, or --shard-by tiles",
                        self.count,
                        if block > 1 { ", the backend's smallest bit-exact split" } else { "" }
                    )));
                }
                let edge = |k: u64| ((k * blocks / n) * block).min(spp as u64) as u32;
                Ok(Work { region: PixelRect::full(width, height), samples: edge(k - 1)..edge(k) })
            }
            Split::Tiles => {
                if (height as u64) < n {
                    return Err(Error::Plan(format!(
                        "{} shards by tiles need at least {n} image rows (the image has {height}): use fewer \
                         shards, or --shard-by samples",
                        self.count
                    )));
                }
                let edge = |k: u64| (k * height as u64 / n) as u32;
                let (y0, y1) = (edge(k - 1), edge(k));
                Ok(Work { region: PixelRect { x: 0, y: y0, width, height: y1 - y0 }, samples: 0..spp })
            }
        }
    }
}

impl std::fmt::Display for ShardSpec {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "shard {}/{} by {}", self.index, self.count, self.split.name())
    }
}

/// A piece of a render: samples `samples` of every pixel in `region`.
#[derive(Clone, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Work {
    /// The pixels.
    pub region: PixelRect,
    /// The sample indices, the same for every pixel of the region.
    pub samples: Range<u32>,
}

impl std::fmt::Display for Work {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "samples {}..{} of {}", self.samples.start, self.samples.end, self.region)
    }
}

impl Work {
    /// The whole render: every pixel, samples `0 .. spp`.
    pub fn whole(width: u32, height: u32, spp: u32) -> Self {
        Self { region: PixelRect::full(width, height), samples: 0..spp }
    }

    /// The work of `shard` (see [`ShardSpec::work`]), or the whole render without one.
    pub fn plan(shard: Option<ShardSpec>, width: u32, height: u32, spp: u32, sample_block: u32) -> Result<Self> {
        match shard {
            Some(spec) => spec.work(width, height, spp, sample_block),
            None => Ok(Self::whole(width, height, spp)),
        }
    }

    /// Pixel samples in it.
    pub fn pixel_samples(&self) -> u64 {
        self.region.pixel_count() * self.samples.len() as u64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_partition_the_samples_and_the_rows() {
        for (spp, block, n) in [(64, 1, 4), (10, 1, 3), (7, 1, 7), (5000, 1024, 4), (1100, 1024, 2), (1, 1, 1)] {
            let works: Vec<Work> = (1..=n)
                .map(|k| ShardSpec { index: k, count: n, split: Split::Samples }.work(9, 5, spp, block).unwrap())
                .collect();
            let mut next = 0;
            for w in &works {
                assert_eq!(w.region, PixelRect::full(9, 5));
                assert_eq!(w.samples.start, next, "{spp} spp, {n} shards");
                assert!(w.samples.start % block == 0 && !w.samples.is_empty());
                next = w.samples.end;
            }
            assert_eq!(next, spp);
        }
        for (height, n) in [(5, 5), (512, 3), (7, 2)] {
            let mut next = 0;
            for k in 1..=n {
                let w = ShardSpec { index: k, count: n, split: Split::Tiles }.work(4, height, 16, 1024).unwrap();
                assert_eq!((w.region.y, w.region.x, w.region.width, w.samples.clone()), (next, 0, 4, 0..16));
                assert!(w.region.height >= height / n);
                next += w.region.height;
            }
            assert_eq!(next, height);
        }
    }

    #[test]
    fn impossible_shards_are_refused() {
        for bad in ["0/4", "5/4", "1/0", "4", "a/b", "-1/2", ""] {
            assert!(ShardSpec::parse(bad, Split::Samples).is_err(), "{bad}");
        }
        assert_eq!(
            ShardSpec::parse(" 2/ 8", Split::Tiles).unwrap(),
            ShardSpec { index: 2, count: 8, split: Split::Tiles }
        );
        let msg = ShardSpec::parse("3/4", Split::Samples).unwrap().work(8, 8, 3, 1).unwrap_err().to_string();
        assert!(msg.contains("--spp 3") && msg.contains("--shard-by tiles"), "{msg}");
        let msg = ShardSpec::parse("1/2", Split::Samples).unwrap().work(8, 8, 1000, 1024).unwrap_err().to_string();
        assert!(msg.contains("blocks of 1024"), "{msg}");
        let msg = ShardSpec::parse("1/9", Split::Tiles).unwrap().work(8, 8, 16, 1).unwrap_err().to_string();
        assert!(msg.contains("the image has 8"), "{msg}");
    }
}
