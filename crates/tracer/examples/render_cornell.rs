//! Rendering through the library API: load an OBJ, prepare it, render a few samples per
//! pixel with the CPU backend and write a PNG and the standard-error EXR.
//!
//! ```sh
//! cargo run --release -p tracer --example render_cornell -- ../shared/scenes/cornell-box/CornellBox-Original.obj
//! ```

use std::path::PathBuf;
use tracer::output::write_image;
use tracer::{Backend, CpuBackend, RenderSettings, SceneOptions, SpectralMode};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path: PathBuf =
        std::env::args().nth(1).unwrap_or_else(|| "../shared/scenes/cornell-box/CornellBox-Original.obj".into()).into();
    let scene = tracer::obj::load_obj(&path)?;
    // A backend prepares the scene its own way (the CPU builds its 4-wide BVH).
    let backend = CpuBackend::new(0)?;
    let prepared = backend.prepare(scene, &SceneOptions::default())?;
    let settings = RenderSettings { width: 256, height: 256, spp: 16, mode: SpectralMode::Hero, ..Default::default() };
    let (film, stats) = tracer::render(prepared.as_ref(), &settings, &|_| {})?;
    write_image("cornell-example.png".as_ref(), film.width(), film.height(), &film.mean_rgb())?;
    write_image("cornell-example-stderr.exr".as_ref(), film.width(), film.height(), &film.std_error_rgb())?;
    println!(
        "{:.3} M samples/s; image means (linear sRGB) {:.4?}; {} NaN/Inf samples dropped",
        stats.samples_per_second() / 1e6,
        film.channel_means(),
        stats.non_finite
    );
    Ok(())
}
