//! `spt atlas`: the atlas integrator's atlas on its own — the atlas thesis's table 1
//! (the gather's time for sample counts × atlas resolutions) and the G-buffer as images.

use crate::{SceneArgs, atlas_settings, loaded_scene, scene_options};
use anyhow::{Context, Result, bail};
use clap::Args;
use std::path::PathBuf;
use tracer::CpuBackend;
use tracer::integrator::{Atlas, AtlasSettings};

/// `spt atlas` options.
#[derive(Args)]
pub struct AtlasArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Points gathered per texel, comma-separated: one gather per count.
    #[arg(long, value_delimiter = ',', default_value = "10,25,50,100,200,400")]
    pub counts: Vec<u32>,
    /// Atlas sides in texels, comma-separated: one atlas per resolution.
    #[arg(long, value_delimiter = ',', default_value = "512,1024")]
    pub resolutions: Vec<u32>,
    /// A directory for the last atlas's images: atlas-normal.png, atlas-position.png,
    /// atlas-direct.png and atlas-indirect.png (sRGB; light clamped at 1).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
}

/// Builds an atlas per resolution, gathers it at each count and prints the times.
pub fn run(args: AtlasArgs) -> Result<()> {
    if args.counts.is_empty() || args.resolutions.is_empty() {
        bail!("--counts and --resolutions need at least one value each");
    }
    let scene = loaded_scene(&args.scene)?;
    let backend = CpuBackend::new(args.scene.threads)?;
    let prepared = backend.prepare_cpu(scene, &scene_options(&args.scene))?;
    let view = prepared.view();
    let pool = rayon::ThreadPoolBuilder::new().num_threads(args.scene.threads).build()?;
    let base = atlas_settings(&args.scene)?;
    println!(
        "# {}: atlas gather, {} visibility, {} threads",
        args.scene.scene.display(),
        if base.visibility { "with" } else { "without" },
        pool.current_num_threads()
    );
    println!("resolution  density  charts   texels  unwrap_ms  direct_ms  samples  gather_ms  gathers/s");
    let mut last = None;
    for &resolution in &args.resolutions {
        let settings = AtlasSettings { resolution, samples: args.counts[0], ..base };
        let mut atlas = pool.install(|| Atlas::build(&view, &settings))?;
        for &samples in &args.counts {
            let settings = AtlasSettings { samples, ..settings };
            settings.validate()?;
            pool.install(|| atlas.gather(&view, &settings));
            let s = atlas.stats;
            println!(
                "{:>10}  {:>7.2}  {:>6}  {:>7}  {:>9.1}  {:>9.1}  {:>7}  {:>9.1}  {:>9.2}",
                format!("{}x{}", s.width, s.height),
                s.density,
                s.charts,
                s.texels_used,
                s.unwrap.as_secs_f64() * 1e3,
                s.direct.as_secs_f64() * 1e3,
                samples,
                s.gather.as_secs_f64() * 1e3,
                1.0 / s.gather.as_secs_f64().max(1e-9)
            );
        }
        last = Some(atlas);
    }
    if let (Some(dir), Some(atlas)) = (&args.output, &last) {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
        let (w, h) = atlas.size();
        for what in ["normal", "position", "direct", "indirect"] {
            let rgb = atlas.image(what).expect("a known image");
            let encode = |v: f32| {
                if what == "normal" || what == "position" {
                    (v.clamp(0.0, 1.0) * 255.0).round() as u8
                } else {
                    spectral::srgb_to_u8(v)
                }
            };
            let bytes: Vec<u8> = rgb.iter().map(|&v| encode(v)).collect();
            let img = image::RgbImage::from_raw(w, h, bytes).expect("w × h × 3 bytes");
            let path = dir.join(format!("atlas-{what}.png"));
            img.save(&path).with_context(|| format!("cannot write {}", path.display()))?;
        }
        eprintln!("wrote the atlas images to {}", dir.display());
    }
    Ok(())
}
