// The path tracer, mirroring crates/tracer/src/integrator.rs (`PathTracer`) for N = 4:
// next-event estimation with one light sample and power-heuristic MIS, BSDF-sampled
// continuation, Russian roulette, hero-wavelength transport (collapsing to one
// wavelength at dispersive surfaces) and Beer–Lambert absorption along every segment
// inside absorbing glass (`segment_transmittance`, `entered_medium`, `shadow_absorption`).

fn pt_power_heuristic(a: f32, b: f32) -> f32 {
    let a2 = a * a;
    let b2 = b * b;
    if a2 + b2 == 0.0 {
        return 0.0;
    }
    return a2 / (a2 + b2);
}

fn pt_is_specular(f: u32) -> bool {
    return (f & SCATTER_SPECULAR) != 0u;
}

fn pt_is_non_specular(f: u32) -> bool {
    return (f & (SCATTER_DIFFUSE | SCATTER_GLOSSY)) != 0u;
}

// `lobe_leaks`: whether a sampled lobe disagrees with the geometry (a reflection must stay
// on ω_o's side of the surface, a transmission cross it — face-forwarded normals exempt —
// and a two-sided surface never transmits).
fn pt_lobe_leaks(ng: vec3f, wo_world: vec3f, wi_world: vec3f, flags: u32, two_sided: bool) -> bool {
    let crosses = dot(wi_world, ng) * dot(wo_world, ng) <= 0.0;
    let transmits = (flags & SCATTER_TRANSMISSION) != 0u;
    return (crosses != transmits && pt_params.shading != PT_SHADING_FACE_FORWARD) || (two_sided && crosses);
}

// A surface hit: position from the vertices, geometric and shading normals, tangent
// (`SceneView::interaction`), and the primitive's material, light pmf and area. A shape's
// surface is its intersection with the ray (o, d) again: the same root as in the traversal
// (an implicit surface's: its point at the traversal's t, `pt_shape_surface`). `prim` is
// the CPU's primitive id (an object's own for a placed object's triangle).
struct PtSurface {
    p: vec3f,
    ng: vec3f,
    ns: vec3f,
    tangent: vec3f,
    m: u32,
    prim_pmf: f32,
    area: f32,
    prim: u32,
}

fn pt_surface(hit: PtHit, o: vec3f, d: vec3f) -> PtSurface {
    if pt_is_shape(hit.prim) {
        let rec = hit.prim & ~PT_SHAPE_PRIM_BIT;
        let h = pt_shape_surface(rec, o, d, hit.t);
        return PtSurface(h.p, h.n, h.n, vec3f(0.0), pt_tu(rec + 1u), pt_tables[rec + 2u], pt_tables[rec + 3u],
            pt_tu(rec + 4u));
    }
    let i = hit.prim;
    // (A placed object's vertices are taken into world space first, as on the CPU.)
    let v = pt_hit_triangle(hit);
    let b0 = 1.0 - hit.u - hit.v;
    let p = b0 * v[0] + hit.u * v[1] + hit.v * v[2];
    let cr = cross(v[1] - v[0], v[2] - v[0]);
    let area = 0.5 * length(cr);
    let it_ng = cr / (2.0 * area) * pt_instance_orientation(hit);
    var it_ns = it_ng;
    var tangent = vec3f(0.0);
    let flags_scene = pt_params.scene_flags;
    if (flags_scene & (PT_HAS_NORMALS | PT_HAS_TANGENTS)) != 0u {
        let vi = pt_tri_vidx[i];
        if (flags_scene & PT_HAS_NORMALS) != 0u && pt_params.shading != PT_SHADING_GEOMETRIC {
            let n_obj = b0 * pt_attrs[2u * vi.x].xyz + hit.u * pt_attrs[2u * vi.y].xyz + hit.v * pt_attrs[2u * vi.z].xyz;
            let n = pt_instance_normal(hit, n_obj);
            if dot(n, n) > 1e-12 {
                let nn = normalize(n);
                it_ns = select(nn, -nn, dot(nn, it_ng) < 0.0);
            }
        }
        if (flags_scene & PT_HAS_TANGENTS) != 0u {
            let t_obj = b0 * pt_attrs[2u * vi.x + 1u].xyz + hit.u * pt_attrs[2u * vi.y + 1u].xyz
                + hit.v * pt_attrs[2u * vi.z + 1u].xyz;
            tangent = pt_instance_tangent(hit, t_obj);
        }
    }
    let m = pt_instance_material(hit, bitcast<u32>(pt_tri_verts[3u * i].w));
    return PtSurface(p, it_ng, it_ns, tangent, m, pt_tri_verts[3u * i + 1u].w, area,
        bitcast<u32>(pt_tri_verts[3u * i + 2u].w));
}

// The surface of `hit` on the ray (o, d) with its texture coordinates (returned) and the
// shading normal bent by a normal or bump map (`SceneView::interaction`).
fn pt_hit_surface(hit: PtHit, o: vec3f, d: vec3f, sf: ptr<function, PtSurface>) -> vec2f {
    *sf = pt_surface(hit, o, d);
    var uv = vec2f(0.0);
    if PT_HAS_TEXTURES {
        uv = pt_hit_uv(hit);
        pt_bend_normal(sf, hit, uv);
    }
    return uv;
}

// Beer–Lambert (`segment_transmittance`): what is left after a segment of length `t` that
// arrived at material `m` (from the `front` or not) having left its last vertex into the
// absorbing material `inside` (PT_NO_HIT: none). The segment ran inside absorbing glass if
// it arrived at the back of one or left into one (directions are unit length, so t is the
// distance).
fn pt_segment_transmittance(m: u32, front: bool, two_sided: bool, inside: u32, t: f32, lambda: vec4f) -> vec4f {
    var medium = inside;
    if !front && !two_sided && material_absorbing(m) {
        medium = m;
    }
    if medium != PT_NO_HIT {
        return exp(-material_absorption(medium, lambda) * t);
    }
    return vec4f(1.0);
}

// The throughput a camera path starts with (RGB mode: three channels; the fourth lane
// carries nothing).
fn pt_unit_throughput() -> vec4f {
    return select(vec4f(1.0), vec4f(1.0, 1.0, 1.0, 0.0), PT_RGB);
}

// Integrators whose paths branch or look up light per wavelength set (Whitted, the atlas)
// collapse to one wavelength up front in scenes with dispersive glass (as the CPU's do).
fn pt_collapse_if_dispersive(wl: ptr<function, PtWavelengths>, smp: ptr<function, PtSampler>) {
    if (pt_params.scene_flags & PT_HAS_DISPERSION) != 0u && !PT_RGB && !(*wl).collapsed {
        pt_collapse_wavelengths(wl, min(u32(pt_next_1d(smp) * 4.0), 3u));
    }
}

// A surface point ready for light sampling (`Shading` in integrator.rs): the surface, its
// shading frame, the geometric normal facing the way the shading normals were reconciled,
// ω_o in world and local coordinates, and whether the material is two-sided.
struct PtShading {
    sf: PtSurface,
    frame: PtFrame,
    ng: vec3f,
    wo_world: vec3f,
    wo: vec3f,
    two_sided: bool,
}

// The shading normals, frame and local ω_o of a hit seen from `wo_world` (the integrators'
// common set-up before light sampling and BSDF sampling).
fn pt_shading(sf: PtSurface, wo_world: vec3f, two_sided: bool) -> PtShading {
    let sn = pt_shading_normals(sf.ng, sf.ns, wo_world, two_sided);
    let frame = pt_frame_from_normal_tangent(sn.ns, sf.tangent);
    return PtShading(sf, frame, sn.ng, wo_world, pt_to_local(frame, wo_world), two_sided);
}

// Next-event estimation (`next_event`): one light sample from `u`, its shadow ray, and
// the contribution as f, Le and the factor |cos θi| · w / pdf, with `mis` the power
// heuristic's w against the BSDF's pdf, else w = 1.
struct PtNextEvent {
    f: vec4f,
    le: vec4f,
    k: f32,
    valid: bool,
}

fn pt_next_event(at: PtShading, lambda: vec4f, u: vec2f, mis: bool, rays: ptr<function, u32>) -> PtNextEvent {
    let ls = pt_sample_light_at(u, at.sf.p, at.sf.ng);
    if !ls.valid {
        return PtNextEvent(vec4f(0.0), vec4f(0.0), 0.0, false);
    }
    return pt_light_contribution(at, lambda, ls, mis, rays);
}

// A light sample's contribution (`light_contribution`): its shadow ray, and f, Le and
// |cos θi| · w / pdf.
fn pt_light_contribution(
    at: PtShading,
    lambda: vec4f,
    ls: PtLightSample,
    mis: bool,
    rays: ptr<function, u32>,
) -> PtNextEvent {
    var out = PtNextEvent(vec4f(0.0), vec4f(0.0), 0.0, false);
    let sf = at.sf;
    let m = sf.m;
    let p = sf.p;
    var wi_world: vec3f;
    var finite_light = true;
    var dist = 0.0;
    var light_pdf = 0.0;
    var le = vec4f(0.0);
    var delta = false;
    if ls.kind == PT_LIGHT_TRIANGLE || ls.kind == PT_LIGHT_SHAPE {
        let dl = ls.point - p;
        let dist2 = dot(dl, dl);
        dist = sqrt(dist2);
        wi_world = dl / dist;
        let cos_l = -dot(wi_world, ls.normal);
        if cos_l > 0.0 {
            light_pdf = ls.pdf * dist2 / cos_l;
            le = material_emission(ls.material, lambda);
        }
    } else if ls.kind == PT_LIGHT_ENVIRONMENT {
        wi_world = ls.point;
        finite_light = false;
        light_pdf = ls.pdf;
        if (pt_params.scene_flags & PT_HAS_ENVIRONMENT) != 0u {
            le = pt_env_radiance(wi_world, lambda);
        }
    } else if PT_HAS_PUNCTUAL {
        // A delta light: I·falloff/d² (or E) stands for the radiance and the pdf is the
        // probability of choosing it.
        let inc = pt_punctual_incidence(ls, p, lambda);
        if !inc.valid {
            return out;
        }
        wi_world = inc.wi;
        dist = inc.dist;
        finite_light = inc.dist < PT_FAR;
        light_pdf = ls.pdf;
        le = inc.le;
        delta = inc.delta;
    }
    let wi = pt_to_local(at.frame, wi_world);
    // Reflection must stay on the geometric side it came from (no light leaks).
    let same_side = dot(wi_world, at.ng) * dot(at.wo_world, at.ng) > 0.0;
    if !(light_pdf > 0.0 && any(le != vec4f(0.0)) && (same_side || !at.two_sided)) {
        return out;
    }
    let f = bsdf_eval(m, at.wo, wi, lambda);
    if all(f == vec4f(0.0)) {
        return out;
    }
    // A shadow ray into the back of absorbing glass runs inside it (Beer–Lambert), and
    // never reaches a light at infinity.
    if material_absorbing(m) && !at.two_sided && dot(wi_world, sf.ng) < 0.0 {
        if !finite_light {
            return out;
        }
        le *= exp(-material_absorption(m, lambda) * dist);
    }
    let off = pt_offset_ray_origin(p, select(-sf.ng, sf.ng, dot(wi_world, sf.ng) > 0.0));
    *rays += 1u;
    // (One trace for both kinds of light: every call site is a copy of the traversal in the
    // compiled kernel.)
    let shadow_dir = select(wi_world, ls.point - off, finite_light);
    let shadow_t_max = select(PT_FAR, PT_SHADOW_T_MAX, finite_light);
    if pt_trace(off, shadow_dir, 0.0, shadow_t_max, true).prim != PT_NO_HIT {
        return out;
    }
    var w = 1.0;
    if mis && !delta {
        w = pt_power_heuristic(light_pdf, bsdf_pdf(m, at.wo, wi, lambda));
    }
    return PtNextEvent(f, le, abs(wi.z) * w / light_pdf, true);
}

// `SampledWavelengths::collapse_to`: lane `k` moved to lane 0, the only one left, its
// weight multiplied by the lane count.
fn pt_collapse_wavelengths(wl: ptr<function, PtWavelengths>, k: u32) {
    let lk = (*wl).lambda[k];
    (*wl).lambda[k] = (*wl).lambda[0];
    (*wl).lambda[0] = lk;
    (*wl).weight = vec4f((*wl).weight[k] * 4.0, 0.0, 0.0, 0.0);
    (*wl).collapsed = true;
}

// What a path escaping along `d` sees of the lights at infinity (the environment and sun
// disks), each weighted by the power heuristic against next-event estimation when the
// last scattering was not a delta (of BSDF pdf `prev_pdf`).
fn pt_escaped(d: vec3f, lambda: vec4f, prev_pdf: f32, prev_specular: bool) -> vec4f {
    var l = vec4f(0.0);
    if (pt_params.scene_flags & PT_HAS_ENVIRONMENT) != 0u {
        var w = 1.0;
        if !prev_specular {
            w = pt_power_heuristic(prev_pdf, pt_env_pdf(d));
        }
        l = pt_env_radiance(d, lambda) * w;
    }
    return l + pt_suns_seen(d, lambda, prev_pdf, !prev_specular);
}

fn pt_radiance(
    origin: vec3f,
    dir: vec3f,
    wl: ptr<function, PtWavelengths>,
    smp: ptr<function, PtSampler>,
    rays: ptr<function, u32>,
    truncated: ptr<function, u32>,
) -> vec4f {
    var o = origin;
    var d = dir;
    var l = vec4f(0.0);
    var beta = pt_unit_throughput();
    // η'² over the transmissions so far, which Russian roulette undoes (the CPU's
    // `eta_scale`).
    var eta_scale = 1.0;
    // The pdf of the previous BSDF sample, and whether it was a delta (no MIS then).
    var prev_pdf = 0.0;
    var prev_specular = true;
    var prev_p = origin;
    // The previous vertex's geometric normal, which a light tree's estimate reads (the
    // CPU's `PathState::prev_n`).
    var prev_n = vec3f(0.0);
    var bounce = 0u;
    var extension_left = pt_params.specular_extension;
    // Non-specular hits so far, against `max_diffuse_depth` (the CPU's `diffuse_bounces`).
    var diffuse_bounces = 0u;
    // The absorbing material the last segment left its vertex into (PT_NO_HIT: none).
    var inside = PT_NO_HIT;
    loop {
        *rays += 1u;
        let hit = pt_trace(o, d, 0.0, PT_FAR, false);
        if hit.prim == PT_NO_HIT {
            l += beta * pt_escaped(d, (*wl).lambda, prev_pdf, prev_specular);
            break;
        }

        var sf: PtSurface;
        let uv = pt_hit_surface(hit, o, d, &sf);
        let m = sf.m;
        let wo_world = -d;
        let front = dot(wo_world, sf.ng) > 0.0;
        let two_sided = material_two_sided(m);

        beta *= pt_segment_transmittance(m, front, two_sided, inside, hit.t, (*wl).lambda);

        // Emission seen by this path (one-sided: front face only).
        if front {
            let le = pt_emission_at(m, uv, (*wl).lambda);
            if any(le != vec4f(0.0)) {
                var w = 1.0;
                if !prev_specular {
                    let dp = sf.p - prev_p;
                    let dist2 = dot(dp, dp);
                    let cos_l = dot(wo_world, sf.ng);
                    let light_pdf = pt_emitter_pmf(sf, prev_p, prev_n) * dist2 / (cos_l * sf.area);
                    w = pt_power_heuristic(prev_pdf, light_pdf);
                }
                l += beta * le * w;
            }
        }

        if pt_params.max_depth > 0u && bounce >= pt_params.max_depth {
            // Past the limit, continue only through purely specular surfaces, while the
            // extension lasts.
            let f = material_flags(m);
            if extension_left == 0u || !pt_is_specular(f) || pt_is_non_specular(f) {
                break;
            }
            extension_left -= 1u;
        }
        // A non-specular hit one more than `max_diffuse_depth` allows ends the path (its
        // emission counted), as the CPU's `diffuse_limit_reached` does.
        if pt_params.max_diffuse_depth > 0u && pt_is_non_specular(material_flags(m)) {
            diffuse_bounces += 1u;
            if diffuse_bounces > pt_params.max_diffuse_depth {
                break;
            }
        }

        // Dispersion: from here on the path follows one wavelength (a random lane, moved
        // to lane 0).
        if material_dispersive(m) && !(*wl).collapsed {
            let k = min(u32(pt_next_1d(smp) * 4.0), 3u);
            pt_collapse_wavelengths(wl, k);
            let bk = beta[k];
            beta[k] = beta[0];
            beta[0] = bk;
            let lk2 = l[k];
            l[k] = l[0];
            l[0] = lk2;
            beta = vec4f(beta[0], 0.0, 0.0, 0.0);
        }
        let lambda = (*wl).lambda;
        // The texels the BSDF calls of this hit read (`Material::bsdf_at`).
        pt_set_texels(m, uv, lambda);

        let at = pt_shading(sf, wo_world, two_sided);
        let flags = material_flags(m);

        // Next-event estimation: one shadow ray to a point on a light.
        if pt_is_non_specular(flags) {
            let e = pt_next_event(at, lambda, pt_next_2d(smp), true, rays);
            if e.valid {
                l += beta * e.f * e.le * e.k;
            }
        }

        // Continue the path by sampling the BSDF.
        let uc = pt_next_1d(smp);
        let u = pt_next_2d(smp);
        let s = bsdf_sample(m, at.wo, uc, u, lambda);
        if s.pdf <= 0.0 || all(s.f == vec4f(0.0)) {
            break;
        }
        let wi_world = pt_to_world(at.frame, s.wi);
        // The sampled lobe must agree with the geometry.
        if pt_lobe_leaks(sf.ng, wo_world, wi_world, s.flags, two_sided) {
            break;
        }
        beta *= s.f * (abs(s.wi.z) / s.pdf);
        if (s.flags & SCATTER_TRANSMISSION) != 0u {
            let eta = material_eta(m);
            let etap = select(1.0 / eta, eta, at.wo.z > 0.0);
            eta_scale *= etap * etap;
        }
        prev_pdf = s.pdf;
        prev_specular = pt_is_specular(s.flags);
        prev_p = sf.p;
        prev_n = sf.ng;
        inside = select(PT_NO_HIT, m, dot(wi_world, sf.ng) < 0.0 && !two_sided && material_absorbing(m));
        o = pt_offset_ray_origin(sf.p, select(-sf.ng, sf.ng, dot(wi_world, sf.ng) > 0.0));
        d = wi_world;
        bounce += 1u;

        // Russian roulette (Arvo & Kirk 1990), judged by the throughput times η'² and rr_scale (the CPU's).
        if bounce >= pt_params.rr_depth {
            let q = max(1.0 - max(max(beta.x, beta.y), max(beta.z, beta.w)) * eta_scale * pt_params.rr_scale, PT_RR_MIN_TERMINATION);
            if pt_next_1d(smp) < q {
                break;
            }
            beta /= 1.0 - q;
        }
        if all(beta == vec4f(0.0)) {
            break;
        }
        // The hard cap (also for an unbounded max_depth): counted, so that it is never silent.
        if bounce >= PT_MAX_BOUNCES {
            *truncated += 1u;
            break;
        }
    }
    return l;
}
