//! A piece of a render on disk.
//!
//! # File format (`.partial`, version 1)
//!
//! All integers little-endian.
//!
//! | bytes | content |
//! |---|---|
//! | 8 | magic `SPTPART1` |
//! | 4 | `u32` M: length of the manifest |
//! | M | the [`Manifest`] as UTF-8 JSON |
//! | 100 per pixel | the region's pixels, row by row: `u32` count, then Σx per channel as three `i128`, then Σx² per channel as three `u128` — the film's fixed-point sums ([`tracer::film::PixelStats`]: x · 2⁶⁴ and x² · 2³⁶ rounded per sample) |
//! | 48 per pixel, only if the manifest's `light_paths` > 0 | the whole image's splat sums, row by row: Σx per channel as three `i128` (x · 2⁶⁴; [`tracer::film::Film::splat_sums`]) |
//! | 32 | SHA-256 of every byte before it |
//!
//! The file is written under a temporary name in the same directory, synced and renamed,
//! so a reader sees either the previous file or the whole new one; and its bytes depend
//! only on what was rendered (no time stamps, no host names), so a shard rerun with the
//! same arguments writes the same bytes.

use crate::manifest::{FORMAT_VERSION, Job, Manifest};
use crate::plan::{ShardSpec, Work};
use crate::{Error, Result};
use sha2::{Digest, Sha256};
use std::fs::File;
use std::io::{BufReader, BufWriter, Read, Write};
use std::path::{Path, PathBuf};
use tracer::film::{Film, PixelStats};

/// The first eight bytes of every partial.
pub const MAGIC: &[u8; 8] = b"SPTPART1";

/// Bytes per pixel record.
pub const PIXEL_BYTES: usize = 4 + 3 * 16 + 3 * 16;

/// Bytes per pixel of the splat section.
pub const SPLAT_BYTES: usize = 3 * 16;

/// The longest manifest accepted (a real one is under 2 KiB).
const MAX_MANIFEST_BYTES: u32 = 1 << 20;

/// A piece of a render: its manifest and a full-size film whose pixels inside the
/// manifest's region hold the piece's samples (the others are empty).
#[derive(Clone, Debug, PartialEq)]
pub struct Partial {
    /// What the piece is.
    pub manifest: Manifest,
    /// The sums.
    pub film: Film,
}

impl Partial {
    /// A piece with nothing rendered yet: an empty full-size film and a manifest whose
    /// `done` is the start of the work's samples.
    pub fn fresh(scene: &str, job: Job, shard: Option<ShardSpec>, work: Work, sample_block: u32) -> Self {
        let film = Film::new(job.width, job.height);
        let manifest = Manifest {
            format: FORMAT_VERSION,
            scene: scene.to_string(),
            job,
            shard,
            done: work.samples.start,
            work,
            sample_block,
            non_finite: 0,
            rays: 0,
            light_paths: 0,
        };
        Partial { manifest, film }
    }

    /// Writes the partial to `path` atomically (temporary file, sync, rename). The
    /// manifest's count of dropped samples is the film's.
    pub fn write(&self, path: &Path) -> Result<()> {
        let m = &Manifest {
            non_finite: self.film.non_finite,
            light_paths: self.film.light_paths(),
            ..self.manifest.clone()
        };
        if self.film.width() != m.job.width || self.film.height() != m.job.height {
            return Err(Error::Mismatch("film size differs from the manifest's".into()));
        }
        let json = serde_json::to_vec_pretty(m).expect("manifests serialise");
        atomically(path, |tmp| {
            let io = |source| Error::Io { path: tmp.to_path_buf(), source };
            let mut out = HashingWriter { inner: BufWriter::new(File::create(tmp).map_err(io)?), hash: Sha256::new() };
            out.write_all(MAGIC).map_err(io)?;
            out.write_all(&(json.len() as u32).to_le_bytes()).map_err(io)?;
            out.write_all(&json).map_err(io)?;
            let r = m.work.region;
            for y in r.y..r.y + r.height {
                for x in r.x..r.x + r.width {
                    out.write_all(&encode(self.film.pixel(x, y))).map_err(io)?;
                }
            }
            if m.light_paths > 0 {
                let none = [[0i128; 3]];
                let sums = self.film.splat_sums().unwrap_or(&none);
                for i in 0..self.film.pixels().len() {
                    let s = sums.get(i).unwrap_or(&[0; 3]);
                    for c in s {
                        out.write_all(&c.to_le_bytes()).map_err(io)?;
                    }
                }
            }
            let digest = out.hash.finalize();
            let mut inner = out.inner;
            inner.write_all(&digest).map_err(io)?;
            let file = inner.into_inner().map_err(|e| io(e.into_error()))?;
            file.sync_all().map_err(io)
        })
    }

    /// Reads a whole partial, checking its manifest, its length and its checksum.
    pub fn read(path: &Path) -> Result<Self> {
        let mut reader = Reader::open(path)?;
        let j = &reader.manifest.job;
        let mut film = Film::new(j.width, j.height);
        reader.add_into(&mut film)?;
        Ok(Partial { manifest: reader.manifest, film })
    }
}

/// A partial opened for reading: the manifest is read and checked, the pixels follow.
pub struct Reader {
    path: PathBuf,
    input: BufReader<File>,
    hash: Sha256,
    /// The file's manifest.
    pub manifest: Manifest,
}

impl Reader {
    /// Opens `path` and reads its manifest; refuses a file whose magic, manifest or
    /// length is wrong (the checksum is checked by [`Reader::add_into`]).
    pub fn open(path: &Path) -> Result<Self> {
        let corrupt = |reason: String| Error::Corrupt { path: path.to_path_buf(), reason };
        let file = File::open(path).map_err(|source| Error::Io { path: path.to_path_buf(), source })?;
        let len = file.metadata().map_err(|source| Error::Io { path: path.to_path_buf(), source })?.len();
        let mut input = BufReader::new(file);
        let mut hash = Sha256::new();
        let mut read = |buf: &mut [u8], what: &str| read_hashed(&mut input, &mut hash, buf, what, path);
        let mut magic = [0u8; 8];
        read(&mut magic, "the magic number")?;
        if &magic != MAGIC {
            return Err(corrupt(format!("it starts with {magic:?}, not the magic number {MAGIC:?}")));
        }
        let mut m = [0u8; 4];
        read(&mut m, "the manifest's length")?;
        let m = u32::from_le_bytes(m);
        if m > MAX_MANIFEST_BYTES || m as u64 > len {
            return Err(corrupt(format!("a manifest of {m} bytes in a file of {len}")));
        }
        let mut json = vec![0u8; m as usize];
        read(&mut json, "the manifest")?;
        let manifest: Manifest =
            serde_json::from_slice(&json).map_err(|e| corrupt(format!("its manifest is not valid: {e}")))?;
        manifest.validate().map_err(|e| corrupt(format!("its manifest is not valid: {e}")))?;
        let splats = if manifest.light_paths > 0 {
            manifest.job.width as u64 * manifest.job.height as u64 * SPLAT_BYTES as u64
        } else {
            0
        };
        let expected = 8 + 4 + m as u64 + manifest.work.region.pixel_count() * PIXEL_BYTES as u64 + splats + 32;
        if len != expected {
            return Err(corrupt(format!(
                "{len} bytes, but its manifest ({}) makes {expected}: the file is truncated or was altered",
                manifest.describe()
            )));
        }
        Ok(Reader { path: path.to_path_buf(), input, hash, manifest })
    }

    /// Adds the file's pixels to `film` (the job's size), then checks the checksum. On an
    /// error the film may hold part of the file: discard it.
    pub fn add_into(&mut self, film: &mut Film) -> Result<()> {
        let m = &self.manifest;
        if film.width() != m.job.width || film.height() != m.job.height {
            return Err(Error::Mismatch(format!(
                "{}: a {}×{} render, not {}×{}",
                self.path.display(),
                m.job.width,
                m.job.height,
                film.width(),
                film.height()
            )));
        }
        let (r, held, width) = (m.work.region, m.done_samples().len() as u32, film.width());
        let mut record = [0u8; PIXEL_BYTES];
        for y in r.y..r.y + r.height {
            for x in r.x..r.x + r.width {
                read_hashed(&mut self.input, &mut self.hash, &mut record, "a pixel", &self.path)?;
                let p = decode(&record);
                if p.count > held {
                    return Err(Error::Corrupt {
                        path: self.path.clone(),
                        reason: format!(
                            "pixel ({x}, {y}) has {} samples, but the file holds {held} per pixel",
                            p.count
                        ),
                    });
                }
                film.pixels_mut()[(y * width + x) as usize].merge(&p);
            }
        }
        if m.light_paths > 0 {
            let mut record = [0u8; SPLAT_BYTES];
            for i in 0..film.pixels().len() {
                read_hashed(&mut self.input, &mut self.hash, &mut record, "a splat", &self.path)?;
                let word = |c: usize| -> [u8; 16] { record[16 * c..16 * c + 16].try_into().expect("16 bytes") };
                film.add_splat_sum(i, std::array::from_fn(|c| i128::from_le_bytes(word(c))));
            }
        }
        let digest = std::mem::take(&mut self.hash).finalize();
        let mut stored = [0u8; 32];
        self.input.read_exact(&mut stored).map_err(|e| Error::Corrupt {
            path: self.path.clone(),
            reason: format!("cannot read the checksum: {e}"),
        })?;
        if stored[..] != digest[..] {
            return Err(Error::Corrupt {
                path: self.path.clone(),
                reason: "its SHA-256 does not match its content: the file was damaged".into(),
            });
        }
        film.non_finite += m.non_finite;
        film.count_light_paths(m.light_paths);
        Ok(())
    }
}

/// Reads exactly `buf.len()` bytes and adds them to the running checksum.
fn read_hashed(input: &mut impl Read, hash: &mut Sha256, buf: &mut [u8], what: &str, path: &Path) -> Result<()> {
    input.read_exact(buf).map_err(|e| Error::Corrupt {
        path: path.to_path_buf(),
        reason: format!("cannot read {what}: {e} (truncated?)"),
    })?;
    hash.update(&*buf);
    Ok(())
}

fn encode(p: &PixelStats) -> [u8; PIXEL_BYTES] {
    let mut out = [0u8; PIXEL_BYTES];
    out[..4].copy_from_slice(&p.count.to_le_bytes());
    for c in 0..3 {
        out[4 + 16 * c..20 + 16 * c].copy_from_slice(&p.sum[c].to_le_bytes());
        out[52 + 16 * c..68 + 16 * c].copy_from_slice(&p.sum_sq[c].to_le_bytes());
    }
    out
}

fn decode(b: &[u8; PIXEL_BYTES]) -> PixelStats {
    let word = |i: usize| -> [u8; 16] { b[i..i + 16].try_into().expect("16 bytes") };
    PixelStats {
        count: u32::from_le_bytes(b[..4].try_into().expect("4 bytes")),
        sum: std::array::from_fn(|c| i128::from_le_bytes(word(4 + 16 * c))),
        sum_sq: std::array::from_fn(|c| u128::from_le_bytes(word(52 + 16 * c))),
    }
}

struct HashingWriter<W: Write> {
    inner: W,
    hash: Sha256,
}

impl<W: Write> Write for HashingWriter<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.hash.update(&buf[..n]);
        Ok(n)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

/// Runs `write` on a temporary path beside `path` (same directory, same extension, so
/// that writers choosing a format by extension still work), then renames it to `path`;
/// on failure the temporary file is removed and `path` is untouched.
pub fn atomically(path: &Path, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let ext = path.extension().map(|e| format!(".{}", e.to_string_lossy())).unwrap_or_default();
    let tmp = path.with_file_name(format!(".{name}.tmp-{}{ext}", std::process::id()));
    let result = write(&tmp)
        .and_then(|()| std::fs::rename(&tmp, path).map_err(|source| Error::Io { path: path.to_path_buf(), source }));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn records_round_trip() {
        let mut p = PixelStats::default();
        for x in [-3.5f32, 1e-20, 17_000_000_000.0, 0.25] {
            assert!(p.add([x, -x, x * 0.5]));
        }
        assert_eq!(decode(&encode(&p)), p);
    }
}
