//! A small viewer run for the Xvfb test and the docs' screenshot: the material-preview
//! sphere on the CPU backend.
//!
//! `view-smoke OUT.png [FRAMES=3] [WIDTH=64] [HEIGHT=48] [SPP_PER_FRAME=1] [MAX_SPP=0]`
//! renders FRAMES frames in a window (stopping early at MAX_SPP samples per pixel, 0 for
//! no limit), saves the image to OUT (PNG or EXR) and prints the session's figures.

use anyhow::{Context, anyhow};
use spectral::spectrum::Colour;
use std::path::PathBuf;
use tracer::{Backend, CpuBackend, Material, RenderSettings, SceneOptions};
use viewer::ViewerOptions;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let out = args
        .first()
        .ok_or_else(|| anyhow!("usage: view-smoke OUT.png [FRAMES] [WIDTH] [HEIGHT] [SPP_PER_FRAME] [MAX_SPP]"))?;
    let number = |i: usize, default: u32| -> anyhow::Result<u32> {
        args.get(i).map_or(Ok(default), |s| s.parse().with_context(|| format!("argument {i}: {s:?}")))
    };
    let sphere = Material::diffuse("sphere", Colour::reflectance_rgb([0.8, 0.35, 0.1])?)?;
    let scene = CpuBackend::new(0)?.prepare(tracer::scenes::material_sphere(sphere), &SceneOptions::default())?;
    let options = ViewerOptions {
        width: number(2, 64)?,
        height: number(3, 48)?,
        spp_per_frame: number(4, 1)?,
        max_spp: Some(number(5, 0)?).filter(|&m| m > 0),
        exit_after_frames: Some(number(1, 3)?),
        save_on_exit: Some(PathBuf::from(out)),
        title: "material sphere".into(),
        ..ViewerOptions::default()
    };
    let stats = viewer::run(scene, RenderSettings::default(), options)?;
    println!("frames {} spp {} samples/s {:.0}", stats.frames, stats.spp, stats.samples_per_second);
    Ok(())
}
