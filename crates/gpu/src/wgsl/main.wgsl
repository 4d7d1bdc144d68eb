// The entry point, mirroring crates/tracer/src/cpu.rs (a pixel's samples in order),
// camera.rs (the ray through a jittered film position) and film.rs (Welford): one
// invocation per pixel of the band, `samples` samples each, added to the pixel's running
// count / mean / M2 in f32 (merged into the film's f64 statistics on the CPU after the
// pass).

// One camera ray's radiance at the wavelengths `wl_in`, in linear sRGB. The integrator is
// a constant: the others' branches compile away.
fn pt_trace_sample(
    dir: vec3f,
    wl_in: PtWavelengths,
    smp: ptr<function, PtSampler>,
    rays: ptr<function, u32>,
    truncated: ptr<function, u32>,
) -> vec3f {
    var wl = wl_in;
    var l: vec4f;
    if PT_INTEGRATOR == PT_INTEGRATOR_DIRECT {
        l = pt_direct(pt_params.eye.xyz, dir, wl, smp, rays);
    } else if PT_INTEGRATOR == PT_INTEGRATOR_AO {
        l = pt_ambient_occlusion(pt_params.eye.xyz, dir, wl, smp, rays);
    } else if PT_INTEGRATOR == PT_INTEGRATOR_WHITTED {
        l = pt_whitted(pt_params.eye.xyz, dir, &wl, smp, rays);
    } else if PT_INTEGRATOR == PT_INTEGRATOR_ATLAS {
        l = pt_atlas(pt_params.eye.xyz, dir, &wl, smp, rays);
    } else if PT_INTEGRATOR == PT_INTEGRATOR_BDPT {
        l = pt_bdpt(pt_params.eye.xyz, dir, &wl, smp, rays, truncated);
    } else {
        l = pt_radiance(pt_params.eye.xyz, dir, &wl, smp, rays, truncated);
    }
    return pt_to_linear_srgb(l, wl);
}

// The camera ray's direction through film position (x, y) + `jitter` (camera.rs).
fn pt_camera_direction(x: u32, y: u32, jitter: vec2f) -> vec3f {
    let film = vec2f(f32(x), f32(y)) + jitter;
    let ndc = vec2f(2.0 * film.x * pt_params.inv_size.x - 1.0, 1.0 - 2.0 * film.y * pt_params.inv_size.y);
    return normalize(pt_params.forward.xyz + ndc.x * pt_params.right.xyz + ndc.y * pt_params.up.xyz);
}

// The pixel being rendered (bdpt reads it: a crop window's other columns must not splat).
var<private> pt_pixel: vec2u;

@compute @workgroup_size(8, 8, 1)
fn pt_main(@builtin(global_invocation_id) gid: vec3u) {
    if gid.x >= pt_params.width || gid.y >= pt_params.band_rows {
        return;
    }
    let x = gid.x;
    let y = pt_params.band_y0 + gid.y;
    let pixel = y * pt_params.width + x;
    let slot = gid.y * pt_params.width + x;
    pt_pixel = vec2u(x, y);
    var acc = pt_film.pixels[slot];
    var rays = 0u;
    var truncated = 0u;
    for (var k = 0u; k < pt_params.samples; k++) {
        var smp = pt_sampler_for(x, y, pixel, pt_params.first_sample + k);
        // Fixed wavelengths (RGB, bins40) draw no wavelength sample.
        let cam = pt_camera(&smp, !PT_RGB && !PT_BINS40);
        let dir = pt_camera_direction(x, y, cam.yz);
        var rgb = vec3f(0.0);
        if PT_BINS40 {
            // The 40 bins as ten paths of four, each from the same sample values: every one
            // estimates its four bins' share of the image without bias (the CPU carries all
            // 40 in one path), and the conversion to sRGB is linear in them.
            for (var g = 0u; g < 10u; g++) {
                var group = smp;
                rgb += pt_trace_sample(dir, pt_bins_wavelengths(g), &group, &rays, &truncated);
            }
        } else if PT_RGB {
            rgb = pt_trace_sample(dir, pt_rgb_wavelengths(), &smp, &rays, &truncated);
        } else {
            rgb = pt_trace_sample(dir, pt_sample_hero(cam.x), &smp, &rays, &truncated);
        }
        pt_film_add(&acc, rgb);
    }
    pt_film.pixels[slot] = acc;
    pt_film_count(rays, truncated);
}

// One sample's colour added to a pixel's running count / mean / M2 (Welford), or counted
// as non-finite.
fn pt_film_add(acc: ptr<function, PtPixel>, rgb: vec3f) {
    if pt_is_finite3(rgb) {
        (*acc).count += 1u;
        let delta = rgb - (*acc).mean;
        (*acc).mean += delta / f32((*acc).count);
        (*acc).m2 += delta * (rgb - (*acc).mean);
    } else {
        (*acc).non_finite += 1u;
    }
}

// Rays traced and paths truncated, added to the film's counters (the rays' 64-bit counter
// from two words: a carry whenever the low word wraps).
fn pt_film_count(rays: u32, truncated: u32) {
    let old = atomicAdd(&pt_film.rays_lo, rays);
    if old + rays < old {
        atomicAdd(&pt_film.rays_hi, 1u);
    }
    if truncated > 0u {
        atomicAdd(&pt_film.truncated, truncated);
    }
}
