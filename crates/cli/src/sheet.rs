//! `spt sheet`: a labelled contact sheet of one BSDF parameter swept over values, each
//! cell the built-in material sphere — the thesis's figures 9.1–9.4, reproducible.

use anyhow::{Context, Result, anyhow, bail};
use brdf::params::ParamValue;
use font8x8::UnicodeFonts;
use std::path::Path;
use tracer::material::{Material, ModelId};
use tracer::{CpuBackend, RenderSettings, SceneOptions, SpectralMode};

/// One sweep: a model, fixed parameters, and the parameter(s) varied per cell.
pub struct Sweep {
    /// The model.
    pub model: ModelId,
    /// Parameters held fixed.
    pub fixed: Vec<(String, f32)>,
    /// Per cell: the parameters that vary, with their values.
    pub cells: Vec<Vec<(String, f32)>>,
}

/// The thesis's sweeps by name.
pub const PRESETS: &[&str] = &["schlick-r", "schlick-p", "sa-n", "sa-aniso"];

/// A named preset sweep.
pub fn preset(name: &str) -> Result<Sweep> {
    let model = |n: &str| ModelId::by_name(n).ok_or_else(|| anyhow!("model '{n}' is not built in"));
    let one = |p: &str, vs: &[f32]| vs.iter().map(|&v| vec![(p.to_string(), v)]).collect::<Vec<_>>();
    Ok(match name {
        // Figure 9.1: Schlick roughness from specular to diffuse.
        "schlick-r" => Sweep {
            model: model("schlick")?,
            fixed: vec![("isotropy".into(), 1.0)],
            cells: one("roughness", &[0.001, 0.01, 0.05, 0.1, 0.25, 0.5, 1.0]),
        },
        // Figure 9.3: Schlick isotropy at roughness 0.1.
        "schlick-p" => Sweep {
            model: model("schlick")?,
            fixed: vec![("roughness".into(), 0.1)],
            cells: one("isotropy", &[1.0, 0.5, 0.2, 0.1, 0.05, 0.01]),
        },
        // Figure 9.2: Shirley–Ashikhmin n_u = n_v on a log scale.
        "sa-n" => Sweep {
            model: model("ashikhmin")?,
            fixed: vec![("rs".into(), 0.6), ("rd".into(), 0.3)],
            cells: [100_000.0f32, 10_000.0, 1000.0, 100.0, 10.0, 1.0]
                .iter()
                .map(|&n| vec![("nu".to_string(), n), ("nv".to_string(), n)])
                .collect(),
        },
        // Figure 9.4: n_u swept at n_v = 10, then the roles swapped.
        "sa-aniso" => Sweep {
            model: model("ashikhmin")?,
            fixed: vec![("rs".into(), 0.6), ("rd".into(), 0.3)],
            cells: [100_000.0f32, 10_000.0, 1000.0, 100.0]
                .iter()
                .map(|&n| vec![("nu".to_string(), n), ("nv".to_string(), 10.0)])
                .chain(
                    [100_000.0f32, 10_000.0, 1000.0, 100.0]
                        .iter()
                        .map(|&n| vec![("nu".to_string(), 10.0), ("nv".to_string(), n)]),
                )
                .collect(),
        },
        other => bail!("unknown preset '{other}' (known: {})", PRESETS.join(", ")),
    })
}

/// Renders every cell and writes the labelled sheet.
pub fn render_sheet(sweep: &Sweep, cell: u32, spp: u32, mode: SpectralMode, threads: usize, out: &Path) -> Result<()> {
    if !(16..=2048).contains(&cell) {
        bail!("--cell {cell} must be between 16 and 2048 pixels");
    }
    if sweep.cells.is_empty() {
        bail!("nothing to render: no values");
    }
    let backend = CpuBackend::new(threads)?;
    let label_h = 12u32;
    let title_h = 12u32;
    let cols = (sweep.cells.len() as u32).min(if sweep.cells.len() == 8 { 4 } else { 7 });
    let rows = (sweep.cells.len() as u32).div_ceil(cols);
    let (w, h) = (cols * cell, title_h + rows * (cell + label_h));
    let mut sheet = image::RgbImage::from_pixel(w, h, image::Rgb([255, 255, 255]));
    // Title: the model, the swept parameter names and the fixed ones.
    let swept: Vec<&str> = sweep.cells[0].iter().map(|(k, _)| k.as_str()).collect();
    let fixed: Vec<String> = sweep.fixed.iter().map(|(k, v)| format!("{k}={}", fmt_value(*v))).collect();
    let title = format!("{}: {} {}", sweep.model.def().name, swept.join("/"), fixed.join(" "));
    draw_text(&mut sheet, 2, 2, &title, w);
    for (i, varied) in sweep.cells.iter().enumerate() {
        let params: Vec<(&str, ParamValue)> =
            sweep.fixed.iter().chain(varied).map(|(k, v)| (k.as_str(), ParamValue::Scalar(*v))).collect();
        // Cell labels hold only the values (the title names the parameters).
        let label: String = varied.iter().map(|(_, v)| fmt_value(*v)).collect::<Vec<_>>().join("/");
        let material = Material::builtin("sheet", sweep.model, &params).with_context(|| format!("cell '{label}'"))?;
        let prepared = backend.prepare_cpu(tracer::scenes::material_sphere(material), &SceneOptions::default())?;
        let settings = RenderSettings { width: cell, height: cell, spp, mode, seed: i as u64, ..Default::default() };
        let (film, stats) = tracer::render(&prepared, &settings, &|_| {})?;
        eprintln!("  {label}: {:.2} s, {} NaN/Inf", stats.wall.as_secs_f64(), stats.non_finite);
        let (x0, y0) = ((i as u32 % cols) * cell, title_h + (i as u32 / cols) * (cell + label_h));
        for (k, px) in film.mean_rgb().chunks_exact(3).enumerate() {
            let (x, y) = (k as u32 % cell, k as u32 / cell);
            sheet.put_pixel(x0 + x, y0 + y, image::Rgb(std::array::from_fn(|c| spectral::srgb_to_u8(px[c]))));
        }
        draw_text(&mut sheet, x0 + 2, y0 + cell + 2, &label, x0 + cell);
    }
    sheet.save(out).with_context(|| format!("cannot write {}", out.display()))?;
    Ok(())
}

fn fmt_value(v: f32) -> String {
    if v >= 1000.0 { format!("{v:.0e}") } else { format!("{v}") }
}

/// Draws ASCII text with the 8×8 public-domain font8x8 glyphs, clipped to the image and
/// to x < `x_end`.
fn draw_text(img: &mut image::RgbImage, x: u32, y: u32, text: &str, x_end: u32) {
    for (i, ch) in text.chars().enumerate() {
        let Some(glyph) = font8x8::BASIC_FONTS.get(ch) else { continue };
        for (row, bits) in glyph.iter().enumerate() {
            for col in 0..8 {
                if bits & (1 << col) != 0 {
                    let (px, py) = (x + i as u32 * 8 + col, y + row as u32);
                    if px < img.width().min(x_end) && py < img.height() {
                        img.put_pixel(px, py, image::Rgb([0, 0, 0]));
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_is_drawn_and_clipped() {
        let mut img = image::RgbImage::from_pixel(20, 10, image::Rgb([255; 3]));
        draw_text(&mut img, 0, 0, "A1 long text beyond the edge", 12);
        let dark = img.pixels().filter(|p| p.0[0] == 0).count();
        assert!(dark > 10);
        assert!(img.enumerate_pixels().all(|(x, _, p)| x < 12 || p.0[0] == 255), "clipped at x_end");
    }

    #[test]
    fn unknown_presets_are_errors() {
        assert!(preset("phong-n").is_err());
    }
}
