//! Writes the procedural sky the example scenes use as an environment map
//! (`scenes/maps/sky.exr`): a latitude–longitude image, y up, with a blue zenith fading to a
//! pale horizon, a darker ground and a small sun, 256 × 128 texels of linear sRGB radiance.
//!
//! `cargo run -p tracer --example sky_map -- scenes/maps/sky.exr`

use glam::Vec2;
use tracer::envmap::EnvironmentMap;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args().nth(1).unwrap_or_else(|| "scenes/maps/sky.exr".into());
    let (w, h) = (256u32, 128u32);
    // Only for its direction ↔ texel mapping.
    let frame = EnvironmentMap::new(1, 1, vec![[0.0; 3]], 0.0)?;
    // The sun: 35° above the horizon, towards −x+z (left, behind the default camera).
    let sun = glam::Vec3::new(-0.5, 35f32.to_radians().sin(), 0.7).normalize();
    let mut image = image::Rgb32FImage::new(w, h);
    for (x, y, p) in image.enumerate_pixels_mut() {
        let d = frame.direction(Vec2::new((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32));
        let rgb = if d.y >= 0.0 {
            // Rayleigh-ish: bluer towards the zenith, whiter at the horizon.
            let t = d.y.powf(0.4);
            let sky = [0.9 - 0.6 * t, 0.95 - 0.4 * t, 1.0];
            let glow = 3.0 * d.dot(sun).max(0.0).powi(32);
            let disk = if d.dot(sun) > 0.9996 { 2000.0 } else { 0.0 };
            sky.map(|c| c + glow + disk)
        } else {
            let t = (-d.y).powf(0.5);
            [0.25 - 0.1 * t, 0.22 - 0.09 * t, 0.18 - 0.08 * t]
        };
        *p = image::Rgb(rgb);
    }
    image.save(&out)?;
    println!("wrote {out}: {w}×{h}");
    Ok(())
}
