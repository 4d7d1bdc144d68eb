use super::*;
use rng::Pcg32;

/// A map with a bright spot, a dim gradient and one black row, `w` × `h`.
fn test_map(w: u32, h: u32, rotation: f32) -> EnvironmentMap {
    let texels = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| {
            if y == h - 1 {
                [0.0; 3]
            } else if (x, y) == (w / 4, h / 3) {
                [40.0, 20.0, 5.0]
            } else {
                [0.1 + x as f32 / w as f32, 0.2, 0.05 + y as f32 / h as f32]
            }
        })
        .collect();
    EnvironmentMap::new(w, h, texels, rotation).unwrap()
}

#[test]
fn directions_and_map_coordinates_are_inverse_and_the_centre_looks_down_minus_z() {
    for rotation in [0.0, 37.0, -90.0] {
        let m = test_map(8, 4, rotation);
        let mut rng = Pcg32::seed_from_u64(1);
        for _ in 0..1000 {
            let uv = Vec2::new(rng.next_f32(), 0.01 + 0.98 * rng.next_f32());
            let d = m.direction(uv);
            assert!((d.length() - 1.0).abs() < 1e-5);
            let back = m.uv(d);
            let du = (back.x - uv.x).abs();
            assert!(du.min(1.0 - du) < 1e-4 && (back.y - uv.y).abs() < 1e-4, "{uv} → {d} → {back}");
        }
    }
    let m = test_map(8, 4, 0.0);
    assert!((m.direction(Vec2::new(0.5, 0.5)) - Vec3::NEG_Z).length() < 1e-6);
    assert!((m.direction(Vec2::new(0.75, 0.5)) - Vec3::X).length() < 1e-6, "u grows towards +x");
    assert!((m.direction(Vec2::new(0.3, 0.0)) - Vec3::Y).length() < 1e-6, "the top row is the zenith");
    // Turning the map by 90° counter-clockwise seen from above moves its centre from −z to −x.
    let turned = test_map(8, 4, 90.0);
    assert!((turned.direction(Vec2::new(0.5, 0.5)) - Vec3::NEG_X).length() < 1e-6);
}

#[test]
fn sampled_directions_follow_the_pdf_texel_by_texel() {
    // χ² over the texels: the sampler's counts against N × (the pdf integrated over each
    // texel's solid angle, by a fine quadrature of `pdf` — not of the distribution's own
    // tables).
    let (w, h) = (16u32, 8u32);
    let m = test_map(w, h, 25.0);
    let n = 400_000usize;
    let mut counts = vec![0usize; (w * h) as usize];
    let mut rng = Pcg32::seed_from_u64(7);
    let mut disagree = 0;
    for _ in 0..n {
        let (d, pdf) = m.sample(Vec2::new(rng.next_f32(), rng.next_f32())).unwrap();
        // The same density looked up from the direction, but for samples within rounding
        // of a texel's edge (the direction's round trip lands in the neighbour).
        if (pdf - m.pdf(d)).abs() > 1e-4 * pdf {
            disagree += 1;
        }
        let uv = m.uv(d);
        let x = ((uv.x * w as f32) as usize).min(w as usize - 1);
        let y = ((uv.y * h as f32) as usize).min(h as usize - 1);
        counts[y * w as usize + x] += 1;
    }
    let k = 24;
    let mut chi2 = 0.0;
    let mut total_p = 0.0;
    for y in 0..h {
        for x in 0..w {
            let mut p = 0.0f64;
            for j in 0..k {
                for i in 0..k {
                    let u = (x as f32 + (i as f32 + 0.5) / k as f32) / w as f32;
                    let v = (y as f32 + (j as f32 + 0.5) / k as f32) / h as f32;
                    // dω = 2π² sin θ du dv on the map.
                    let dw = 2.0 * PI * PI * (v * PI).sin() / (w * h) as f32 / (k * k) as f32;
                    p += (m.pdf(m.direction(Vec2::new(u, v))) * dw) as f64;
                }
            }
            total_p += p;
            let e = p * n as f64;
            let o = counts[(y * w + x) as usize] as f64;
            chi2 += (o - e).powi(2) / e;
        }
    }
    assert!(disagree < n / 1000, "{disagree} of {n} sample pdfs differ from pdf(dir)");
    assert!((total_p - 1.0).abs() < 2e-3, "the pdf integrates to {total_p}");
    // 127 degrees of freedom: the 0.9999 quantile is about 190.
    assert!(chi2 < 190.0, "χ² = {chi2}");
}

#[test]
fn a_missing_sine_factor_fails_the_pdf_integral() {
    // The check above must catch a pdf without the 1/sin θ of the map's Jacobian: its
    // integral over the sphere is then far from 1.
    let m = test_map(16, 8, 0.0);
    let k = 200;
    let mut wrong = 0.0f64;
    for j in 0..k {
        for i in 0..k {
            let uv = Vec2::new((i as f32 + 0.5) / k as f32, (j as f32 + 0.5) / k as f32);
            let sin = (uv.y * PI).sin();
            let dw = 2.0 * PI * PI * sin / (k * k) as f32;
            wrong += (m.pdf(m.direction(uv)) * sin * dw) as f64;
        }
    }
    assert!((wrong - 1.0).abs() > 0.1, "{wrong}");
}

#[test]
fn the_bright_texel_draws_most_samples_and_black_texels_keep_a_floor() {
    let m = test_map(16, 8, 0.0);
    let bright = m.direction(Vec2::new((4.0 + 0.5) / 16.0, (2.0 + 0.5) / 8.0));
    let dim = m.direction(Vec2::new(0.6, 0.4));
    assert!(m.pdf(bright) > 20.0 * m.pdf(dim));
    let black = m.direction(Vec2::new(0.5, (7.0 + 0.5) / 8.0));
    assert!(m.pdf(black) > 0.0);
    assert_eq!(m.rgb(black), [0.0; 3]);
}

#[test]
fn radiance_is_bilinear_in_rgb_and_its_spectrum_has_the_texel_colour() {
    let texels = vec![[1.0, 0.5, 0.25], [3.0, 0.5, 0.25]];
    let m = EnvironmentMap::new(2, 1, texels, 0.0).unwrap();
    // Halfway between the texel centres (u = ½ is −z): the mean.
    let mid = m.rgb(Vec3::NEG_Z);
    assert!((mid[0] - 2.0).abs() < 1e-5 && (mid[1] - 0.5).abs() < 1e-5, "{mid:?}");
    // The spectral radiance seen as linear sRGB is the RGB (the illuminant uplift).
    const N: usize = 95;
    let wl = SampledWavelengths::<N>::fixed_bins(362.5, 5.0);
    let back = wl.to_linear_srgb(&m.radiance(Vec3::NEG_Z, &wl));
    for c in 0..3 {
        assert!((back[c] - mid[c]).abs() < 0.02 * mid[c], "{back:?} vs {mid:?}");
    }
    let rgb = SampledWavelengths::<3>::rgb();
    assert_eq!(m.radiance(Vec3::NEG_Z, &rgb).0, mid);
}

#[test]
fn bad_maps_are_refused_with_the_reason() {
    assert!(EnvironmentMap::new(0, 4, vec![], 0.0).unwrap_err().contains("0×4"));
    assert!(EnvironmentMap::new(2, 1, vec![[0.0; 3]], 0.0).unwrap_err().contains("1 texels"));
    let e = EnvironmentMap::new(2, 1, vec![[0.0; 3], [f32::NAN, 0.0, 0.0]], 0.0).unwrap_err();
    assert!(e.contains("texel (1, 0)"), "{e}");
    assert!(EnvironmentMap::new(1, 1, vec![[-1.0, 0.0, 0.0]], 0.0).is_err());
    assert!(EnvironmentMap::new(1, 1, vec![[1.0; 3]], f32::INFINITY).is_err());
    let e = EnvironmentMap::load(Path::new("/nonexistent/sky.exr"), 0.0).unwrap_err().to_string();
    assert!(e.contains("sky.exr"), "{e}");
}
