// Whitted ray tracing, mirroring crates/tracer/src/integrator/whitted.rs (`Whitted`): at a
// purely specular surface the ray splits into its reflected and refracted parts weighted
// by the exact Fresnel terms; elsewhere every punctual light by its own shadow ray plus one
// sample of the area lights and the environment (no MIS), and the branch ends. The CPU
// recurses; here the tree is walked depth first with an explicit stack (the second lobe
// pushed, the first followed), which visits the branches, and draws the sample values, in
// the CPU's order. A branch carries the product of its ancestors' lobe weights and
// Beer–Lambert attenuations, so each vertex adds its own emission and direct light times
// that product — the CPU's (emission + direct + Σ weight · child) · attenuation, unrolled.

// A branch waiting on the stack: its ray, throughput, depth and the absorbing material
// its ray left into (PT_NO_HIT: none).
struct PtBranch {
    o: vec3f,
    depth: u32,
    d: vec3f,
    inside: u32,
    beta: vec4f,
}

fn pt_whitted(
    origin: vec3f,
    dir: vec3f,
    wl: ptr<function, PtWavelengths>,
    smp: ptr<function, PtSampler>,
    rays: ptr<function, u32>,
) -> vec4f {
    // Dispersive glass: one wavelength for the whole tree (its branches must share it).
    pt_collapse_if_dispersive(wl, smp);
    let lambda = (*wl).lambda;
    let max_depth = select(PT_WHITTED_DEFAULT_DEPTH, pt_params.max_depth, pt_params.max_depth > 0u);
    var stack: array<PtBranch, PT_WHITTED_STACK>;
    var top = 0u;
    var br = PtBranch(origin, 0u, dir, PT_NO_HIT, pt_unit_throughput());
    var l = vec4f(0.0);
    loop {
        // Follow `br`; `more` says whether it split and continues into its first lobe.
        var more = false;
        *rays += 1u;
        let hit = pt_trace(br.o, br.d, 0.0, PT_FAR, false);
        if hit.prim == PT_NO_HIT {
            // `SceneView::escaped_radiance`: the environment and any sun disk.
            if (pt_params.scene_flags & PT_HAS_ENVIRONMENT) != 0u {
                l += br.beta * pt_env_radiance(br.d, lambda);
            }
            l += br.beta * pt_suns_seen(br.d, lambda, 0.0, false);
        } else {
            var sf: PtSurface;
            let uv = pt_hit_surface(hit, br.o, br.d, &sf);
            let m = sf.m;
            let wo_world = -br.d;
            let front = dot(wo_world, sf.ng) > 0.0;
            let two_sided = material_two_sided(m);
            // Beer–Lambert (`segment_transmittance`), on everything this vertex returns.
            br.beta *= pt_segment_transmittance(m, front, two_sided, br.inside, hit.t, lambda);
            if front {
                l += br.beta * pt_emission_at(m, uv, lambda);
            }
            if br.depth < max_depth {
                pt_set_texels(m, uv, lambda);
                let at = pt_shading(sf, wo_world, two_sided);
                if pt_is_non_specular(material_flags(m)) {
                    // Every punctual light deterministically (probability 1 each; a sun disk
                    // by one direction drawn within it)…
                    if PT_HAS_PUNCTUAL {
                        for (var k = pt_params.punctual_first; k < pt_params.light_count; k++) {
                            var u = vec2f(0.0);
                            if pt_punctual_has_disk(k) {
                                u = pt_next_2d(smp);
                            }
                            let ls = pt_sample_punctual(k, u, 1.0);
                            let e = pt_light_contribution(at, lambda, ls, false, rays);
                            if e.valid {
                                l += br.beta * e.f * e.le * e.k;
                            }
                        }
                    }
                    // …and one sample of the rest: a punctual light drawn here counts zero.
                    if pt_params.punctual_first > 0u || pt_params.env_pmf > 0.0 {
                        let ls = pt_sample_light(pt_next_2d(smp));
                        if ls.valid && (ls.kind == PT_LIGHT_TRIANGLE || ls.kind == PT_LIGHT_SHAPE
                            || ls.kind == PT_LIGHT_ENVIRONMENT) {
                            let e = pt_light_contribution(at, lambda, ls, false, rays);
                            if e.valid {
                                l += br.beta * e.f * e.le * e.k;
                            }
                        }
                    }
                } else {
                    // Purely specular: uc at either end of [0, 1) picks each lobe
                    // (reflection below the Fresnel reflectance, transmission above).
                    let a = bsdf_sample(m, at.wo, 0.0, vec2f(0.0), lambda);
                    let b = bsdf_sample(m, at.wo, PT_ONE_MINUS_EPSILON, vec2f(0.0), lambda);
                    let one_lobe = a.pdf > 0.0 && b.pdf > 0.0 && a.flags == b.flags;
                    let split = b.pdf > 0.0 && !one_lobe;
                    let first = pt_whitted_child(br, at, a, split);
                    if split {
                        let second = pt_whitted_child(br, at, b, true);
                        if second.depth != PT_NO_HIT {
                            stack[top] = second;
                            top += 1u;
                        }
                    }
                    if first.depth != PT_NO_HIT {
                        br = first;
                        more = true;
                    }
                }
            }
        }
        if !more {
            if top == 0u {
                break;
            }
            top -= 1u;
            br = stack[top];
        }
    }
    return l;
}

// The branch a specular lobe sample `s` starts at `sf` (depth PT_NO_HIT: none — no sample,
// black, or a lobe the geometry disagrees with, `lobe_leaks`). A split lobe's weight is
// f·|cos θ| (both are followed), a single one's f·|cos θ|/pdf.
fn pt_whitted_child(br: PtBranch, at: PtShading, s: BsdfSample, split: bool) -> PtBranch {
    let sf = at.sf;
    let m = sf.m;
    var out = br;
    out.depth = PT_NO_HIT;
    if s.pdf <= 0.0 || all(s.f == vec4f(0.0)) {
        return out;
    }
    let wi_world = pt_to_world(at.frame, s.wi);
    if pt_lobe_leaks(sf.ng, at.wo_world, wi_world, s.flags, at.two_sided) {
        return out;
    }
    let weight = select(s.f * (abs(s.wi.z) / s.pdf), s.f * abs(s.wi.z), split);
    out.o = pt_offset_ray_origin(sf.p, select(-sf.ng, sf.ng, dot(wi_world, sf.ng) > 0.0));
    out.d = wi_world;
    out.beta = br.beta * weight;
    out.depth = br.depth + 1u;
    out.inside = select(PT_NO_HIT, m, dot(wi_world, sf.ng) < 0.0 && !at.two_sided && material_absorbing(m));
    return out;
}
