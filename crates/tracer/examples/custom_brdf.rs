//! A BRDF written outside the workspace, plugged into the renderer without touching it:
//! the modified Phong model of Lafortune & Willems 1994 (`support/phong.rs`: it implements
//! `brdf::Bsdf<N>` for any number of wavelengths, `brdf::BsdfBuilder` to be instantiated at
//! each hit, and ships its WGSL twin through `BsdfBuilder::wgsl_twin`, which lets the GPU
//! backend run it too); the example replaces the material of the Cornell box's two blocks
//! and renders on the CPU. On the GPU, the same scene renders through the twin
//! (`custom_bsdf_twins_match_the_cpu` in `crates/gpu/tests/equivalence.rs`).
//!
//! ```sh
//! cargo run --release -p tracer --example custom_brdf -- ../shared/scenes/cornell-box/CornellBox-Original.obj
//! ```

#[path = "support/phong.rs"]
mod phong;

use phong::PhongParams;
use spectral::spectrum::Colour;
use std::sync::Arc;
use tracer::material::Material;
use tracer::output::write_image;
use tracer::{Backend, CpuBackend, RenderSettings, SceneOptions};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args().nth(1).unwrap_or_else(|| "../shared/scenes/cornell-box/CornellBox-Original.obj".into());
    let mut scene = tracer::obj::load_obj(path.as_ref())?;
    let phong = Arc::new(PhongParams {
        kd: Colour::reflectance_rgb([0.35, 0.3, 0.25])?,
        ks: Colour::reflectance_rgb([0.5, 0.5, 0.5])?,
        exponent: 60.0,
    });
    let mut replaced = 0;
    for m in &mut scene.materials {
        if m.name == "shortBox" || m.name == "tallBox" {
            *m = Material::custom(&m.name, phong.clone(), false);
            replaced += 1;
        }
    }
    let prepared = CpuBackend::new(0)?.prepare(scene, &SceneOptions::default())?;
    let settings = RenderSettings { width: 256, height: 256, spp: 64, ..Default::default() };
    let (film, stats) = tracer::render(prepared.as_ref(), &settings, &|_| {})?;
    write_image("custom-brdf.png".as_ref(), film.width(), film.height(), &film.mean_rgb())?;
    println!(
        "replaced {replaced} materials with the custom Phong BRDF; wrote custom-brdf.png ({:.3} M samples/s, {} NaN/Inf)",
        stats.samples_per_second() / 1e6,
        stats.non_finite
    );
    Ok(())
}
