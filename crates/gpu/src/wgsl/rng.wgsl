// PCG32 (O'Neill 2014) seeded per pixel sample, mirroring `Pcg32` (crates/rng/src/lib.rs):
// `Pcg32::for_sample(seed, pixel, sample)` — seeded through splitmix64's finaliser —
// with the 64-bit arithmetic done on (lo, hi) word pairs, since WGSL has no 64-bit
// integers. The integrator draws in the CPU's order, so a GPU path starts with the CPU's
// random numbers (and usually follows the same route until rounding sends it elsewhere).
// PT_PCG_MULT, PT_PCG_SAMPLE_STREAM_KEY and PT_MIX64_MUL* (as (lo, hi) word pairs) are
// generated from the Rust constants.

struct PtRng {
    state: vec2u,
    inc: vec2u,
}

fn pt_add64(a: vec2u, b: vec2u) -> vec2u {
    let lo = a.x + b.x;
    return vec2u(lo, a.y + b.y + select(0u, 1u, lo < a.x));
}

// The full 64-bit product of two 32-bit words, from 16-bit halves.
fn pt_mul32_wide(x: u32, y: u32) -> vec2u {
    let x0 = x & 0xffffu;
    let x1 = x >> 16u;
    let y0 = y & 0xffffu;
    let y1 = y >> 16u;
    let p00 = x0 * y0;
    let p01 = x0 * y1;
    let p10 = x1 * y0;
    let p11 = x1 * y1;
    let mid = (p00 >> 16u) + (p01 & 0xffffu) + (p10 & 0xffffu);
    return vec2u((mid << 16u) | (p00 & 0xffffu), p11 + (p01 >> 16u) + (p10 >> 16u) + (mid >> 16u));
}

// a · b mod 2⁶⁴.
fn pt_mul64(a: vec2u, b: vec2u) -> vec2u {
    let lo = pt_mul32_wide(a.x, b.x);
    return vec2u(lo.x, lo.y + a.x * b.y + a.y * b.x);
}

// a >> n for 0 < n < 32.
fn pt_shr64(a: vec2u, n: u32) -> vec2u {
    return vec2u((a.x >> n) | (a.y << (32u - n)), a.y >> n);
}

// `rng::mix64` (splitmix64's finaliser).
fn pt_mix64(z0: vec2u) -> vec2u {
    var z = z0;
    z = pt_mul64(z ^ pt_shr64(z, 30u), PT_MIX64_MUL1);
    z = pt_mul64(z ^ pt_shr64(z, 27u), PT_MIX64_MUL2);
    return z ^ pt_shr64(z, 31u);
}

fn pt_rng_next(r: ptr<function, PtRng>) -> u32 {
    let old = (*r).state;
    (*r).state = pt_add64(pt_mul64(old, PT_PCG_MULT), (*r).inc);
    // ((old >> 18) ^ old) >> 27, truncated to 32 bits; rotation by old >> 59.
    let x = pt_shr64(pt_shr64(old, 18u) ^ old, 27u).x;
    let rot = old.y >> 27u;
    return (x >> rot) | (x << ((32u - rot) & 31u));
}

// A uniform float in [0, 1) from 24 random bits, as `Pcg32::next_f32`.
fn pt_rng_f32(r: ptr<function, PtRng>) -> f32 {
    return f32(pt_rng_next(r) >> 8u) * (1.0 / 16777216.0);
}

// `Pcg32::for_sample`: key = mix64(seed ^ mix64(pixel << 32 | sample)), then
// `Pcg32::new(key, mix64(key ^ 0xDA94_2042_E4DD_58B5))`.
fn pt_rng_for_sample(pixel: u32, sample: u32) -> PtRng {
    let seed = vec2u(pt_params.seed_lo, pt_params.seed_hi);
    let key = pt_mix64(seed ^ pt_mix64(vec2u(sample, pixel)));
    let stream = pt_mix64(key ^ PT_PCG_SAMPLE_STREAM_KEY);
    var r = PtRng(vec2u(0u), vec2u((stream.x << 1u) | 1u, (stream.y << 1u) | (stream.x >> 31u)));
    _ = pt_rng_next(&r);
    r.state = pt_add64(r.state, key);
    _ = pt_rng_next(&r);
    return r;
}
