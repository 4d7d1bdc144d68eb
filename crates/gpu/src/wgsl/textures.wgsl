// Textures, mirroring crates/tracer/src/texture.rs (`TextureMap::sample`, `reflectance_spectrum`,
// `MaterialTextures::texels`/`emission_scale`/`bent_normal`, `Alpha::passes`, `alpha_hash`),
// crates/spectral/src/uplift/table.rs (`UpliftTable::lookup`) and uplift.rs (`sigmoid`), and
// the texture parts of crates/tracer/src/integrator.rs (`SceneView::bend_normal`,
// `through_cutouts`, `uv_at`). Without textures (PT_HAS_TEXTURES false) none of it runs.
//
// Tables: a material's texture record (`pt_params.material_textures_offset` + m gives its
// offset, PT_NO_HIT for none) holds the offsets of its maps' descriptors (PT_NO_HIT where
// absent): +0 base colour, +1 specular, +2 metallic-roughness, +3 emissive, +4 normal (+5 its
// scale), +6 bump (+7 its scale), +8 alpha mode (0 opaque, 1 mask, 2 blend), +9 cut-off,
// +10 factor, +11 alpha map. A map descriptor: +0 first texel in `pt_texels` (bits), +1
// width, +2 height, +3/+4 wrap along u/v, +5 encoding (0 sRGB, 1 linear), +6 whether the
// image has alpha, +7 whether the transform is the identity, +8..+14 the transform's columns
// (x axis, y axis, translation; two floats each). Texels are RGBA8 words (red lowest).
//
// Differences from the CPU: texel coordinates are folded in i32 (coordinates beyond ±2^30
// texels lose their position; the CPU's i64 keeps them to ±10^12, where f32 has no fraction
// left anyway).

const PT_WRAP_REPEAT: u32 = 0u;
const PT_WRAP_CLAMP: u32 = 1u;
const PT_ALPHA_MASK: u32 = 1u;
const PT_ALPHA_BLEND: u32 = 2u;

// `Wrap::index`: texel index `i` folded into 0..n.
fn pt_wrap(mode: u32, i: i32, n: u32) -> u32 {
    let m = i32(n);
    if mode == PT_WRAP_REPEAT {
        return u32(((i % m) + m) % m);
    }
    if mode == PT_WRAP_CLAMP {
        return u32(clamp(i, 0, m - 1));
    }
    let k = ((i % (2 * m)) + 2 * m) % (2 * m);
    return u32(select(2 * m - 1 - k, k, k < m));
}

// The bilinear footprint of `uv` on a w × h image (texel centres at half-integers; a
// non-finite coordinate reads texel 0): the lower-left texel (unfolded) and the weights'
// fractions.
struct PtTexelCoords {
    x0: i32,
    y0: i32,
    fx: f32,
    fy: f32,
}

fn pt_texel_coords(uv: vec2f, w: u32, h: u32) -> PtTexelCoords {
    var x = uv.x * f32(w) - 0.5;
    var y = uv.y * f32(h) - 0.5;
    if !pt_is_finite(x) {
        x = 0.0;
    }
    if !pt_is_finite(y) {
        y = 0.0;
    }
    let x0 = floor(x);
    let y0 = floor(y);
    let lo = -1073741824.0;
    let hi = 1073741824.0;
    return PtTexelCoords(i32(clamp(x0, lo, hi)), i32(clamp(y0, lo, hi)), x - x0, y - y0);
}

// `TextureMap::sample`: bilinear at `uv`, RGB decoded by the map's encoding, alpha linear.
fn pt_tex_sample(d: u32, uv_in: vec2f) -> vec4f {
    var uv = uv_in;
    if pt_tu(d + 7u) == 0u {
        uv = vec2f(pt_tables[d + 8u], pt_tables[d + 9u]) * uv_in.x + vec2f(pt_tables[d + 10u], pt_tables[d + 11u]) * uv_in.y
            + vec2f(pt_tables[d + 12u], pt_tables[d + 13u]);
    }
    let first = pt_tu(d);
    let w = pt_tu(d + 1u);
    let h = pt_tu(d + 2u);
    let c = pt_texel_coords(uv, w, h);
    let x0 = c.x0;
    let y0 = c.y0;
    let fx = c.fx;
    let fy = c.fy;
    let wrap_u = pt_tu(d + 3u);
    let wrap_v = pt_tu(d + 4u);
    let xs = vec2u(pt_wrap(wrap_u, x0, w), pt_wrap(wrap_u, x0 + 1, w));
    let ys = vec2u(pt_wrap(wrap_v, y0, h), pt_wrap(wrap_v, y0 + 1, h));
    let weights = vec4f((1.0 - fx) * (1.0 - fy), fx * (1.0 - fy), (1.0 - fx) * fy, fx * fy);
    // The decode tables: sRGB's transfer function, then ÷255 (`srgb_table`, `linear_table`).
    let decode = pt_params.decode_offset + 256u * pt_tu(d + 5u);
    var out = vec4f(0.0);
    for (var k = 0u; k < 4u; k++) {
        let t = pt_texels[first + ys[k >> 1u] * w + xs[k & 1u]];
        let wk = weights[k];
        out.x += wk * pt_tables[decode + (t & 0xffu)];
        out.y += wk * pt_tables[decode + ((t >> 8u) & 0xffu)];
        out.z += wk * pt_tables[decode + ((t >> 16u) & 0xffu)];
        out.w += wk * (f32(t >> 24u) * (1.0 / 255.0));
    }
    return out;
}

// uplift.rs: `sigmoid`, exactly 0 or 1 beyond ±1e18.
fn pt_sigmoid(x: vec4f) -> vec4f {
    let y = 0.5 + x / (2.0 * sqrt(1.0 + x * x));
    return select(y, select(vec4f(0.0), vec4f(1.0), x > vec4f(0.0)), abs(x) > vec4f(1e18));
}

// `UpliftTable::lookup`: the sigmoid coefficients of a non-grey linear-sRGB colour in
// [0, 1]³ (largest component, then trilinear in the table).
fn pt_uplift(rgb: vec3f) -> vec3f {
    let n = 32u;
    var l = 2u;
    if rgb.x >= rgb.y && rgb.x >= rgb.z {
        l = 0u;
    } else if rgb.y >= rgb.z {
        l = 1u;
    }
    let z = rgb[l];
    let scale = f32(n - 1u) / z;
    let x = rgb[(l + 1u) % 3u] * scale;
    let y = rgb[(l + 2u) % 3u] * scale;
    let nodes = pt_params.uplift_offset;
    // partition_point(|node| node <= z), clamped to 1..n-1, minus one.
    var below = 0u;
    while below < n && pt_tables[nodes + below] <= z {
        below += 1u;
    }
    let zi = clamp(below, 1u, n - 1u) - 1u;
    let tz = clamp((z - pt_tables[nodes + zi]) / (pt_tables[nodes + zi + 1u] - pt_tables[nodes + zi]), 0.0, 1.0);
    let xi = min(u32(x), n - 2u);
    let yi = min(u32(y), n - 2u);
    let tx = x - f32(xi);
    let ty = y - f32(yi);
    let coeffs = nodes + n;
    var plane: array<vec3f, 2>;
    for (var dz = 0u; dz < 2u; dz++) {
        var c: array<vec3f, 4>;
        for (var j = 0u; j < 4u; j++) {
            let e = coeffs + 3u * (((l * n + zi + dz) * n + yi + (j >> 1u)) * n + xi + (j & 1u));
            c[j] = pt_tv3(e);
        }
        let a = c[0] + tx * (c[1] - c[0]);
        let b = c[2] + tx * (c[3] - c[2]);
        plane[dz] = a + ty * (b - a);
    }
    return plane[0] + tz * (plane[1] - plane[0]);
}

// `reflectance_spectrum`: a linear-sRGB reflectance at the path's wavelengths (the RGB
// itself in RGB mode; greys exactly constant).
fn pt_reflectance(rgb_in: vec3f, lambda: vec4f) -> vec4f {
    if PT_RGB {
        return vec4f(rgb_in, 0.0);
    }
    let rgb = clamp(rgb_in, vec3f(0.0), vec3f(1.0));
    if rgb.x == rgb.y && rgb.y == rgb.z {
        return vec4f(rgb.x);
    }
    let c = pt_uplift(rgb);
    return pt_sigmoid((c.x * lambda + c.y) * lambda + c.z);
}

// The texture record of material `m`, or PT_NO_HIT.
fn pt_material_textures(m: u32) -> u32 {
    if !PT_HAS_TEXTURES {
        return PT_NO_HIT;
    }
    return pt_tu(pt_params.material_textures_offset + m);
}

// A map's filtered colour at `uv` as a reflectance (`TextureMap::reflectance`), or 1 where
// the record has none at `slot`.
fn pt_tex_reflectance(rec: u32, slot: u32, uv: vec2f, lambda: vec4f) -> vec4f {
    let d = pt_tu(rec + slot);
    if d == PT_NO_HIT {
        return vec4f(1.0);
    }
    return pt_reflectance(pt_tex_sample(d, uv).xyz, lambda);
}

// `MaterialTextures::texels` handed to the material code for the BSDF calls of this hit
// (`mat_set_texels`), or none for an untextured material.
fn pt_set_texels(m: u32, uv: vec2f, lambda: vec4f) {
    if !PT_HAS_TEXTURES {
        return;
    }
    let rec = pt_material_textures(m);
    if rec == PT_NO_HIT {
        mat_clear_texels();
        return;
    }
    var roughness = 1.0;
    var metallic = 1.0;
    let mr = pt_tu(rec + 2u);
    if mr != PT_NO_HIT {
        let t = pt_tex_sample(mr, uv);
        roughness = t.y;
        metallic = t.z;
    }
    mat_set_texels(m, pt_tex_reflectance(rec, 0u, uv, lambda), pt_tex_reflectance(rec, 1u, uv, lambda), roughness, metallic);
}

// `Material::emission_at`: the emission times the emissive texel.
fn pt_emission_at(m: u32, uv: vec2f, lambda: vec4f) -> vec4f {
    let e = material_emission(m, lambda);
    let rec = pt_material_textures(m);
    if rec == PT_NO_HIT || all(e == vec4f(0.0)) {
        return e;
    }
    return e * pt_tex_reflectance(rec, 3u, uv, lambda);
}

// The texture coordinates of triangle `prim`'s vertices (zeros where the mesh has none).
fn pt_triangle_uvs(prim: u32) -> array<vec2f, 3> {
    if (pt_params.scene_flags & PT_HAS_UVS) == 0u {
        return array<vec2f, 3>(vec2f(0.0), vec2f(0.0), vec2f(0.0));
    }
    let vi = pt_tri_vidx[prim];
    return array<vec2f, 3>(
        vec2f(pt_attrs[2u * vi.x].w, pt_attrs[2u * vi.x + 1u].w),
        vec2f(pt_attrs[2u * vi.y].w, pt_attrs[2u * vi.y + 1u].w),
        vec2f(pt_attrs[2u * vi.z].w, pt_attrs[2u * vi.z + 1u].w),
    );
}

// The hit's texture coordinates (`SceneView::uv_at`: zero for shapes and meshes without).
fn pt_hit_uv(hit: PtHit) -> vec2f {
    if !PT_HAS_TEXTURES || (pt_params.scene_flags & PT_HAS_UVS) == 0u || pt_is_shape(hit.prim) {
        return vec2f(0.0);
    }
    let t = pt_triangle_uvs(hit.prim);
    return (1.0 - hit.u - hit.v) * t[0] + hit.u * t[1] + hit.v * t[2];
}

// The material a hit is on.
fn pt_hit_material(hit: PtHit) -> u32 {
    if pt_is_shape(hit.prim) {
        return pt_tu((hit.prim & ~PT_SHAPE_PRIM_BIT) + 1u);
    }
    return pt_instance_material(hit, bitcast<u32>(pt_tri_verts[3u * hit.prim].w));
}

// The CPU's primitive id of a hit (`alpha_hash` hashes it).
fn pt_hit_cpu_prim(hit: PtHit) -> u32 {
    if pt_is_shape(hit.prim) {
        return pt_tu((hit.prim & ~PT_SHAPE_PRIM_BIT) + 4u);
    }
    return pt_instance_cpu_prim(hit, bitcast<u32>(pt_tri_verts[3u * hit.prim + 2u].w));
}

// `alpha_hash`: a stable hash of a ray and a primitive to [0, 1), in 64-bit arithmetic on
// word pairs.
fn pt_alpha_hash(o: vec3f, d: vec3f, prim: u32) -> f32 {
    var h = vec2u(0x7f4a7c15u ^ prim, 0x9e3779b9u);
    let values = array<f32, 6>(o.x, o.y, o.z, d.x, d.y, d.z);
    for (var i = 0u; i < 6u; i++) {
        h.x ^= bitcast<u32>(values[i]);
        h = pt_mul64(h, vec2u(0xed558ccdu, 0xff51afd7u));
        h.x ^= pt_shr64_any(h, 33u).x;
    }
    h = pt_mul64(h, vec2u(0x1a85ec53u, 0xc4ceb9feu));
    h.x ^= pt_shr64_any(h, 33u).x;
    return f32(pt_shr64_any(h, 40u).x) * (1.0 / 16777216.0);
}

// `Alpha::passes`: whether a ray (o, d) goes through material `m` at `uv`.
fn pt_alpha_passes(m: u32, uv: vec2f, o: vec3f, d: vec3f, prim: u32) -> bool {
    let rec = pt_material_textures(m);
    if rec == PT_NO_HIT {
        return false;
    }
    let mode = pt_tu(rec + 8u);
    if mode != PT_ALPHA_MASK && mode != PT_ALPHA_BLEND {
        return false;
    }
    var value = pt_tables[rec + 10u];
    let map = pt_tu(rec + 11u);
    if map != PT_NO_HIT {
        let t = pt_tex_sample(map, uv);
        value *= select(t.x, t.w, pt_tu(map + 6u) != 0u);
    }
    if mode == PT_ALPHA_MASK {
        return value < pt_tables[rec + 9u];
    }
    return pt_alpha_hash(o, d, prim) >= value;
}

// `SceneView::through_cutouts`: from `hit` on, the first hit that alpha does not let
// through (a closest-hit query per layer, at most 256 layers).
fn pt_through_cutouts(o: vec3f, d: vec3f, t_max: f32, first: PtHit) -> PtHit {
    var hit = first;
    for (var layer = 0u; layer < 256u; layer++) {
        if hit.prim == PT_NO_HIT {
            return hit;
        }
        if !pt_alpha_passes(pt_hit_material(hit), pt_hit_uv(hit), o, d, pt_hit_cpu_prim(hit)) {
            return hit;
        }
        hit = pt_trace_opaque(o, d, hit.t, t_max, false);
    }
    return hit;
}

// ∂p/∂u, ∂p/∂v of a triangle (`triangle_uv_derivatives`); zeros for degenerate uvs.
struct PtUvDerivatives {
    dpdu: vec3f,
    dpdv: vec3f,
}

fn pt_triangle_uv_derivatives(p0: vec3f, p1: vec3f, p2: vec3f, uv0: vec2f, uv1: vec2f, uv2: vec2f) -> PtUvDerivatives {
    let none = PtUvDerivatives(vec3f(0.0), vec3f(0.0));
    let duv02 = uv0 - uv2;
    let duv12 = uv1 - uv2;
    let dp02 = p0 - p2;
    let dp12 = p1 - p2;
    let det = duv02.x * duv12.y - duv02.y * duv12.x;
    if !(abs(det) >= 1e-12) || !pt_is_finite(det) {
        return none;
    }
    let inv = 1.0 / det;
    let dpdu = (duv12.y * dp02 - duv02.y * dp12) * inv;
    let dpdv = (duv02.x * dp12 - duv12.x * dp02) * inv;
    if !pt_is_finite3(dpdu) || !pt_is_finite3(dpdv) {
        return none;
    }
    return PtUvDerivatives(dpdu, dpdv);
}

// `tangent_frame`: T = ∂p/∂u perpendicular to n, B = n × T signed to point up the image;
// `valid` false without usable derivatives.
struct PtTangentFrame {
    t: vec3f,
    b: vec3f,
    valid: bool,
}

fn pt_tangent_frame(n: vec3f, dpdu: vec3f, dpdv: vec3f) -> PtTangentFrame {
    let t0 = dpdu - n * dot(n, dpdu);
    let r = 1.0 / length(t0);
    if !(pt_is_finite(r) && r > 0.0) {
        return PtTangentFrame(vec3f(0.0), vec3f(0.0), false);
    }
    let t = t0 * r;
    let b = cross(n, t);
    let sign = select(1.0, -1.0, dot(b, -dpdv) < 0.0);
    return PtTangentFrame(t, b * sign, true);
}

// glam's `normalize_or` (and `try_normalize`): v times the reciprocal of its length where
// that is finite and positive, else `fallback`.
fn pt_normalize_or(v: vec3f, fallback: vec3f) -> vec3f {
    let r = 1.0 / length(v);
    if pt_is_finite(r) && r > 0.0 {
        return v * r;
    }
    return fallback;
}

// `bump_normal`: the normal of the surface displaced by the height map (finite differences
// over half a texel).
fn pt_bump_normal(d: u32, scale: f32, uv: vec2f, n: vec3f, dpdu: vec3f, dpdv: vec3f) -> vec3f {
    if all(dpdu == vec3f(0.0)) || all(dpdv == vec3f(0.0)) {
        return n;
    }
    let du = 0.5 / f32(pt_tu(d + 1u));
    let dv = 0.5 / f32(pt_tu(d + 2u));
    let h0 = pt_tex_sample(d, uv).x * scale;
    let dhdu = (pt_tex_sample(d, uv + vec2f(du, 0.0)).x * scale - h0) / du;
    let dhdv = (pt_tex_sample(d, uv + vec2f(0.0, dv)).x * scale - h0) / dv;
    let pu = dpdu + dhdu * n;
    let pv = dpdv + dhdv * n;
    let b = pt_normalize_or(cross(pu, pv), vec3f(0.0));
    if all(b == vec3f(0.0)) {
        return n;
    }
    return select(b, -b, dot(b, n) < 0.0);
}

// `mapped_normal`: the tangent-space normal map (OpenGL's +y up the image).
fn pt_mapped_normal(d: u32, scale: f32, uv: vec2f, n: vec3f, dpdu: vec3f, dpdv: vec3f) -> vec3f {
    let f = pt_tangent_frame(n, dpdu, dpdv);
    if !f.valid {
        return n;
    }
    let texel = pt_tex_sample(d, uv);
    let x = (2.0 * texel.x - 1.0) * scale;
    let y = (2.0 * texel.y - 1.0) * scale;
    let z = 2.0 * texel.z - 1.0;
    return pt_normalize_or(x * f.t + y * f.b + max(z, 1e-3) * n, n);
}

// `SceneView::bend_normal`: the shading normal (and tangent) bent by the material's
// normal or bump map at a triangle hit.
fn pt_bend_normal(sf: ptr<function, PtSurface>, hit: PtHit, uv: vec2f) {
    if !PT_HAS_TEXTURES || pt_is_shape(hit.prim) || pt_params.shading == PT_SHADING_GEOMETRIC {
        return;
    }
    let rec = pt_material_textures((*sf).m);
    if rec == PT_NO_HIT {
        return;
    }
    let normal = pt_tu(rec + 4u);
    let bump = pt_tu(rec + 6u);
    if normal == PT_NO_HIT && bump == PT_NO_HIT {
        return;
    }
    let p = pt_hit_triangle(hit);
    let t = pt_triangle_uvs(hit.prim);
    let der = pt_triangle_uv_derivatives(p[0], p[1], p[2], t[0], t[1], t[2]);
    var n = (*sf).ns;
    if bump != PT_NO_HIT {
        n = pt_bump_normal(bump, pt_tables[rec + 7u], uv, n, der.dpdu, der.dpdv);
    }
    if normal != PT_NO_HIT {
        n = pt_mapped_normal(normal, pt_tables[rec + 5u], uv, n, der.dpdu, der.dpdv);
    }
    // Kept on the geometric normal's side, as every shading normal is.
    let ng = (*sf).ng;
    if dot(n, ng) < 0.0 {
        n = pt_normalize_or(n - 2.0 * dot(n, ng) * ng, ng);
    }
    (*sf).ns = n;
    if any((*sf).tangent != vec3f(0.0)) || any(der.dpdu != vec3f(0.0)) {
        (*sf).tangent = der.dpdu;
    }
}
