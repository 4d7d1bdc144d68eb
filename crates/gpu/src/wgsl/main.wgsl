// The entry point, mirroring crates/tracer/src/cpu.rs (a pixel's samples in order),
// camera.rs (the ray through a jittered film position) and film.rs (Welford): one
// invocation per pixel of the band, `samples` samples each, added to the pixel's running
// count / mean / M2 in f32 (merged into the film's f64 statistics on the CPU after the
// pass).

@compute @workgroup_size(8, 8, 1)
fn pt_main(@builtin(global_invocation_id) gid: vec3u) {
    if gid.x >= pt_params.width || gid.y >= pt_params.band_rows {
        return;
    }
    let x = gid.x;
    let y = pt_params.band_y0 + gid.y;
    let pixel = y * pt_params.width + x;
    let slot = gid.y * pt_params.width + x;
    var acc = pt_film.pixels[slot];
    var rays = 0u;
    var truncated = 0u;
    for (var k = 0u; k < pt_params.samples; k++) {
        var smp = pt_sampler_for(x, y, pixel, pt_params.first_sample + k);
        let cam = pt_camera(&smp, !PT_RGB);
        var wl: PtWavelengths;
        if PT_RGB {
            wl = pt_rgb_wavelengths();
        } else {
            wl = pt_sample_hero(cam.x);
        }
        let jitter = cam.yz;
        let film = vec2f(f32(x), f32(y)) + jitter;
        let ndc = vec2f(2.0 * film.x * pt_params.inv_size.x - 1.0, 1.0 - 2.0 * film.y * pt_params.inv_size.y);
        let dir = normalize(pt_params.forward.xyz + ndc.x * pt_params.right.xyz + ndc.y * pt_params.up.xyz);
        // The integrator is a constant: the others' branches compile away.
        var l: vec4f;
        if PT_INTEGRATOR == PT_INTEGRATOR_DIRECT {
            l = pt_direct(pt_params.eye.xyz, dir, wl, &smp, &rays);
        } else if PT_INTEGRATOR == PT_INTEGRATOR_AO {
            l = pt_ambient_occlusion(pt_params.eye.xyz, dir, wl, &smp, &rays);
        } else {
            l = pt_radiance(pt_params.eye.xyz, dir, &wl, &smp, &rays, &truncated);
        }
        let rgb = pt_to_linear_srgb(l, wl);
        if pt_is_finite3(rgb) {
            acc.count += 1u;
            let delta = rgb - acc.mean;
            acc.mean += delta / f32(acc.count);
            acc.m2 += delta * (rgb - acc.mean);
        } else {
            acc.non_finite += 1u;
        }
    }
    pt_film.pixels[slot] = acc;
    // A 64-bit ray counter from two words: a carry whenever the low word wraps.
    let old = atomicAdd(&pt_film.rays_lo, rays);
    if old + rays < old {
        atomicAdd(&pt_film.rays_hi, 1u);
    }
    if truncated > 0u {
        atomicAdd(&pt_film.truncated, truncated);
    }
}
