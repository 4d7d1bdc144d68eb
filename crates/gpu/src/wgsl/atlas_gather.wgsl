// The atlas's gather on the device: `GatherProblem::gather` of
// crates/tracer/src/integrator/atlas.rs, one invocation per texel that lies on a triangle,
// over the sample range [first, end) of its Hammersley points (a dispatch per range, so
// that no invocation runs long; the sums carry over in `pt_gather_sums`). The host scales
// the sums by the estimator's factor and dilates them into the gutter, as the CPU does.
// Compiled in with the atlas integrator only; its own bind group (1).

struct PtGather {
    count: u32,
    samples: u32,
    first: u32,
    end: u32,
    density: f32,
    min_r2: f32,
    visibility: u32,
    // Invocations per row of workgroups (the dispatch is 2-D past the device's limit).
    row: u32,
}

@group(1) @binding(0) var<uniform> pt_gather: PtGather;
// Per texel five vec4s: (position, direct r), (normal, direct g), (chart u, direct b),
// (chart v, 0), (shift, 0, 0).
@group(1) @binding(1) var<storage, read> pt_gather_texels: array<vec4f>;
@group(1) @binding(2) var<storage, read_write> pt_gather_sums: array<vec4f>;

// The i-th of n points of the 2-D Hammersley set (`atlas::hammersley`).
fn pt_hammersley(i: u32, n: u32) -> vec2f {
    return vec2f(f32(i) / f32(n), f32(reverseBits(i)) * 2.3283064365386963e-10);
}

@compute @workgroup_size(64, 1, 1)
fn pt_atlas_gather(@builtin(global_invocation_id) gid: vec3u) {
    let k = gid.x + gid.y * pt_gather.row;
    let used = pt_gather.count;
    if k >= used {
        return;
    }
    let x_pos = pt_gather_texels[5u * k].xyz;
    let x_normal = pt_gather_texels[5u * k + 1u].xyz;
    let shift = pt_gather_texels[5u * k + 4u].xy;
    var sum = pt_gather_sums[k].xyz;
    let origin = pt_offset_ray_origin(x_pos, x_normal);
    for (var s = pt_gather.first; s < pt_gather.end; s++) {
        var a = pt_hammersley(s, pt_gather.samples) + shift;
        a -= floor(a);
        let pick = a.x * f32(used);
        let slot = min(u32(pick), used - 1u);
        if slot == k {
            continue;
        }
        let y0 = pt_gather_texels[5u * slot];
        let y1 = pt_gather_texels[5u * slot + 1u];
        let y2 = pt_gather_texels[5u * slot + 2u];
        let y3 = pt_gather_texels[5u * slot + 3u];
        let b = vec3f(y0.w, y1.w, y2.w);
        if all(b == vec3f(0.0)) {
            continue;
        }
        // The drawn point: the texel's position moved within the texel along its chart's
        // axes (by the first coordinate's remainder and the second).
        let within = (vec2f(pick - f32(slot), a.y) - 0.5) / pt_gather.density;
        let py = y0.xyz + within.x * y2.xyz + within.y * y3.xyz;
        let d = py - x_pos;
        let r2 = max(dot(d, d), pt_gather.min_r2);
        let r = sqrt(r2);
        let cos_x = dot(x_normal, d) / r;
        let cos_y = -dot(y1.xyz, d) / r;
        if cos_x <= 0.0 || cos_y <= 0.0 {
            continue;
        }
        if pt_gather.visibility != 0u {
            let to = pt_offset_ray_origin(py, y1.xyz);
            if pt_trace(origin, to - origin, 0.0, PT_SHADOW_T_MAX, true).prim != PT_NO_HIT {
                continue;
            }
        }
        sum += b * (cos_x * cos_y / r2);
    }
    pt_gather_sums[k] = vec4f(sum, 0.0);
}
