//! `spt compare`: render a scene under several configurations at growing sample counts,
//! measure each image's error against a reference, and chart error against time.

use crate::{
    SceneArgs, best_sampler, parse_bvh_builder, parse_bvh_width, parse_sampler, parse_shading_normals,
    parse_triangle_test, prepare,
};
use anyhow::{Context, Result, anyhow, bail};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use plotters::prelude::*;
use serde::Deserialize;
use spectral::SpectralMode;
use std::path::{Path, PathBuf};
use tracer::output::{read_rgb32f, write_image};

/// `spt compare`'s arguments.
#[derive(Args)]
pub struct CompareArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// The configurations: a preset (spectral, samplers, integrators, triangle-tests,
    /// bvh-widths, bvh-builders, shading-normals, light-samplers) or a JSON file: a list
    /// of objects with "name" and any of "integrator", "spectral", "sampler",
    /// "triangle_test", "bvh_width", "bvh_builder", "shading_normals", "light_sampler",
    /// "backend", "max_depth", "rr_scale" and "set" (a
    /// list of KEY=VALUE changes to a .toml scene, e.g. a material's parameter: BSDF
    /// variants); unset fields take the command line's values.
    #[arg(long, default_value = "samplers")]
    configs: String,
    /// The reference image (linear EXR of the same size), e.g. a Mitsuba render.
    #[arg(long, conflicts_with = "reference_spp")]
    reference: Option<PathBuf>,
    /// Without --reference: render one with the path tracer (hero, zsobol, another seed)
    /// at this many samples per pixel (written to DIR/reference.exr and reused if it is
    /// there).
    #[arg(long, default_value_t = 1024)]
    reference_spp: u32,
    /// The largest sample count; each configuration renders at 1, 2, 4, … up to it.
    #[arg(long, default_value_t = 64)]
    spp_max: u32,
    /// A time budget instead: each configuration doubles its sample count until a render
    /// takes at least this many seconds (or reaches --spp-max).
    #[arg(long)]
    time_max: Option<f64>,
    /// Chart and rate each render by its preparation (BVH build, atlas, kernel compile)
    /// plus its sampling time, not its sampling time alone: what a builder or an
    /// integrator's precomputation costs end to end.
    #[arg(long)]
    end_to_end: bool,
    /// Directory for compare.csv, compare.png and compare.svg.
    #[arg(short, long, default_value = "compare")]
    output: PathBuf,
}

/// One configuration: a name and the settings it changes.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Config {
    name: String,
    integrator: Option<String>,
    spectral: Option<String>,
    sampler: Option<String>,
    triangle_test: Option<String>,
    bvh_width: Option<String>,
    bvh_builder: Option<String>,
    shading_normals: Option<String>,
    light_sampler: Option<String>,
    backend: Option<String>,
    max_depth: Option<u32>,
    rr_scale: Option<f32>,
    #[serde(default)]
    set: Vec<String>,
}

impl Config {
    fn named(name: &str) -> Self {
        Self { name: name.into(), ..Default::default() }
    }

    /// The scene arguments and spectral mode of this configuration over `base`.
    fn apply(&self, base: &SceneArgs, mode: SpectralMode) -> Result<(SceneArgs, SpectralMode)> {
        let mut args = base.clone();
        let named = |what: &str, e: String| anyhow!("configuration '{}': {what}: {e}", self.name);
        let one_of = |what: &str, value: &String, known: &[&str]| {
            if known.contains(&value.as_str()) {
                Ok(value.clone())
            } else {
                Err(named(what, format!("unknown '{value}' (known: {})", known.join(", "))))
            }
        };
        if let Some(i) = &self.integrator {
            args.integrator = one_of("integrator", i, &crate::INTEGRATORS)?;
        }
        if let Some(b) = &self.backend {
            args.backend = one_of("backend", b, &crate::BACKENDS)?;
        }
        if let Some(s) = &self.sampler {
            args.sampler = Some(parse_sampler(s).map_err(|e| named("sampler", e))?);
        }
        if let Some(t) = &self.triangle_test {
            args.triangle_test = parse_triangle_test(t).map_err(|e| named("triangle_test", e))?;
        }
        if let Some(w) = &self.bvh_width {
            args.bvh_width = parse_bvh_width(w).map_err(|e| named("bvh_width", e))?;
        }
        if let Some(b) = &self.bvh_builder {
            args.bvh_builder = Some(parse_bvh_builder(b).map_err(|e| named("bvh_builder", e))?);
        }
        if let Some(n) = &self.shading_normals {
            args.shading_normals = parse_shading_normals(n).map_err(|e| named("shading_normals", e))?;
        }
        if let Some(l) = &self.light_sampler {
            args.light_sampler = crate::parse_light_sampler(l).map_err(|e| named("light_sampler", e))?;
        }
        if let Some(d) = self.max_depth {
            args.max_depth = d;
        }
        if let Some(s) = self.rr_scale {
            args.rr_scale = s;
        }
        args.sets.extend(self.set.iter().cloned());
        let mode = match &self.spectral {
            Some(m) => m.parse().map_err(|e: String| named("spectral", e))?,
            None => mode,
        };
        Ok((args, mode))
    }
}

/// The configurations of a preset, or `None` for an unknown name.
pub fn preset(name: &str) -> Option<Vec<Config>> {
    let each = |field: fn(&mut Config) -> &mut Option<String>, values: &[&str]| {
        values
            .iter()
            .map(|v| {
                let mut c = Config::named(v);
                *field(&mut c) = Some(v.to_string());
                c
            })
            .collect()
    };
    Some(match name {
        "spectral" => each(|c| &mut c.spectral, &["hero", "bins40", "rgb"]),
        "samplers" => each(|c| &mut c.sampler, &["zsobol", "sobol", "independent"]),
        "integrators" => each(|c| &mut c.integrator, &["path", "path-caustics", "bdpt", "atlas", "direct", "whitted"]),
        "triangle-tests" => each(|c| &mut c.triangle_test, &["watertight", "moller-trumbore"]),
        "bvh-widths" => each(|c| &mut c.bvh_width, &["4", "8"]),
        "bvh-builders" => each(|c| &mut c.bvh_builder, &["binned_sah", "sweep_sah", "midpoint", "hybrid"]),
        "shading-normals" => each(|c| &mut c.shading_normals, &["adapted", "face-forward", "geometric"]),
        "light-samplers" => each(|c| &mut c.light_sampler, &["power", "tree"]),
        _ => return None,
    })
}

const PRESETS: &str =
    "spectral, samplers, integrators, triangle-tests, bvh-widths, bvh-builders, shading-normals, light-samplers";

fn configs(spec: &str) -> Result<Vec<Config>> {
    if let Some(c) = preset(spec) {
        return Ok(c);
    }
    let path = Path::new(spec);
    if !path.exists() {
        bail!("--configs '{spec}' is neither a preset ({PRESETS}) nor a file");
    }
    let text = std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let list: Vec<Config> =
        serde_json::from_str(&text).map_err(|e| anyhow!("{}:{}:{}: {e}", path.display(), e.line(), e.column()))?;
    if list.is_empty() {
        bail!("{}: no configurations", path.display());
    }
    Ok(list)
}

/// One measured render.
#[derive(Clone, Debug, PartialEq)]
pub struct Measurement {
    /// The configuration's name.
    pub config: String,
    /// Samples per pixel.
    pub spp: u32,
    /// Seconds of sampling.
    pub render_s: f64,
    /// Seconds preparing the scene (BVH build, kernel compile), once per configuration.
    pub prepare_s: f64,
    /// relMSE against the reference.
    pub rel_mse: f64,
    /// SSIM of the sRGB-encoded luminance against the reference's.
    pub ssim: f64,
    /// Mean ꟻLIP error of the sRGB-encoded image against the reference's (0 = the same).
    pub flip: f64,
}

impl Measurement {
    /// The seconds a render is rated by: sampling alone, or with the configuration's
    /// preparation (`--end-to-end`).
    fn seconds(&self, end_to_end: bool) -> f64 {
        if end_to_end { self.render_s + self.prepare_s } else { self.render_s }
    }
}

/// Added to the seed of a reference `spt compare` renders itself.
const REFERENCE_SEED_OFFSET: u64 = 0x005e_ed0f_7e7e;

/// `spt compare`.
pub fn run(args: CompareArgs) -> Result<()> {
    if args.spp_max == 0 {
        bail!("--spp-max must be at least 1");
    }
    let configs = configs(&args.configs)?;
    std::fs::create_dir_all(&args.output).with_context(|| format!("creating {}", args.output.display()))?;
    let (w, h) = (args.scene.width, args.scene.height);
    let reference = match &args.reference {
        Some(p) => p.clone(),
        None => args.output.join("reference.exr"),
    };
    if args.reference.is_none() && !reference.exists() {
        eprintln!("rendering the reference: path tracer, hero, zsobol, {} spp, another seed", args.reference_spp);
        let mut base = args.scene.clone();
        base.integrator = "path".into();
        base.sampler = None;
        // Its own seed: with the renders' seed its first samples would be theirs, and a
        // render at the reference's sample count would measure no error at all.
        base.seed = base.seed.wrapping_add(REFERENCE_SEED_OFFSET);
        let (prepared, settings) = prepare(&base, args.reference_spp, SpectralMode::Hero, best_sampler)?;
        let (film, _) = tracer::render(prepared.as_ref(), &settings, &|_| {})?;
        write_image(&reference, w, h, &film.mean_rgb())?;
    }
    let (rw, rh, reference_rgb) = read_rgb32f(&reference)?;
    if (rw, rh) != (w, h) {
        bail!("{}: the reference is {rw}×{rh}, the renders {w}×{h}", reference.display());
    }
    if let Some(t) = args.time_max
        && !(t > 0.0 && t.is_finite())
    {
        bail!("--time-max {t} must be a positive number of seconds");
    }
    let budgets: Vec<u32> =
        std::iter::successors(Some(1u32), |&n| (n < args.spp_max).then(|| (2 * n).min(args.spp_max))).collect();
    // With a time budget the bar counts the sample-count budgets (its end is unknown).
    let total: u64 = configs.len() as u64 * budgets.iter().map(|&n| n as u64).sum::<u64>() * w as u64 * h as u64;
    let bar = ProgressBar::new(total)
        .with_style(ProgressStyle::with_template("{bar:40} {percent:>3}% {msg} ETA {eta}").expect("static template"));
    let mut rows = Vec::new();
    let crop = Crop::centred(w, h);
    for config in &configs {
        let mut strip = Vec::new();
        let (scene_args, mode) = config.apply(&args.scene, SpectralMode::Hero)?;
        // The integrators preset on the GPU: the one integrator it lacks is left out (a
        // configuration file that asks for it is refused, as `spt render` refuses it).
        if args.configs == "integrators" && scene_args.backend == "gpu" && scene_args.integrator == "path-caustics" {
            eprintln!("configuration 'path-caustics' left out: the GPU backend has no such integrator");
            continue;
        }
        let (prepared, base) = prepare(&scene_args, args.spp_max, mode, best_sampler)
            .with_context(|| format!("configuration '{}'", config.name))?;
        let prepare_s = prepared.stats().total.as_secs_f64();
        for (k, &spp) in budgets.iter().enumerate() {
            bar.set_message(format!("{} at {spp} spp", config.name));
            let settings = tracer::RenderSettings { spp, ..base.clone() };
            let (film, stats) = tracer::render(prepared.as_ref(), &settings, &|n| bar.inc(n))?;
            let rgb = film.mean_rgb();
            strip.push(crop.cut(&rgb, w));
            let out_of_time = args.time_max.is_some_and(|t| stats.wall.as_secs_f64() >= t);
            if k + 1 == budgets.len() || out_of_time {
                let heat = heat_map(&rgb, &reference_rgb);
                let path = args.output.join(format!("heat-{}.png", file_name(&config.name)));
                image::save_buffer(&path, &heat, w, h, image::ColorType::Rgb8)
                    .with_context(|| format!("writing {}", path.display()))?;
            }
            rows.push(Measurement {
                config: config.name.clone(),
                spp,
                render_s: stats.wall.as_secs_f64(),
                prepare_s,
                rel_mse: rel_mse(&rgb, &reference_rgb),
                ssim: ssim(&luminance_srgb(&rgb), &luminance_srgb(&reference_rgb), w as usize, h as usize),
                flip: flip(&rgb, &reference_rgb, w, h),
            });
            if out_of_time {
                break;
            }
        }
        strip.push(crop.cut(&reference_rgb, w));
        let path = args.output.join(format!("strip-{}.png", file_name(&config.name)));
        crop.write_strip(&path, &strip)?;
    }
    bar.finish_and_clear();
    let csv_path = args.output.join("compare.csv");
    std::fs::write(&csv_path, csv(&rows, args.end_to_end))
        .with_context(|| format!("writing {}", csv_path.display()))?;
    let title = format!("{} — relMSE against {}", args.scene.scene.display(), reference.display());
    // Both backends lay text out with the registered font.
    if crate::stability::load_font() {
        chart(&args.output.join("compare.svg"), &title, &rows, false, args.end_to_end)?;
        chart(&args.output.join("compare.png"), &title, &rows, true, args.end_to_end)?;
    }
    print!("{}", table(&rows, args.end_to_end));
    eprintln!("wrote {} and its charts", csv_path.display());
    Ok(())
}

/// The part of the image a convergence strip shows: a centred square of at most 128
/// pixels a side.
struct Crop {
    x: u32,
    y: u32,
    side: u32,
}

impl Crop {
    fn centred(width: u32, height: u32) -> Self {
        let side = width.min(height).min(128);
        Self { x: (width - side) / 2, y: (height - side) / 2, side }
    }

    /// The crop of a linear RGB image `width` wide, row-major RGB.
    fn cut(&self, rgb: &[f32], width: u32) -> Vec<f32> {
        (self.y..self.y + self.side)
            .flat_map(|y| {
                let start = 3 * (y * width + self.x) as usize;
                rgb[start..start + 3 * self.side as usize].iter().copied()
            })
            .collect()
    }

    /// The crops side by side, left to right (each budget, then the reference), sRGB.
    fn write_strip(&self, path: &Path, crops: &[Vec<f32>]) -> Result<()> {
        let side = self.side as usize;
        let width = side * crops.len();
        let mut pixels = vec![0u8; 3 * width * side];
        for (k, crop) in crops.iter().enumerate() {
            for y in 0..side {
                for x in 0..side {
                    for c in 0..3 {
                        pixels[3 * (y * width + k * side + x) + c] = spectral::srgb_to_u8(crop[3 * (y * side + x) + c]);
                    }
                }
            }
        }
        image::save_buffer(path, &pixels, width as u32, side as u32, image::ColorType::Rgb8)
            .with_context(|| format!("writing {}", path.display()))
    }
}

/// The per-pixel relative squared error (as [`rel_mse`], averaged over the channels) as
/// an 8-bit RGB heat map on a fixed logarithmic scale — 10⁻⁵ and below black, then dark
/// red, orange, yellow, 1 and above white — so that the maps of several configurations
/// compare by eye.
fn heat_map(image: &[f32], reference: &[f32]) -> Vec<u8> {
    image
        .chunks_exact(3)
        .zip(reference.chunks_exact(3))
        .flat_map(|(x, r)| {
            let e = rel_mse(x, r).max(1e-12);
            let t = ((e.log10() + 5.0) / 5.0).clamp(0.0, 1.0) as f32;
            // Black → red → yellow → white in three equal thirds of t.
            let ramp = |from: f32| ((3.0 * t - from).clamp(0.0, 1.0) * 255.0).round() as u8;
            [ramp(0.0), ramp(1.0), ramp(2.0)]
        })
        .collect()
}

/// A configuration's name as a file name: letters, digits and `-` only.
fn file_name(name: &str) -> String {
    name.chars().map(|c| if c.is_ascii_alphanumeric() { c } else { '-' }).collect()
}

/// Mean over pixel-channels of (x − r)² / (r² + 10⁻²): the relative MSE of
/// `bench/compare_error.py` (the 10⁻² keeps black pixels from dominating).
pub fn rel_mse(image: &[f32], reference: &[f32]) -> f64 {
    let sum: f64 = image
        .iter()
        .zip(reference)
        .map(|(&x, &r)| {
            let (x, r) = (x as f64, r as f64);
            (x - r).powi(2) / (r * r + 1e-2)
        })
        .sum();
    sum / image.len().max(1) as f64
}

/// The mean ꟻLIP error (Andersson, Nilsson, Akenine-Möller, Oskarsson, Åström &
/// Fairchild 2020, "FLIP: A Difference Evaluator for Alternating Images") of two linear
/// RGB images, as a viewer sees them: sRGB-encoded, clamped, at NVIDIA's default 67
/// pixels per degree (LDR-ꟻLIP, through the `nv-flip` bindings).
pub fn flip(image: &[f32], reference: &[f32], width: u32, height: u32) -> f64 {
    let encode = |rgb: &[f32]| -> Vec<u8> { rgb.iter().map(|&v| spectral::srgb_to_u8(v)).collect() };
    let test = nv_flip::FlipImageRgb8::with_data(width, height, &encode(image));
    let reference = nv_flip::FlipImageRgb8::with_data(width, height, &encode(reference));
    let error = nv_flip::flip(reference, test, nv_flip::DEFAULT_PIXELS_PER_DEGREE);
    nv_flip::FlipPool::from_image(&error).mean() as f64
}

/// Per pixel: the luminance of the sRGB-encoded, clamped colour (what a viewer sees).
fn luminance_srgb(rgb: &[f32]) -> Vec<f64> {
    rgb.chunks_exact(3)
        .map(|p| {
            let y = 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
            spectral::srgb_to_u8(y) as f64 / 255.0
        })
        .collect()
}

/// The structural similarity index (Wang, Bovik, Sheikh & Simoncelli 2004, eq. 13) of two
/// single-channel images in [0, 1]: local means, variances and covariance over an 11×11
/// Gaussian window (σ = 1.5, clipped at the borders and renormalised), C₁ = (0.01)²,
/// C₂ = (0.03)², averaged over every pixel.
pub fn ssim(a: &[f64], b: &[f64], width: usize, height: usize) -> f64 {
    const RADIUS: isize = 5;
    let kernel: Vec<f64> = (-RADIUS..=RADIUS).map(|i| (-(i * i) as f64 / (2.0 * 1.5 * 1.5)).exp()).collect();
    // Separable Gaussian blur with renormalisation at the borders.
    let blur = |img: &[f64]| -> Vec<f64> {
        let pass = |src: &[f64], horizontal: bool| -> Vec<f64> {
            let mut out = vec![0.0; src.len()];
            for y in 0..height {
                for x in 0..width {
                    let (mut sum, mut weight) = (0.0, 0.0);
                    for (k, w) in kernel.iter().enumerate() {
                        let d = k as isize - RADIUS;
                        let (sx, sy) =
                            if horizontal { (x as isize + d, y as isize) } else { (x as isize, y as isize + d) };
                        if sx >= 0 && sy >= 0 && (sx as usize) < width && (sy as usize) < height {
                            sum += w * src[sy as usize * width + sx as usize];
                            weight += w;
                        }
                    }
                    out[y * width + x] = sum / weight;
                }
            }
            out
        };
        pass(&pass(img, true), false)
    };
    let product = |p: &[f64], q: &[f64]| -> Vec<f64> { p.iter().zip(q).map(|(x, y)| x * y).collect() };
    let (ma, mb) = (blur(a), blur(b));
    let (saa, sbb, sab) = (blur(&product(a, a)), blur(&product(b, b)), blur(&product(a, b)));
    let (c1, c2) = (1e-4, 9e-4);
    let n = a.len().max(1) as f64;
    (0..a.len())
        .map(|i| {
            let (va, vb, cov) = (saa[i] - ma[i] * ma[i], sbb[i] - mb[i] * mb[i], sab[i] - ma[i] * mb[i]);
            ((2.0 * ma[i] * mb[i] + c1) * (2.0 * cov + c2)) / ((ma[i] * ma[i] + mb[i] * mb[i] + c1) * (va + vb + c2))
        })
        .sum::<f64>()
        / n
}

/// The configurations' names, in order of first appearance.
fn config_names(rows: &[Measurement]) -> Vec<&str> {
    let mut names: Vec<&str> = Vec::new();
    for r in rows {
        if !names.contains(&r.config.as_str()) {
            names.push(&r.config);
        }
    }
    names
}

fn csv(rows: &[Measurement], end_to_end: bool) -> String {
    let mut out = String::from("config,spp,render_s,prepare_s,rel_mse,ssim,flip,efficiency\n");
    for r in rows {
        let quoted = if r.config.contains([',', '"']) {
            format!("\"{}\"", r.config.replace('"', "\"\""))
        } else {
            r.config.clone()
        };
        out += &format!(
            "{quoted},{},{:.6},{:.6},{:.6e},{:.6},{:.6},{:.6e}\n",
            r.spp,
            r.render_s,
            r.prepare_s,
            r.rel_mse,
            r.ssim,
            r.flip,
            1.0 / (r.rel_mse * r.seconds(end_to_end)).max(1e-300)
        );
    }
    out
}

/// A table: per configuration, the largest budget's figures and its efficiency
/// 1 / (relMSE · seconds) relative to the first configuration's.
fn table(rows: &[Measurement], end_to_end: bool) -> String {
    let names = config_names(rows);
    let last = |name: &str| rows.iter().filter(|r| r.config == name).max_by_key(|r| r.spp);
    let efficiency = |r: &Measurement| 1.0 / (r.rel_mse * r.seconds(end_to_end)).max(1e-300);
    let first = names.first().and_then(|n| last(n)).map(efficiency).unwrap_or(1.0);
    let mut out = format!(
        "{:<20} {:>6} {:>10} {:>12} {:>8} {:>8} {:>12}\n",
        "config",
        "spp",
        if end_to_end { "total_s" } else { "render_s" },
        "relMSE",
        "SSIM",
        "FLIP",
        "efficiency"
    );
    for name in names {
        if let Some(r) = last(name) {
            out += &format!(
                "{:<20} {:>6} {:>10.3} {:>12.5e} {:>8.4} {:>8.4} {:>11.2}×\n",
                name,
                r.spp,
                r.seconds(end_to_end),
                r.rel_mse,
                r.ssim,
                r.flip,
                efficiency(r) / first
            );
        }
    }
    out
}

/// relMSE against render time, log–log, one line per configuration, with the 1/t slope
/// of an unbiased estimator through the first configuration's first point as a guide
/// (a biased method's line flattens away from it).
fn chart(path: &Path, title: &str, rows: &[Measurement], bitmap: bool, end_to_end: bool) -> Result<()> {
    if bitmap {
        let root = BitMapBackend::new(path, (1000, 680)).into_drawing_area();
        draw_chart(root, title, rows, end_to_end)
    } else {
        let root = SVGBackend::new(path, (1000, 680)).into_drawing_area();
        draw_chart(root, title, rows, end_to_end)
    }
}

fn draw_chart<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    title: &str,
    rows: &[Measurement],
    end_to_end: bool,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let err = |e: &dyn std::fmt::Display| anyhow!("drawing the chart: {e}");
    let points: Vec<(f64, f64)> =
        rows.iter().map(|r| (r.seconds(end_to_end).max(1e-6), r.rel_mse.max(1e-12))).collect();
    let (x0, x1) = points.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), p| (lo.min(p.0), hi.max(p.0)));
    let (y0, y1) = points.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), p| (lo.min(p.1), hi.max(p.1)));
    if !(x0.is_finite() && y0.is_finite()) {
        bail!("nothing to chart");
    }
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 20))
        .margin(20)
        .x_label_area_size(50)
        .y_label_area_size(80)
        .build_cartesian_2d((x0 / 1.5..x1 * 1.5).log_scale(), (y0 / 2.0..y1 * 2.0).log_scale())
        .map_err(|e| err(&e))?;
    chart
        .configure_mesh()
        .x_desc(if end_to_end { "preparation + render time, s" } else { "render time, s" })
        .y_desc("relMSE")
        .x_labels(8)
        .y_labels(8)
        .x_label_formatter(&|v: &f64| format!("{v:.2e}"))
        .y_label_formatter(&|v: &f64| format!("{v:.0e}"))
        .draw()
        .map_err(|e| err(&e))?;
    let names = config_names(rows);
    for (i, name) in names.iter().enumerate() {
        let colour = crate::stability::COLOURS[i % crate::stability::COLOURS.len()];
        let line: Vec<(f64, f64)> =
            rows.iter().zip(&points).filter(|(r, _)| r.config == *name).map(|(_, p)| *p).collect();
        chart
            .draw_series(LineSeries::new(line.clone(), colour.stroke_width(2)))
            .map_err(|e| err(&e))?
            .label(*name)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2)));
        chart.draw_series(line.iter().map(|&p| Circle::new(p, 4, colour.filled()))).map_err(|e| err(&e))?;
    }
    // The unbiased 1/t slope through the first point.
    let (tx, ty) = points[0];
    let guide: Vec<(f64, f64)> = [x0 / 1.5, x1 * 1.5].iter().map(|&x| (x, ty * tx / x)).collect();
    chart
        .draw_series(LineSeries::new(guide, BLACK.mix(0.4).stroke_width(1)))
        .map_err(|e| err(&e))?
        .label("1/t (unbiased)")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK.mix(0.4)));
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(|e| err(&e))?;
    root.present().map_err(|e| err(&e))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The heat map's scale: no error is black, 10⁻⁵ still black, 10⁻² past red into
    /// orange, ≥ 1 white; the crop takes the centred square, row by row.
    #[test]
    fn heat_maps_and_crops() {
        let reference = [0.5f32, 0.5, 0.5];
        let heat = |x: f32| heat_map(&[x, x, x], &reference);
        assert_eq!(heat(0.5), [0, 0, 0]);
        // (x − r)² / (r² + 0.01) = 1e-5 at the bottom of the scale.
        assert_eq!(heat(0.5 + (1e-5f32 * 0.26).sqrt()), [0, 0, 0]);
        let mid = heat(0.5 + (1e-2f32 * 0.26).sqrt());
        assert!(mid[0] == 255 && mid[1] > 0 && mid[1] < 255 && mid[2] == 0, "{mid:?}");
        assert_eq!(heat(5.0), [255, 255, 255]);
        assert_eq!(file_name("gpu zsobol/2"), "gpu-zsobol-2");

        let (w, h) = (5u32, 3u32);
        let rgb: Vec<f32> = (0..w * h * 3).map(|i| i as f32).collect();
        let crop = Crop::centred(w, h);
        assert_eq!((crop.x, crop.y, crop.side), (1, 0, 3));
        let cut = crop.cut(&rgb, w);
        assert_eq!(cut.len(), 27);
        assert_eq!(&cut[..3], &rgb[3..6], "row 0 starts at column 1");
        assert_eq!(&cut[9..12], &rgb[18..21], "row 1 starts at pixel 6");
    }

    #[test]
    fn flip_is_zero_for_equal_images_and_grows_with_the_difference() {
        let (w, h) = (32u32, 24u32);
        let img: Vec<f32> = (0..w * h * 3).map(|i| ((i % 97) as f32 / 97.0).powi(2)).collect();
        assert_eq!(flip(&img, &img, w, h), 0.0);
        let mut rng = rng::Pcg32::seed_from_u64(3);
        let noisy = |amount: f32, rng: &mut rng::Pcg32| -> Vec<f32> {
            img.iter().map(|&v| (v + amount * (rng.next_f32() - 0.5)).max(0.0)).collect()
        };
        let (a, b) = (noisy(0.05, &mut rng), noisy(0.4, &mut rng));
        let (fa, fb) = (flip(&a, &img, w, h), flip(&b, &img, w, h));
        assert!(0.0 < fa && fa < fb && fb < 1.0, "{fa} {fb}");
    }

    #[test]
    fn ssim_is_one_for_equal_images_and_falls_with_noise() {
        let (w, h) = (24, 20);
        let img: Vec<f64> = (0..w * h).map(|i| (i % w) as f64 / w as f64 * 0.8 + 0.1).collect();
        assert!((ssim(&img, &img, w, h) - 1.0).abs() < 1e-12);
        let mut rng = rng::Pcg32::new(3, 1);
        let mut noisy =
            |amp: f64| -> Vec<f64> { img.iter().map(|v| v + amp * (rng.next_f32() as f64 - 0.5)).collect() };
        let (slight, strong) = (noisy(0.02), noisy(0.4));
        let (s1, s2) = (ssim(&slight, &img, w, h), ssim(&strong, &img, w, h));
        assert!(s1 < 1.0 && s2 < s1 && s2 > -1.0, "{s1} {s2}");
        // Symmetric.
        assert!((ssim(&img, &strong, w, h) - s2).abs() < 1e-12);
    }

    #[test]
    fn rel_mse_matches_its_formula() {
        assert_eq!(rel_mse(&[1.0, 0.0], &[1.0, 0.0]), 0.0);
        let v = rel_mse(&[2.0, 0.1], &[1.0, 0.0]);
        assert!((v - (1.0 / 1.01 + 0.01 / 0.01) / 2.0).abs() < 1e-6, "{v}");
    }

    #[test]
    fn presets_and_files_name_valid_settings() {
        #[derive(clap::Parser)]
        struct Wrapper {
            #[command(flatten)]
            scene: SceneArgs,
        }
        let base = <Wrapper as clap::Parser>::parse_from(["spt", "scene.obj"]).scene;
        for p in PRESETS.split(", ") {
            let configs = preset(p).unwrap_or_else(|| panic!("{p} is listed but not a preset"));
            assert!(configs.len() >= 2, "{p}");
            for c in &configs {
                // Every value a preset sets is one the command line accepts.
                c.apply(&base, SpectralMode::Hero).unwrap_or_else(|e| panic!("{p}: {e}"));
            }
        }
        let bad = Config { spectral: Some("cmyk".into()), ..Config::named("x") };
        let Err(e) = bad.apply(&base, SpectralMode::Hero) else { panic!("cmyk accepted") };
        assert!(e.to_string().contains("'x': spectral"), "{e}");
        let bad = Config { integrator: Some("mlt".into()), ..Config::named("y") };
        let Err(e) = bad.apply(&base, SpectralMode::Hero) else { panic!("mlt accepted") };
        assert!(e.to_string().contains("'y': integrator"), "{e}");
        assert!(configs("nope").unwrap_err().to_string().contains("preset"));
        let dir = std::env::temp_dir().join(format!("spt-compare-unit-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("c.json");
        std::fs::write(&file, r#"[{"name": "a", "sampler": "sobol"}, {"name": "b", "colour": "red"}]"#).unwrap();
        let msg = configs(file.to_str().unwrap()).unwrap_err().to_string();
        assert!(msg.contains("c.json:1:") && msg.contains("colour"), "{msg}");
    }

    #[test]
    fn csv_and_table_have_a_row_per_measurement() {
        let m = |config: &str, spp, render_s, rel_mse| Measurement {
            config: config.into(),
            spp,
            render_s,
            prepare_s: 0.01,
            rel_mse,
            ssim: 0.9,
            flip: 0.1,
        };
        let rows = [m("a", 1, 1.0, 0.4), m("a", 2, 2.0, 0.2), m("b, quoted", 1, 1.0, 0.1)];
        let text = csv(&rows, false);
        assert_eq!(text.lines().count(), 4);
        assert!(text.contains("\"b, quoted\""));
        // b reaches 4× the efficiency of a at its largest budget: 1/(0.1·1) against 1/(0.2·2).
        assert!(table(&rows, false).contains("4.00×"), "{}", table(&rows, false));
        // End to end, each render also pays its preparation: 1/(0.1·1.01) against 1/(0.2·2.01).
        let slow_prepare = [m("a", 2, 2.0, 0.2), Measurement { prepare_s: 1.0, ..m("b", 1, 1.0, 0.1) }];
        assert!(table(&slow_prepare, true).contains("2.01×"), "{}", table(&slow_prepare, true));
        assert!(table(&slow_prepare, true).contains("total_s"));
    }
}
