// The biased integrators, mirroring crates/tracer/src/integrator/simple.rs: direct
// lighting (`DirectLighting`: emission seen by the camera plus one light sample at the
// first surface, no MIS) and ambient occlusion (`AmbientOcclusion`: whether a
// cosine-distributed direction above the first surface reaches `ao_distance`, as a grey
// of D65 white at luminance 1). They draw the CPU's random numbers in the CPU's order.

fn pt_direct(origin: vec3f, dir: vec3f, wl: PtWavelengths, smp: ptr<function, PtSampler>, rays: ptr<function, u32>) -> vec4f {
    let lambda = wl.lambda;
    *rays += 1u;
    let hit = pt_trace(origin, dir, 0.0, PT_FAR, false);
    if hit.prim == PT_NO_HIT {
        // `SceneView::escaped_radiance`: the environment and any sun disk.
        var env = vec4f(0.0);
        if (pt_params.scene_flags & PT_HAS_ENVIRONMENT) != 0u {
            env = pt_env_radiance(dir, lambda);
        }
        return env + pt_suns_seen(dir, lambda, 0.0, false);
    }
    var sf: PtSurface;
    let uv = pt_hit_surface(hit, origin, dir, &sf);
    let wo_world = -dir;
    var l = vec4f(0.0);
    if dot(wo_world, sf.ng) > 0.0 {
        l += pt_emission_at(sf.m, uv, lambda);
    }
    pt_set_texels(sf.m, uv, lambda);
    let two_sided = material_two_sided(sf.m);
    if pt_is_non_specular(material_flags(sf.m)) {
        let e = pt_next_event(pt_shading(sf, wo_world, two_sided), lambda, pt_next_2d(smp), false, rays);
        if e.valid {
            l += e.f * e.le * e.k;
        }
    }
    return l;
}

fn pt_ambient_occlusion(
    origin: vec3f,
    dir: vec3f,
    wl: PtWavelengths,
    smp: ptr<function, PtSampler>,
    rays: ptr<function, u32>,
) -> vec4f {
    *rays += 1u;
    let hit = pt_trace(origin, dir, 0.0, PT_FAR, false);
    if hit.prim == PT_NO_HIT {
        return vec4f(0.0);
    }
    var sf: PtSurface;
    _ = pt_hit_surface(hit, origin, dir, &sf);
    // The hemisphere on the viewer's side.
    let side = select(-1.0, 1.0, dot(dir, sf.ng) < 0.0);
    let ng = sf.ng * side;
    var ns = sf.ns * side;
    if dot(ns, ng) <= 0.0 {
        ns = ng;
    }
    let wi = pt_to_world(pt_frame_from_normal_tangent(ns, sf.tangent), mat_cosine_hemisphere(pt_next_2d(smp)));
    if dot(wi, ng) <= 0.0 {
        // A shading normal tilted the sample under the surface: it is blocked.
        return vec4f(0.0);
    }
    let o = pt_offset_ray_origin(sf.p, ng);
    *rays += 1u;
    if pt_trace(o, wi, 0.0, pt_params.ao_distance, true).prim != PT_NO_HIT {
        return vec4f(0.0);
    }
    return pt_table_spectrum(pt_params.white_offset, wl.lambda);
}
