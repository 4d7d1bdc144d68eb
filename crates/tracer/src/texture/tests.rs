use super::*;

/// A 2×2 checkerboard: white and black texels, alpha 255/0 alternating by column.
fn checker() -> Arc<TextureImage> {
    let w = [255, 255, 255, 255];
    let b = [0, 0, 0, 0];
    Arc::new(TextureImage::from_rgba8(2, 2, vec![w, b, b, w]).unwrap())
}

fn linear(image: Arc<TextureImage>) -> TextureMap {
    TextureMap::new(image, Encoding::Linear)
}

#[test]
fn texel_centres_read_their_texels_and_midpoints_their_mean() {
    let m = linear(checker());
    assert_eq!(m.sample(Vec2::new(0.25, 0.25)), [1.0; 4]);
    assert_eq!(m.sample(Vec2::new(0.75, 0.25)), [0.0; 4]);
    assert_eq!(m.sample(Vec2::new(0.25, 0.75)), [0.0; 4]);
    assert_eq!(m.sample(Vec2::new(0.75, 0.75)), [1.0; 4]);
    // Halfway between a white and a black centre: the mean, in each channel.
    let mid = m.sample(Vec2::new(0.5, 0.25));
    assert!(mid.iter().all(|&c| (c - 0.5).abs() < 1e-6), "{mid:?}");
    // A quarter of the way from the white centre towards the black one.
    let q = m.sample(Vec2::new(0.375, 0.25));
    assert!((q[0] - 0.75).abs() < 1e-6, "{q:?}");
}

#[test]
fn wrap_modes_fold_coordinates_as_gltf_says() {
    let mut m = linear(checker());
    // Repeat: one period over is the same texel.
    assert_eq!(m.sample(Vec2::new(1.25, 0.25)), [1.0; 4]);
    assert_eq!(m.sample(Vec2::new(-0.25, 0.25)), [0.0; 4]);
    // Clamp: beyond the edge the edge texel continues.
    m.wrap = [Wrap::Clamp; 2];
    assert_eq!(m.sample(Vec2::new(-3.0, 0.25)), [1.0; 4]);
    assert_eq!(m.sample(Vec2::new(7.0, 0.25)), [0.0; 4]);
    // Mirror: [1, 2) is [0, 1) reversed, so u = 1.25 reads the texel at 0.75.
    m.wrap = [Wrap::Mirror; 2];
    assert_eq!(m.sample(Vec2::new(1.25, 0.25)), [0.0; 4]);
    assert_eq!(m.sample(Vec2::new(-0.25, 0.25)), [1.0; 4]);
    // Non-finite coordinates read a texel rather than panicking.
    assert!(m.sample(Vec2::new(f32::NAN, f32::INFINITY)).iter().all(|c| c.is_finite()));
    assert!(m.sample(Vec2::new(1e30, -1e30)).iter().all(|c| c.is_finite()));
}

#[test]
fn srgb_texels_are_decoded_and_alpha_is_not() {
    let image = Arc::new(TextureImage::from_rgba8(1, 1, vec![[188, 188, 188, 188]]).unwrap());
    let t = TextureMap::new(image, Encoding::Srgb).sample(Vec2::splat(0.5));
    // sRGB 188/255 = 0.737 encodes linear 0.5029 (IEC 61966-2-1).
    assert!((t[0] - 0.502_886).abs() < 1e-5, "{t:?}");
    assert!((t[3] - 188.0 / 255.0).abs() < 1e-6, "{t:?}");
}

#[test]
fn a_transform_moves_scales_and_rotates_the_lookup() {
    let mut m = linear(checker());
    // Offset by half the image: the white texel's centre (0.25, 0.25) now reads black.
    m.transform = Mat3::from_cols(Vec3::X, Vec3::Y, Vec3::new(0.5, 0.0, 1.0));
    assert_eq!(m.sample(Vec2::new(0.25, 0.25)), [0.0; 4]);
    // Scale 2: (0.125, 0.125) maps to the white centre (0.25, 0.25).
    m.transform = Mat3::from_cols(Vec3::X * 2.0, Vec3::Y * 2.0, Vec3::Z);
    assert_eq!(m.sample(Vec2::new(0.125, 0.375)), [0.0; 4]);
    assert_eq!(m.sample(Vec2::new(0.125, 0.125)), [1.0; 4]);
    // KHR_texture_transform: the extension's rotation matrix [[cos, sin], [−sin, cos]]
    // takes (1, 0) to (0, −1) at a quarter turn; scale before rotation, offset last.
    let t = khr_texture_transform([0.5, 0.25], std::f32::consts::FRAC_PI_2, [2.0, 3.0]);
    let moved = t.transform_point2(Vec2::new(1.0, 0.0));
    assert!((moved - Vec2::new(0.5, 0.25 - 2.0)).length() < 1e-6, "{moved}");
    let moved = t.transform_point2(Vec2::new(0.0, 1.0));
    assert!((moved - Vec2::new(0.5 + 3.0, 0.25)).length() < 1e-6, "{moved}");
    assert_eq!(khr_texture_transform([0.0; 2], 0.0, [1.0; 2]), Mat3::IDENTITY);
}

#[test]
fn textures_must_have_a_size_within_bounds_and_match_their_texels() {
    assert!(TextureImage::from_rgba8(0, 1, vec![]).is_err());
    assert!(TextureImage::from_rgba8(MAX_TEXTURE_SIZE + 1, 1, vec![[0; 4]; MAX_TEXTURE_SIZE as usize + 1]).is_err());
    assert!(TextureImage::from_rgba8(2, 2, vec![[0; 4]; 3]).is_err());
    let e = TextureImage::decode(b"not an image at all").unwrap_err();
    assert!(e.contains("not a PNG"), "{e}");
    // A PNG header claiming 100000×100000 pixels is refused before decoding.
    let mut png = Vec::new();
    let img = image::RgbaImage::from_pixel(3, 2, image::Rgba([10, 20, 30, 255]));
    img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png).unwrap();
    let decoded = TextureImage::decode(&png).unwrap();
    assert_eq!((decoded.width(), decoded.height(), decoded.texel(2, 1)), (3, 2, [10, 20, 30, 255]));
    let mut huge = png.clone();
    huge[16..20].copy_from_slice(&100_000u32.to_be_bytes());
    huge[20..24].copy_from_slice(&100_000u32.to_be_bytes());
    assert!(TextureImage::decode(&huge).is_err());
    // Truncated files are errors.
    for cut in [8, 30, png.len() - 5] {
        assert!(TextureImage::decode(&png[..cut]).is_err(), "cut at {cut}");
    }
}

#[test]
fn a_texel_colour_becomes_a_spectrum_of_the_same_colour() {
    // Many fixed wavelengths over the visible range: their XYZ → linear sRGB gives back
    // the texel's colour (the uplift's round trip, through the table).
    const N: usize = 95;
    let wl = SampledWavelengths::<N>::fixed_bins(362.5, 5.0);
    for rgb in [[0.8, 0.2, 0.1], [0.1, 0.5, 0.9], [0.3, 0.3, 0.3], [0.05, 0.6, 0.2]] {
        let s = reflectance_spectrum(rgb, &wl);
        // Seen under D65, sRGB's white, the reflectance is its own colour.
        let lit = SampledSpectrum(std::array::from_fn(|i| s.0[i] * spectral::uplift::d65_normalised(wl.lambda[i])));
        let back = wl.to_linear_srgb(&lit);
        for c in 0..3 {
            assert!((back[c] - rgb[c]).abs() < 0.01, "{rgb:?} → {back:?}");
        }
    }
    // RGB mode passes the value through.
    let rgb = SampledWavelengths::<3>::rgb();
    assert_eq!(reflectance_spectrum([0.2, 0.4, 0.6], &rgb).0, [0.2, 0.4, 0.6]);
}

#[test]
fn uv_derivatives_of_a_known_triangle() {
    // u along +x over 2 units, v along −z over 4 units.
    let p = [Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0), Vec3::new(0.0, 0.0, -4.0)];
    let uv = [Vec2::ZERO, Vec2::new(1.0, 0.0), Vec2::new(0.0, 1.0)];
    let (dpdu, dpdv) = triangle_uv_derivatives(p, uv);
    assert!((dpdu - Vec3::new(2.0, 0.0, 0.0)).length() < 1e-6, "{dpdu}");
    assert!((dpdv - Vec3::new(0.0, 0.0, -4.0)).length() < 1e-6, "{dpdv}");
    // Degenerate uvs: no derivatives.
    assert_eq!(triangle_uv_derivatives(p, [Vec2::ZERO; 3]), (Vec3::ZERO, Vec3::ZERO));
}

/// A one-texel normal map.
fn normal_map(rgb: [u8; 3]) -> MaterialTextures {
    let image = Arc::new(TextureImage::from_rgba8(1, 1, vec![[rgb[0], rgb[1], rgb[2], 255]]).unwrap());
    MaterialTextures {
        normal: Some(NormalMap { map: TextureMap::new(image, Encoding::Linear), scale: 1.0 }),
        ..Default::default()
    }
}

#[test]
fn normal_maps_tilt_towards_increasing_u_and_up_the_image() {
    // A floor (normal +y) whose u runs along +x and whose v runs along +z, so that up in
    // the image (decreasing v) is −z.
    let (n, dpdu, dpdv) = (Vec3::Y, Vec3::X, Vec3::Z);
    let flat = normal_map([128, 128, 255]).bent_normal(Vec2::ZERO, n, dpdu, dpdv);
    assert!((flat - n).length() < 0.01, "{flat}");
    // Red > ½ tilts towards +u (+x).
    let red = normal_map([255, 128, 128]).bent_normal(Vec2::ZERO, n, dpdu, dpdv);
    assert!(red.x > 0.7 && red.z.abs() < 0.01, "{red}");
    // Green > ½ tilts up the image: towards −∂p/∂v (−z), OpenGL's (glTF's) convention.
    let green = normal_map([128, 255, 128]).bent_normal(Vec2::ZERO, n, dpdu, dpdv);
    assert!(green.z < -0.7 && green.x.abs() < 0.01, "{green}");
    // A mirrored layout (v running along −z) flips the bitangent with it.
    let mirrored = normal_map([128, 255, 128]).bent_normal(Vec2::ZERO, n, dpdu, -dpdv);
    assert!(mirrored.z > 0.7, "{mirrored}");
    for v in [flat, red, green, mirrored] {
        assert!((v.length() - 1.0).abs() < 1e-5);
    }
    // Without derivatives the normal is left alone.
    assert_eq!(normal_map([255, 0, 0]).bent_normal(Vec2::ZERO, n, Vec3::ZERO, Vec3::ZERO), n);
}

#[test]
fn a_height_ramp_tilts_the_normal_down_its_slope() {
    // Heights rising with u (0, 85, 170, 255 across four texels), 1 world unit per unit
    // of height, over a floor where one unit of u is 10 world units along +x: slope 0.1.
    let image = TextureImage::from_rgba8(4, 1, [0u8, 85, 170, 255].map(|h| [h, h, h, 255]).to_vec()).unwrap();
    let mut map = TextureMap::new(Arc::new(image), Encoding::Linear);
    map.wrap = [Wrap::Clamp; 2];
    let t = MaterialTextures { bump: Some(BumpMap { map, scale: 1.0 }), ..Default::default() };
    let n = t.bent_normal(Vec2::new(0.5, 0.5), Vec3::Y, Vec3::X * 10.0, Vec3::Z * 10.0);
    // Displaced surface y = 0.1·x: normal (−0.1, 1, 0)/|…|, leaning against the rise.
    let want = Vec3::new(-0.4 / 3.0, 1.0, 0.0).normalize();
    assert!((n - want).length() < 1e-3, "{n} vs {want}");
}

#[test]
fn alpha_masks_cut_below_the_cutoff_and_blending_passes_one_minus_alpha() {
    let image = Arc::new(TextureImage::from_rgba8(2, 1, vec![[0, 0, 0, 100], [0, 0, 0, 200]]).unwrap());
    let mut map = TextureMap::new(image, Encoding::Linear);
    map.wrap = [Wrap::Clamp; 2];
    let (left, right) = (Vec2::new(0.1, 0.5), Vec2::new(0.9, 0.5));
    let mask = Alpha { mode: AlphaMode::Mask { cutoff: 0.5 }, factor: 1.0, map: Some(map.clone()) };
    assert!(mask.passes(left, || 0.99) && mask.passes(left, || 0.0));
    assert!(!mask.passes(right, || 0.99) && !mask.passes(right, || 0.0));
    // The factor scales the texture's alpha (200/255 · 0.5 < 0.5: cut).
    assert!(Alpha { factor: 0.5, ..mask.clone() }.passes(right, || 0.0));
    let blend = Alpha { mode: AlphaMode::Blend, factor: 1.0, map: Some(map) };
    let n = 100_000;
    let passed = (0..n)
        .filter(|&i| blend.passes(left, || alpha_hash(Vec3::new(i as f32, 0.5, -2.0), Vec3::new(0.0, 0.6, 0.8), 7)))
        .count();
    let expected = 1.0 - 100.0 / 255.0;
    let rate = passed as f64 / n as f64;
    // Binomial σ = 0.0015: 5σ.
    assert!((rate - expected).abs() < 0.008, "{rate} vs {expected}");
    assert!(!Alpha { mode: AlphaMode::Opaque, ..blend }.passes(left, || 0.9));
}

#[test]
fn the_alpha_hash_is_uniform_and_depends_on_ray_and_primitive() {
    let n = 200_000;
    let values: Vec<f32> = (0..n).map(|i| alpha_hash(Vec3::new(0.1, i as f32 * 1e-3, 0.0), Vec3::Z, 3)).collect();
    let mut bins = [0usize; 10];
    for v in &values {
        assert!((0.0..1.0).contains(v));
        bins[(v * 10.0) as usize] += 1;
    }
    // χ² with 9 degrees of freedom; 27.9 is its 0.999 quantile.
    let e = n as f64 / 10.0;
    let chi2: f64 = bins.iter().map(|&b| (b as f64 - e).powi(2) / e).sum();
    assert!(chi2 < 27.9, "{chi2} {bins:?}");
    assert_ne!(alpha_hash(Vec3::ONE, Vec3::Z, 1), alpha_hash(Vec3::ONE, Vec3::Z, 2));
}

/// An OpenEXR header with these attributes (name, type, value), no pixels.
fn exr_header(attributes: &[(&str, &str, Vec<u8>)]) -> Vec<u8> {
    let mut b = vec![0x76, 0x2f, 0x31, 0x01, 2, 2, 0, 0];
    for (name, kind, value) in attributes {
        b.extend_from_slice(name.as_bytes());
        b.push(0);
        b.extend_from_slice(kind.as_bytes());
        b.push(0);
        b.extend_from_slice(&(value.len() as i32).to_le_bytes());
        b.extend_from_slice(value);
    }
    b.push(0);
    b
}

#[test]
fn an_exr_tile_larger_than_its_image_is_refused_before_decoding() {
    let window = [0i32, 0, 7, 3].iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<u8>>();
    let tiles = |w: u32, h: u32| [w.to_le_bytes(), h.to_le_bytes()].concat().into_iter().chain([0u8]).collect();
    let forged = exr_header(&[("dataWindow", "box2i", window.clone()), ("tiles", "tiledesc", tiles(64, 2_621_504))]);
    let e = check_exr_tiles(&forged).unwrap_err();
    assert!(e.contains("larger than its image"), "{e}");
    // Ordinary tiles, even larger than a small image, pass.
    assert!(
        check_exr_tiles(&exr_header(&[("dataWindow", "box2i", window), ("tiles", "tiledesc", tiles(64, 64))])).is_ok()
    );
    // And a real scanline file written by the image crate decodes.
    let mut exr = Vec::new();
    image::Rgb32FImage::from_pixel(3, 2, image::Rgb([0.5, 1.5, 2.5]))
        .write_to(&mut std::io::Cursor::new(&mut exr), image::ImageFormat::OpenExr)
        .unwrap();
    assert!(check_exr_tiles(&exr).is_ok());
    assert!(crate::envmap::EnvironmentMap::decode(&exr, 0.0).is_ok());
}
