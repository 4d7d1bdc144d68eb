// Atlas-based one-bounce global illumination, mirroring crates/tracer/src/integrator/atlas.rs
// (`AtlasGi::radiance`): the camera path follows mirrors and glass (at most
// PT_ATLAS_SPECULAR_CHAIN bounces), then at the first non-specular surface adds direct light
// (one light sample, no MIS) and one bounce of indirect light looked up in the atlas —
// the irradiance the CPU gathered per texel when the scene was prepared — times the
// surface's albedo from one BSDF sample.

fn pt_atlas_f(j: u32) -> f32 {
    return pt_tables[pt_params.atlas_offset + j];
}

fn pt_atlas_u(j: u32) -> u32 {
    return bitcast<u32>(pt_atlas_f(j));
}

// `Atlas::irradiance_at`: the gathered irradiance (linear sRGB) at `p` on primitive `prim`,
// bilinear between the four texels around it (those outside the atlas count zero); w < 0
// where the primitive has no chart.
fn pt_atlas_irradiance(prim: u32, p: vec3f) -> vec4f {
    if prim >= pt_atlas_u(8u) {
        return vec4f(-1.0);
    }
    let chart = bitcast<u32>(pt_tables[pt_atlas_u(3u) + prim]);
    if chart == PT_NO_HIT {
        return vec4f(-1.0);
    }
    let c = pt_atlas_u(4u) + 13u * chart;
    let origin = vec3f(pt_tables[c], pt_tables[c + 1u], pt_tables[c + 2u]);
    let u = vec3f(pt_tables[c + 3u], pt_tables[c + 4u], pt_tables[c + 5u]);
    let v = vec3f(pt_tables[c + 6u], pt_tables[c + 7u], pt_tables[c + 8u]);
    let lo = vec2f(pt_tables[c + 9u], pt_tables[c + 10u]);
    let corner = vec2f(pt_tables[c + 11u], pt_tables[c + 12u]);
    let d = p - origin;
    let local = vec2f(dot(d, u), dot(d, v)) - lo;
    let a = corner + local * pt_atlas_f(2u) - vec2f(0.5);
    let x0 = floor(a.x);
    let y0 = floor(a.y);
    let fx = a.x - x0;
    let fy = a.y - y0;
    let width = pt_atlas_u(0u);
    let height = pt_atlas_u(1u);
    let texels = pt_atlas_u(5u);
    var e = vec3f(0.0);
    for (var k = 0u; k < 4u; k++) {
        let dx = k & 1u;
        let dy = k >> 1u;
        let w = select(1.0 - fx, fx, dx == 1u) * select(1.0 - fy, fy, dy == 1u);
        let x = x0 + f32(dx);
        let y = y0 + f32(dy);
        if x < 0.0 || y < 0.0 || x >= f32(width) || y >= f32(height) {
            continue;
        }
        let t = texels + 3u * (u32(y) * width + u32(x));
        e += w * vec3f(pt_tables[t], pt_tables[t + 1u], pt_tables[t + 2u]);
    }
    return vec4f(e, 1.0);
}

// `irradiance_spectrum`: linear-sRGB irradiance at the path's wavelengths (uplifted as an
// illuminant: its largest component times the reflectance of RGB/max times D65).
fn pt_irradiance_spectrum(rgb: vec3f, lambda: vec4f) -> vec4f {
    if PT_RGB {
        return vec4f(rgb, 0.0);
    }
    let scale = max(max(max(0.0, rgb.x), rgb.y), rgb.z);
    if !(scale > 0.0) || !pt_is_finite3(vec3f(scale)) {
        return vec4f(0.0);
    }
    let reflectance = pt_reflectance(max(rgb, vec3f(0.0)) / scale, lambda);
    return reflectance * pt_d65_at(pt_atlas_u(6u), pt_atlas_f(7u), lambda) * scale;
}

fn pt_atlas(
    origin: vec3f,
    dir: vec3f,
    wl: ptr<function, PtWavelengths>,
    smp: ptr<function, PtSampler>,
    rays: ptr<function, u32>,
) -> vec4f {
    // Dispersive glass on the way: one wavelength per sample, as in Whitted.
    pt_collapse_if_dispersive(wl, smp);
    let lambda = (*wl).lambda;
    var l = vec4f(0.0);
    var beta = pt_unit_throughput();
    var o = origin;
    var d = dir;
    var inside = PT_NO_HIT;
    for (var bounce = 0u; bounce <= PT_ATLAS_SPECULAR_CHAIN; bounce++) {
        *rays += 1u;
        let hit = pt_trace(o, d, 0.0, PT_FAR, false);
        if hit.prim == PT_NO_HIT {
            if (pt_params.scene_flags & PT_HAS_ENVIRONMENT) != 0u {
                l += beta * pt_env_radiance(d, lambda);
            }
            return l + beta * pt_suns_seen(d, lambda, 0.0, false);
        }
        var sf: PtSurface;
        let uv = pt_hit_surface(hit, o, d, &sf);
        let m = sf.m;
        let wo_world = -d;
        let front = dot(wo_world, sf.ng) > 0.0;
        let two_sided = material_two_sided(m);
        beta *= pt_segment_transmittance(m, front, two_sided, inside, hit.t, lambda);
        if front {
            l += beta * pt_emission_at(m, uv, lambda);
        }
        pt_set_texels(m, uv, lambda);
        let at = pt_shading(sf, wo_world, two_sided);
        if pt_is_non_specular(material_flags(m)) {
            // Direct light, per pixel.
            let e = pt_next_event(at, lambda, pt_next_2d(smp), false, rays);
            if e.valid {
                l += beta * e.f * e.le * e.k;
            }
            // One bounce of indirect light from the atlas: E/π times the albedo (one BSDF
            // sample: f |cos| / pdf).
            let uc = pt_next_1d(smp);
            let u = pt_next_2d(smp);
            if front || !two_sided {
                let e_rgb = pt_atlas_irradiance(pt_hit_cpu_prim(hit), sf.p);
                if e_rgb.w >= 0.0 {
                    let s = bsdf_sample(m, at.wo, uc, u, lambda);
                    if s.pdf > 0.0 {
                        let wi_world = pt_to_world(at.frame, s.wi);
                        if !pt_lobe_leaks(sf.ng, wo_world, wi_world, s.flags, two_sided) {
                            let albedo = s.f * (abs(s.wi.z) / s.pdf);
                            l += beta * albedo * pt_irradiance_spectrum(e_rgb.xyz, lambda) * (1.0 / PT_PI);
                        }
                    }
                }
            }
            return l;
        }
        // A mirror or glass: follow it.
        let uc = pt_next_1d(smp);
        let s = bsdf_sample(m, at.wo, uc, pt_next_2d(smp), lambda);
        if s.pdf <= 0.0 || all(s.f == vec4f(0.0)) {
            return l;
        }
        let wi_world = pt_to_world(at.frame, s.wi);
        if pt_lobe_leaks(sf.ng, wo_world, wi_world, s.flags, two_sided) {
            return l;
        }
        beta *= s.f * (abs(s.wi.z) / s.pdf);
        inside = select(PT_NO_HIT, m, dot(wi_world, sf.ng) < 0.0 && !two_sided && material_absorbing(m));
        o = pt_offset_ray_origin(sf.p, select(-sf.ng, sf.ng, dot(wi_world, sf.ng) > 0.0));
        d = wi_world;
    }
    return l;
}
