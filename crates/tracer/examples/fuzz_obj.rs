//! A dependency-free mutation fuzzer for the OBJ and MTL readers
//! ([`tracer::obj::load_obj_text`]): real scene files are mutated at random and loaded
//! from memory; every input must load or fail with an error, never panic, hang, or
//! allocate out of proportion to its size.
//!
//! Why an example and not a cargo-fuzz target: cargo-fuzz needs a nightly compiler for
//! its sanitizers, and this workspace builds on stable. An example links the real library
//! (the release build for long runs), may install its own global allocator to measure
//! allocation per input (a library must not), adds no crate to the workspace, and —
//! declared with `test = true` in `Cargo.toml` — its short run below executes as an
//! ordinary `cargo test -p tracer`, in the test profile with overflow checks on.
//!
//! Long runs, with release optimisation but overflow checks and debug assertions on (so
//! that arithmetic overflow in the loader or in `tobj` panics instead of wrapping; a
//! separate target directory keeps the ordinary release build untouched):
//!
//! ```sh
//! CARGO_PROFILE_RELEASE_OVERFLOW_CHECKS=true CARGO_PROFILE_RELEASE_DEBUG_ASSERTIONS=true \
//!   CARGO_TARGET_DIR=target/fuzz cargo run --release -p tracer --example fuzz_obj -- \
//!   --inputs 10000000 --seed 1
//! ```
//!
//! Options: `--inputs N` (default 100000), `--seed S` (default 1), `--shared DIR` (the
//! shared scenes, default `../shared` beside the checkout; the hand-written seeds are
//! used without it), `--replay K` (run only input K and print it), `--dump DIR` (write
//! every input that panics there, as `K.obj` and `K.mtl`). Input K is a function of the
//! seed and K alone, so any input of a long run can be replayed on its own.

use std::collections::HashMap;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

// ---------------------------------------------------------------------------------------
// Allocation counting
// ---------------------------------------------------------------------------------------

#[path = "support/counting_alloc.rs"]
mod counting_alloc;
use counting_alloc::{LIVE, PEAK};

#[global_allocator]
static ALLOCATOR: counting_alloc::Counting = counting_alloc::Counting;

// ---------------------------------------------------------------------------------------
// Random numbers
// ---------------------------------------------------------------------------------------

/// SplitMix64 (Steele, Lea & Flood 2014): tiny, fast, and good enough to pick mutations.
struct SplitMix64(u64);

impl SplitMix64 {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in 0..n (n > 0; the modulo bias is irrelevant here).
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
    /// True with probability 1/n.
    fn one_in(&mut self, n: usize) -> bool {
        self.below(n) == 0
    }
    fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
}

/// The generator of input `index` of a run with `seed`: inputs are independent, so any
/// one can be replayed alone.
fn input_rng(seed: u64, index: u64) -> SplitMix64 {
    let mut r = SplitMix64(seed ^ index.wrapping_mul(0xD1B5_4A32_D192_ED03));
    r.next();
    r
}

// ---------------------------------------------------------------------------------------
// Seeds
// ---------------------------------------------------------------------------------------

/// An OBJ with the MTL library it names (empty name: none).
#[derive(Clone)]
struct Seed {
    name: String,
    obj: String,
    mtl_name: String,
    mtl: String,
}

/// Every MTL statement the loader reads, with one- and three-value colours, every
/// `illum` that picks a model, every `bsdf` name and the thesis's extensions.
const ALL_STATEMENTS_MTL: &str = "# every statement the loader reads
newmtl grey
Ka 0.1 0.1 0.1
Kd 0.5
Ks 0
Ke 0 0 0
Ns 10.0
Ni 1.5
d 1
Tr 0
Tf 1 1 1
illum 2
map_Kd grey.png
map_bump grey-bump.png
bump grey-bump.png
newmtl red # a comment
Kd 0.63 0.065 0.05 # red
illum 1
newmtl lamp
Kd 0.78 0.78 0.78
Ke 17 12 4
newmtl grey-lamp
Ke 5
newmtl mirror
illum 3
Ks 0.9 0.9 0.9
newmtl glass
illum 7
Ni 1.33
Tf 0.9 0.95 1
dispersion 1
cauchy_b 0.01
absorption 0.1 0.2 0.3
newmtl faded
d 0.5
Ni 1.2
newmtl transparent
Tr 0.25
newmtl schlick
Kd 0.5 0.2 0.1
rough 0.2
p 0.5
newmtl ashikhmin
nu 1000
nv 10
Rs 0.1 0.1 0.1
Rd 0.4
newmtl velvet
bsdf orennayar
Kd 0.5 0.5 0.5
sigma 0.3
newmtl gold
bsdf conductor
newmtl brushed
bsdf roughconductor
newmtl frosted
bsdf roughdielectric
Ni 1.5
newmtl plain
bsdf lambert
Kd 0.25
newmtl steel
bsdf mirror
newmtl water
bsdf dielectric
Ni 1.33
";

/// An OBJ using every material above and every geometry statement: quads, polygons,
/// negative indices, `v/vt/vn` forms, `w`, vertex colours, groups, objects, smoothing
/// groups, points and lines.
const ALL_STATEMENTS_OBJ: &str = "# a small scene using every statement
mtllib all.mtl
o room
v -1 0 -1
v 1 0 -1
v 1 0 1
v -1 0 1
v -1 2 -1 1
v 1 2 -1 1.0
v 1 2 1 0.5 0.5 0.5
v -1 2 1
vt 0 0
vt 1 0
vt 1 1
vt 0.5
vn 0 1 0
vn 0 -1 0
g floor
usemtl grey
s 1
f 1/1/1 2/2/1 3/3/1 4/4/1
g ceiling
usemtl lamp
f 8//2 7//2 6//2 5//2 # a comment
usemtl red
f 1 5 6 2
usemtl mirror
f -8 -4 -1 -5
usemtl glass
f 2/1 6/2 7/3
f 2 7 3
usemtl faded
f 3 7 8
usemtl transparent
f 3 8 4
usemtl schlick
f 1 2 3
usemtl ashikhmin
f 1 3 4
usemtl velvet
f 5 6 7 8 1 2
usemtl gold
f 1 2 3
usemtl brushed
f 1 2 3
usemtl frosted
f 1 2 3
usemtl plain
f 1 2 3
usemtl steel
f 1 2 3
usemtl water
f 1 2 3
usemtl grey-lamp
f 4 3 2
usemtl undefined
f 1 2 4
p 1
l 1 2
l 1 2 3
";

/// A tiny OBJ with a one-value `Kd`, the form that used to panic.
const ONE_VALUE_OBJ: &str = "mtllib one.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n";
const ONE_VALUE_MTL: &str = "newmtl a\nKd 0.5\nKe 1\nTf 0.5\n";

fn builtin_seeds() -> Vec<Seed> {
    let seed = |name: &str, obj: &str, mtl_name: &str, mtl: &str| Seed {
        name: name.into(),
        obj: obj.into(),
        mtl_name: mtl_name.into(),
        mtl: mtl.into(),
    };
    vec![
        seed("all", ALL_STATEMENTS_OBJ, "all.mtl", ALL_STATEMENTS_MTL),
        seed("one-value", ONE_VALUE_OBJ, "one.mtl", ONE_VALUE_MTL),
    ]
}

/// The first `max_each` `v`, `vt` and `vn` lines of an OBJ, the faces that use only
/// those, and every other statement: a small, valid excerpt of a big file.
fn excerpt(text: &str, max_each: usize) -> String {
    let mut counts = HashMap::new();
    let mut out = String::new();
    for line in text.lines() {
        let key = line.split_whitespace().next().unwrap_or("");
        let keep = match key {
            "v" | "vt" | "vn" => {
                let n = counts.entry(key).or_insert(0usize);
                *n += 1;
                *n <= max_each
            }
            "f" => line
                .split_whitespace()
                .skip(1)
                .flat_map(|c| c.split('/'))
                .all(|i| i.is_empty() || i.parse::<usize>().is_ok_and(|i| i <= max_each)),
            _ => true,
        };
        if keep {
            out.push_str(line);
            out.push('\n');
        }
    }
    out
}

/// The shared scenes' files as seeds, where they exist: the Cornell box whole, and
/// excerpts of Sponza (with its MTL) and of the bunny.
fn shared_seeds(dir: &Path) -> Vec<Seed> {
    let read = |p: &str| std::fs::read_to_string(dir.join(p)).ok();
    let mut seeds = Vec::new();
    if let (Some(obj), Some(mtl)) =
        (read("scenes/cornell-box/CornellBox-Original.obj"), read("scenes/cornell-box/CornellBox-Original.mtl"))
    {
        seeds.push(Seed { name: "cornell".into(), obj, mtl_name: "CornellBox-Original.mtl".into(), mtl });
    }
    if let (Some(obj), Some(mtl)) = (read("scenes/sponza/sponza.obj"), read("scenes/sponza/sponza.mtl")) {
        // The first group only (Sponza's groups number their vertices globally).
        let first_group: String = obj.split("\ng ").take(2).collect::<Vec<_>>().join("\ng ");
        seeds.push(Seed {
            name: "sponza-excerpt".into(),
            obj: excerpt(&first_group, 60),
            mtl_name: "sponza.mtl".into(),
            mtl,
        });
    }
    if let Some(obj) = read("scenes/bunny/bunny_res4.obj") {
        seeds.push(Seed {
            name: "bunny-excerpt".into(),
            obj: excerpt(&obj, 120),
            mtl_name: String::new(),
            mtl: String::new(),
        });
    }
    seeds
}

fn default_shared_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared")
}

// ---------------------------------------------------------------------------------------
// Mutations
// ---------------------------------------------------------------------------------------

const OBJ_KEYS: &[&str] = &["v", "vn", "vt", "vp", "f", "l", "p", "o", "g", "s", "usemtl", "mtllib", "#", "cstype"];
const MTL_KEYS: &[&str] = &[
    "newmtl",
    "Ka",
    "Kd",
    "Ks",
    "Ke",
    "Tf",
    "Ns",
    "Ni",
    "d",
    "Tr",
    "illum",
    "map_Kd",
    "map_Ka",
    "map_bump",
    "bump",
    "bsdf",
    "rough",
    "p",
    "nu",
    "nv",
    "Rs",
    "Rd",
    "sigma",
    "dispersion",
    "absorption",
    "cauchy_b",
];
const COLOUR_KEYS: &[&str] = &["Ka", "Kd", "Ks", "Ke", "Tf", "Rs", "Rd", "absorption"];
const BSDF_NAMES: &[&str] = &[
    "lambert",
    "orennayar",
    "mirror",
    "dielectric",
    "conductor",
    "roughconductor",
    "roughdielectric",
    "schlick",
    "ashikhmin",
    "LAMBERT",
    "velvet",
    "",
];
/// Numbers at and beyond every edge a parser might mishandle.
const EXTREME_NUMBERS: &[&str] = &[
    "1e39",
    "-1e39",
    "3.4028235e38",
    "1e-45",
    "1e-400",
    "-0",
    "0",
    "-0.0",
    "nan",
    "NaN",
    "-nan",
    "inf",
    "-inf",
    "infinity",
    "2147483647",
    "2147483648",
    "-2147483648",
    "-2147483649",
    "4294967295",
    "4294967296",
    "9223372036854775807",
    "9223372036854775808",
    "-9223372036854775808",
    "-9223372036854775809",
    "18446744073709551615",
    "18446744073709551616",
    "1",
    "-1",
    "0.5",
    "1.5",
    "10",
    "11",
    "255",
    "256",
    "",
    "0x10",
    "1e",
    ".",
    "-",
    "+1",
    "1,5",
    "1..2",
    "١",
];
/// Face corners: valid forms, missing parts, zero, negative and huge indices.
const CORNERS: &[&str] = &[
    "1",
    "2",
    "3",
    "-1",
    "-2",
    "-3",
    "0",
    "-0",
    "1/1",
    "1//1",
    "1/1/1",
    "1/",
    "1//",
    "/1",
    "//",
    "/",
    "1/1/1/1",
    "1/-1",
    "1/-99",
    "1//-99",
    "-99",
    "1/-1/-99",
    "1//-1",
    "-1/-1/-1",
    "4294967296",
    "-4294967296",
    "9223372036854775807",
    "-9223372036854775808",
    "2147483648",
    "1/2147483648",
    "1//9223372036854775807",
    "+1",
    "1.5",
    "x",
    "#",
    "1#",
];
const BYTES: &[u8] = b" \n\t\r\x0b\x0c/-+.#eE0123456789xX\0\xff\xc3\xa9";

fn tokens(line: &str) -> Vec<&str> {
    line.split_whitespace().collect()
}

fn join_tokens(t: &[&str]) -> String {
    t.join(" ")
}

/// A random statement for an OBJ or an MTL file.
fn random_line(r: &mut SplitMix64) -> String {
    let key = if r.one_in(2) { *r.pick(OBJ_KEYS) } else { *r.pick(MTL_KEYS) };
    let n = r.below(8);
    let mut parts = vec![key.to_string()];
    for _ in 0..n {
        parts.push(match r.below(4) {
            0 => r.pick(EXTREME_NUMBERS).to_string(),
            1 => r.pick(CORNERS).to_string(),
            2 => r.pick(BSDF_NAMES).to_string(),
            _ => format!("{}", (r.next() % 2000) as f64 / 1000.0 - 0.5),
        });
    }
    parts.join(" ")
}

/// Applies one random mutation to `text`; `other` is another seed file to splice from.
fn mutate(r: &mut SplitMix64, text: &str, other: &str) -> String {
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let n = lines.len();
    let at = r.below(n + 1);
    let line_at = |r: &mut SplitMix64| if n == 0 { None } else { Some(r.below(n)) };
    match r.below(17) {
        // Byte-level damage: flip a bit, or set a byte that means something to a parser.
        0 | 1 => {
            let mut bytes = text.as_bytes().to_vec();
            if !bytes.is_empty() {
                let i = r.below(bytes.len());
                if r.one_in(2) {
                    bytes[i] ^= 1 << r.below(8);
                } else {
                    bytes[i] = *r.pick(BYTES);
                }
            }
            return String::from_utf8_lossy(&bytes).into_owned();
        }
        // Truncate anywhere (on a character boundary).
        2 => {
            let mut cut = r.below(text.len() + 1);
            while !text.is_char_boundary(cut) {
                cut -= 1;
            }
            return text[..cut].to_string();
        }
        3 => lines.insert(at, random_line(r)),
        4 => {
            if let Some(i) = line_at(r) {
                lines.remove(i);
            }
        }
        // Duplicate a line: once, a few times, or a thousand times (amplification).
        5 => {
            if let Some(i) = line_at(r) {
                let times = *r.pick(&[1, 1, 2, 10, 1000]);
                let copy = lines[i].clone();
                for _ in 0..times {
                    lines.insert(i, copy.clone());
                }
            }
        }
        6 => {
            if let (Some(i), Some(j)) = (line_at(r), line_at(r)) {
                lines.swap(i, j);
            }
        }
        // Token-level edits within a line.
        7 => {
            if let Some(i) = line_at(r) {
                let line = lines[i].clone();
                let mut t = tokens(&line);
                if !t.is_empty() {
                    let k = r.below(t.len());
                    match r.below(3) {
                        0 => {
                            t.remove(k);
                        }
                        1 => {
                            let copy = t[k];
                            let times = *r.pick(&[1, 2, 5]);
                            for _ in 0..times {
                                t.insert(k, copy);
                            }
                        }
                        _ => t.insert(k, if r.one_in(2) { *r.pick(EXTREME_NUMBERS) } else { *r.pick(CORNERS) }),
                    }
                    lines[i] = join_tokens(&t);
                }
            }
        }
        // A number replaced by an extreme one.
        8 | 9 => {
            if let Some(i) = line_at(r) {
                let line = lines[i].clone();
                let mut t = tokens(&line);
                let numeric: Vec<usize> =
                    (1..t.len()).filter(|&k| t[k].starts_with(|c: char| c.is_ascii_digit() || c == '-')).collect();
                if !numeric.is_empty() {
                    let k = *r.pick(&numeric);
                    t[k] = *r.pick(EXTREME_NUMBERS);
                    lines[i] = join_tokens(&t);
                }
            }
        }
        // Face corners replaced by odd or out-of-range ones.
        10 => {
            if let Some(i) = line_at(r) {
                let line = lines[i].clone();
                let mut t = tokens(&line);
                if t.len() > 1 {
                    let k = 1 + r.below(t.len() - 1);
                    t[k] = *r.pick(CORNERS);
                    lines[i] = join_tokens(&t);
                }
            }
        }
        // A face with very many corners, all valid or not.
        11 => {
            let corners = *r.pick(&[1usize, 2, 4, 7, 100, 10_000, 100_000]);
            let corner = if r.one_in(2) { "1" } else { r.pick(CORNERS) };
            let mut line = String::from("f");
            for _ in 0..corners {
                line.push(' ');
                line.push_str(corner);
            }
            lines.insert(at, line);
        }
        // Lines from another seed file (OBJ into MTL and back).
        12 => {
            let other: Vec<&str> = other.lines().collect();
            if !other.is_empty() {
                let start = r.below(other.len());
                let len = 1 + r.below(20.min(other.len() - start));
                for (k, l) in other[start..start + len].iter().enumerate() {
                    lines.insert((at + k).min(lines.len()), l.to_string());
                }
            }
        }
        // Colour statements with no, one, two, three or four values.
        13 => {
            let colours: Vec<usize> = (0..n)
                .filter(|&i| lines[i].split_whitespace().next().is_some_and(|k| COLOUR_KEYS.contains(&k)))
                .collect();
            if !colours.is_empty() {
                let i = *r.pick(&colours);
                let line = lines[i].clone();
                let t = tokens(&line);
                let value = t.get(1).copied().unwrap_or("0.5");
                let count = *r.pick(&[0usize, 1, 1, 2, 3, 4]);
                lines[i] = std::iter::once(t[0]).chain(std::iter::repeat_n(value, count)).collect::<Vec<_>>().join(" ");
            }
        }
        // A statement's values removed entirely.
        14 => {
            if let Some(i) = line_at(r) {
                lines[i] = lines[i].split_whitespace().next().unwrap_or("").to_string();
            }
        }
        // A statement's keyword replaced by another (an OBJ key in an MTL and so on).
        15 => {
            if let Some(i) = line_at(r) {
                let line = lines[i].clone();
                let mut t = tokens(&line);
                if !t.is_empty() {
                    t[0] = if r.one_in(2) { *r.pick(OBJ_KEYS) } else { *r.pick(MTL_KEYS) };
                    lines[i] = join_tokens(&t);
                }
            }
        }
        // `bsdf` statements with every name.
        _ => lines.insert(at, format!("bsdf {}", r.pick(BSDF_NAMES))),
    }
    let mut out = lines.join("\n");
    if !r.one_in(8) {
        out.push('\n');
    }
    out
}

/// The largest file a mutation may make: stacked duplications would otherwise grow
/// inputs to hundreds of megabytes, which tests nothing new and slows the run.
const MAX_FILE: usize = 1 << 20;

/// Input `index`: a seed, then one to eight mutations of its OBJ, its MTL or both.
fn make_input(seeds: &[Seed], seed: u64, index: u64) -> Seed {
    let mut r = input_rng(seed, index);
    let mut input = r.pick(seeds).clone();
    let rounds = 1 + r.below(8);
    for _ in 0..rounds {
        let donor = r.pick(seeds);
        let donor_text = if r.one_in(2) { &donor.obj } else { &donor.mtl };
        let target = if input.mtl_name.is_empty() || r.one_in(2) { &mut input.obj } else { &mut input.mtl };
        let mutated = mutate(&mut r, target, donor_text);
        if mutated.len() <= MAX_FILE {
            *target = mutated;
        }
    }
    input
}

// ---------------------------------------------------------------------------------------
// Running
// ---------------------------------------------------------------------------------------

/// How one input went.
enum Outcome {
    Loaded,
    Failed(String),
    Panicked,
}

static PANICS: AtomicU64 = AtomicU64::new(0);
static PANIC_NOTES: Mutex<Vec<String>> = Mutex::new(Vec::new());
/// Panics counted by where they happened (`file:line`).
static PANIC_SITES: Mutex<Vec<(String, u64)>> = Mutex::new(Vec::new());
/// The input being run, for the panic hook's notes.
static CURRENT_INPUT: AtomicU64 = AtomicU64::new(0);

/// Counts every panic, caught or not, anywhere in the loader (a panic contained inside
/// the loader would otherwise look like an ordinary error), and notes the first few.
fn install_panic_counter() {
    std::panic::set_hook(Box::new(|info| {
        PANICS.fetch_add(1, Ordering::Relaxed);
        let site = info.location().map(|l| format!("{}:{}", l.file(), l.line())).unwrap_or_default();
        if let Ok(mut sites) = PANIC_SITES.lock() {
            match sites.iter_mut().find(|(s, _)| *s == site) {
                Some((_, n)) => *n += 1,
                None => sites.push((site, 1)),
            }
        }
        if let Ok(mut notes) = PANIC_NOTES.lock()
            && notes.len() < 20
        {
            notes.push(format!("input {}: {info}", CURRENT_INPUT.load(Ordering::Relaxed)));
        }
    }));
}

/// A 2×2 RGBA PNG, encoded once.
fn tiny_png() -> &'static [u8] {
    static PNG: std::sync::OnceLock<Vec<u8>> = std::sync::OnceLock::new();
    PNG.get_or_init(|| {
        let mut bytes = Vec::new();
        image::RgbaImage::from_fn(2, 2, |x, y| image::Rgba([x as u8 * 200, y as u8 * 200, 90, 255]))
            .write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png)
            .expect("a PNG in memory");
        bytes
    })
}

/// Loads one input from memory, as `spt render` would from disk.
fn run_one(input: &Seed) -> Outcome {
    let obj_path = Path::new("fuzz").join(format!("{}.obj", input.name));
    let read_mtl = |p: &Path| -> std::io::Result<String> {
        if !input.mtl_name.is_empty() && p.file_name().is_some_and(|f| f == input.mtl_name.as_str()) {
            Ok(input.mtl.clone())
        } else {
            Err(std::io::Error::new(std::io::ErrorKind::NotFound, "no such file"))
        }
    };
    // Every texture the MTL names is a small PNG in memory (the images' own decoding is
    // fuzzed by `fuzz_scenes`); names ending otherwise are missing files.
    let read_image = |p: &Path| -> std::io::Result<Vec<u8>> {
        let name = p.to_string_lossy().to_ascii_lowercase();
        if [".jpg", ".png", ".tga", ".bmp"].iter().any(|e| name.ends_with(e)) {
            Ok(tiny_png().to_vec())
        } else {
            Err(std::io::Error::new(std::io::ErrorKind::NotFound, "no such file"))
        }
    };
    let before = PANICS.load(Ordering::Relaxed);
    let result = catch_unwind(AssertUnwindSafe(|| {
        tracer::obj::load_obj_text_with(&input.obj, &obj_path, &read_mtl, &read_image)
    }));
    match result {
        _ if PANICS.load(Ordering::Relaxed) != before => Outcome::Panicked,
        Ok(Ok(_)) => Outcome::Loaded,
        Ok(Err(e)) => Outcome::Failed(e.to_string()),
        Err(_) => Outcome::Panicked,
    }
}

/// What a run found.
#[derive(Default)]
struct Stats {
    inputs: u64,
    loaded: u64,
    failed: u64,
    panicked: u64,
    panicked_inputs: Vec<u64>,
    max_time: (Duration, u64),
    total_time: Duration,
    /// Bytes allocated at the peak of one input, beyond what was live before it.
    max_peak: (usize, u64, usize),
    /// The largest peak per byte of input (plus 4 KiB for the fixed costs of any load),
    /// and the input.
    max_ratio: (f64, u64, usize),
    error_kinds: HashMap<String, u64>,
    /// Errors whose message names no line (`file.obj:LINE:`).
    unlocated: u64,
}

/// True if an error message names a line: `PATH:LINE: …` (the path may end in
/// anything, `one.mtl/` say, so only the line number is looked for).
fn has_line(message: &str) -> bool {
    let head = message.split(": ").next().unwrap_or("");
    head.rsplit_once(':').is_some_and(|(_, n)| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()))
}

/// An error message with its file, numbers and quoted text blanked, so that messages of
/// one kind count together.
fn error_kind(message: &str) -> String {
    let message = message.split_once(".obj").or_else(|| message.split_once(".mtl")).map_or(message, |(_, m)| m);
    let mut out = String::new();
    let mut quoted = false;
    for c in message.chars() {
        if c == '\'' {
            quoted = !quoted;
            out.push_str(if quoted { "'…" } else { "'" });
        } else if !quoted && !c.is_ascii_digit() {
            out.push(c);
        }
    }
    out.chars().take(90).collect()
}

fn run(seeds: &[Seed], seed: u64, range: std::ops::Range<u64>, dump: Option<&Path>, verbose: bool) -> Stats {
    let mut stats = Stats::default();
    let progress_every = ((range.end - range.start) / 20).max(1);
    let started = Instant::now();
    for index in range.clone() {
        let input = make_input(seeds, seed, index);
        let size = input.obj.len() + input.mtl.len();
        CURRENT_INPUT.store(index, Ordering::Relaxed);
        let base = LIVE.load(Ordering::Relaxed);
        PEAK.store(base, Ordering::Relaxed);
        let t0 = Instant::now();
        let outcome = run_one(&input);
        let dt = t0.elapsed();
        let peak = PEAK.load(Ordering::Relaxed).saturating_sub(base);
        stats.inputs += 1;
        stats.total_time += dt;
        if dt > stats.max_time.0 {
            stats.max_time = (dt, index);
        }
        if peak > stats.max_peak.0 {
            stats.max_peak = (peak, index, size);
        }
        let ratio = peak as f64 / (size + 4096) as f64;
        if ratio > stats.max_ratio.0 {
            stats.max_ratio = (ratio, index, size);
        }
        match outcome {
            Outcome::Loaded => stats.loaded += 1,
            Outcome::Failed(message) => {
                stats.failed += 1;
                let mut kind = error_kind(&message);
                if !has_line(&message) {
                    stats.unlocated += 1;
                    kind.insert_str(0, "(no line) ");
                }
                *stats.error_kinds.entry(kind).or_default() += 1;
            }
            Outcome::Panicked => {
                stats.panicked += 1;
                if stats.panicked_inputs.len() < 100 {
                    stats.panicked_inputs.push(index);
                }
                if let Some(dir) = dump {
                    let _ = std::fs::create_dir_all(dir);
                    let _ = std::fs::write(dir.join(format!("{index}.obj")), &input.obj);
                    let _ = std::fs::write(dir.join(format!("{index}.mtl")), &input.mtl);
                }
            }
        }
        if verbose && (index - range.start + 1).is_multiple_of(progress_every) {
            eprintln!(
                "{} inputs, {} panics, {:.0} s",
                index - range.start + 1,
                stats.panicked,
                started.elapsed().as_secs_f64()
            );
        }
    }
    stats
}

fn report(stats: &Stats, seeds: &[Seed], seed: u64) {
    println!("seeds: {}", seeds.iter().map(|s| s.name.as_str()).collect::<Vec<_>>().join(", "));
    println!("seed {seed}: {} inputs", stats.inputs);
    println!("  panics:    {}", stats.panicked);
    println!("  errors:    {} ({} without a line number)", stats.failed, stats.unlocated);
    println!("  successes: {}", stats.loaded);
    println!(
        "  time per input: max {:.3} ms (input {}), mean {:.1} µs",
        stats.max_time.0.as_secs_f64() * 1e3,
        stats.max_time.1,
        stats.total_time.as_secs_f64() * 1e6 / stats.inputs.max(1) as f64
    );
    println!(
        "  peak allocation per input: max {} bytes (input {}, {} bytes of input)",
        stats.max_peak.0, stats.max_peak.1, stats.max_peak.2
    );
    println!(
        "  peak allocation per byte of input (+4 KiB): max {:.1} (input {}, {} bytes of input)",
        stats.max_ratio.0, stats.max_ratio.1, stats.max_ratio.2
    );
    if !stats.panicked_inputs.is_empty() {
        println!("  panicking inputs (first 100): {:?}", stats.panicked_inputs);
        println!("  panics by site:");
        for (site, n) in PANIC_SITES.lock().map(|s| s.clone()).unwrap_or_default() {
            println!("    {n:>9}  {site}");
        }
        for note in PANIC_NOTES.lock().map(|n| n.clone()).unwrap_or_default() {
            println!("  {note}");
        }
    }
    let mut kinds: Vec<_> = stats.error_kinds.iter().collect();
    kinds.sort_by(|a, b| b.1.cmp(a.1).then(a.0.cmp(b.0)));
    println!("  most common errors, and every kind without a line number:");
    for (i, (kind, count)) in kinds.iter().enumerate() {
        if i < 25 || kind.starts_with("(no line)") {
            println!("    {count:>9}  {kind}");
        }
    }
}

#[cfg_attr(test, allow(dead_code))]
fn main() {
    let mut inputs = 100_000u64;
    let mut seed = 1u64;
    let mut shared = default_shared_dir();
    let mut replay = None;
    let mut dump = None;
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        let mut value = || args.next().unwrap_or_else(|| usage(&format!("{arg} needs a value")));
        match arg.as_str() {
            "--inputs" => inputs = value().parse().unwrap_or_else(|_| usage("--inputs: not a count")),
            "--seed" => seed = value().parse().unwrap_or_else(|_| usage("--seed: not a number")),
            "--shared" => shared = value().into(),
            "--replay" => replay = Some(value().parse().unwrap_or_else(|_| usage("--replay: not an index"))),
            "--dump" => dump = Some(PathBuf::from(value())),
            _ => usage(&format!("unknown argument '{arg}'")),
        }
    }
    let mut seeds = shared_seeds(&shared);
    if seeds.is_empty() {
        eprintln!("note: no shared scenes under {}; hand-written seeds only", shared.display());
    }
    seeds.extend(builtin_seeds());
    if let Some(index) = replay {
        let input = make_input(&seeds, seed, index);
        println!("== input {index} (seed {}): {}.obj\n{}", input.name, input.name, input.obj);
        println!("== {}\n{}", input.mtl_name, input.mtl);
        match run_one(&input) {
            Outcome::Loaded => println!("== loaded"),
            Outcome::Failed(e) => println!("== error: {e}"),
            Outcome::Panicked => println!("== PANICKED"),
        }
        return;
    }
    install_panic_counter();
    let stats = run(&seeds, seed, 0..inputs, dump.as_deref(), true);
    report(&stats, &seeds, seed);
    if stats.panicked > 0 {
        std::process::exit(1);
    }
}

fn usage(problem: &str) -> ! {
    eprintln!("fuzz_obj: {problem}\nusage: fuzz_obj [--inputs N] [--seed S] [--shared DIR] [--replay K] [--dump DIR]");
    std::process::exit(2)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The short run CI executes: every seed loads, and 20,000 mutated inputs load or
    /// fail with an error naming file and line; none panics or allocates out of
    /// proportion to its size.
    #[test]
    fn twenty_thousand_mutations_do_not_panic() {
        assert!(has_line("fuzz/one.mtl/:2: Ns needs 1 number, got 2") && has_line("a.obj:12: face: …"));
        assert!(!has_line("a.obj: cannot read") && !has_line("material 'a:1': x"));
        let mut seeds = shared_seeds(&default_shared_dir());
        seeds.extend(builtin_seeds());
        for seed in &seeds {
            match run_one(seed) {
                Outcome::Loaded => {}
                Outcome::Failed(e) => panic!("seed {} does not load: {e}", seed.name),
                Outcome::Panicked => panic!("seed {} panics", seed.name),
            }
        }
        install_panic_counter();
        let stats = run(&seeds, 20260101, 0..20_000, None, false);
        report(&stats, &seeds, 20260101);
        assert_eq!(stats.panicked, 0, "panicking inputs: {:?}", stats.panicked_inputs);
        assert!(stats.loaded > 1000 && stats.failed > 1000, "{} loaded, {} failed", stats.loaded, stats.failed);
        assert_eq!(stats.unlocated, 0, "every error names its file and line");
        // Allocation proportional to the input (about 60 bytes per byte at most now).
        assert!(
            stats.max_ratio.0 < 256.0,
            "input {} allocates {:.0} bytes per byte",
            stats.max_ratio.1,
            stats.max_ratio.0
        );
    }
}
