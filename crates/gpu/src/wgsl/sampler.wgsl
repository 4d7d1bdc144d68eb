// Where the integrators' random numbers come from, mirroring crates/tracer/src/sampler.rs:
// independent PCG32 per pixel sample (`Pcg32`), per-pixel Owen-scrambled Sobol
// (`PaddedSobol`) and Owen-scrambled Sobol in Morton order over the image (`ZSobol`,
// after Ahmed & Wonka 2020 and pbrt-v4's `ZSobolSampler`), the one `PT_SAMPLER` names
// compiled in (the backend keeps a kernel per sampler used). The Sobol samplers reproduce the CPU's values
// bit for bit: 64-bit scrambles on (lo, hi) word pairs, the second dimension from the
// CPU's bit-reversed tables (uploaded into `pt_tables`).

struct PtSampler {
    rng: PtRng,
    // Sobol: the sample index at the top of 64 bits, bit-reversed.
    reversed: vec2u,
    // Padded Sobol: the pixel's hash.
    pixel: vec2u,
    dimension: u32,
}

// a << n and a >> n for 0 ≤ n < 64.
fn pt_shl64_any(a: vec2u, n: u32) -> vec2u {
    if n == 0u {
        return a;
    }
    if n >= 32u {
        return vec2u(0u, a.x << (n - 32u));
    }
    return vec2u(a.x << n, (a.y << n) | (a.x >> (32u - n)));
}

fn pt_shr64_any(a: vec2u, n: u32) -> vec2u {
    if n == 0u {
        return a;
    }
    if n >= 32u {
        return vec2u(a.y >> (n - 32u), 0u);
    }
    return pt_shr64(a, n);
}

fn pt_reverse64(a: vec2u) -> vec2u {
    return vec2u(reverseBits(a.y), reverseBits(a.x));
}

// `laine_karras_64`.
fn pt_laine_karras_64(v0: vec2u, seed: vec2u) -> vec2u {
    var v = v0;
    v ^= pt_mul64(v, PT_LK64_MUL0);
    v = pt_add64(v, seed);
    v = pt_mul64(v, vec2u(seed.y | 1u, 0u));
    v ^= pt_mul64(v, PT_LK64_MUL1);
    v ^= pt_mul64(v, PT_LK64_MUL2);
    return v;
}

// `laine_karras`.
fn pt_laine_karras(v0: u32, seed: u32) -> u32 {
    var v = v0;
    v ^= v * PT_LK_MUL0;
    v = v + seed;
    v = v * ((seed >> 16u) | 1u);
    v ^= v * PT_LK_MUL1;
    v ^= v * PT_LK_MUL2;
    return v;
}

fn pt_to_unit(v: u32) -> f32 {
    return f32(v >> 8u) * (1.0 / 16777216.0);
}

// `scrambled_sobol_1`: the second Sobol dimension, bit-reversed by `sobol_1_reversed`'s
// Taylor shift over GF(2) (five shift-and-XORs, no tables).
fn pt_scrambled_sobol_1(i: u32, seed: u32) -> u32 {
    var v = i;
    v ^= (v >> 16u) & 0x0000ffffu;
    v ^= (v >> 8u) & 0x00ff00ffu;
    v ^= (v >> 4u) & 0x0f0f0f0fu;
    v ^= (v >> 2u) & 0x33333333u;
    v ^= (v >> 1u) & 0x55555555u;
    return reverseBits(pt_laine_karras(v, seed));
}

// `morton2` for coordinates below 2¹⁶ (the image side is at most MAX_IMAGE_SIDE).
fn pt_spread16(v0: u32) -> u32 {
    var v = v0 & 0xffffu;
    v = (v | (v << 8u)) & 0x00ff00ffu;
    v = (v | (v << 4u)) & 0x0f0f0f0fu;
    v = (v | (v << 2u)) & 0x33333333u;
    return (v | (v << 1u)) & 0x55555555u;
}

fn pt_sampler_for(x: u32, y: u32, pixel: u32, sample: u32) -> PtSampler {
    var s = PtSampler(PtRng(vec2u(0u), vec2u(0u)), vec2u(0u), vec2u(0u), 0u);
    if PT_SAMPLER == PT_SAMPLER_ZSOBOL {
        let morton = vec2u((pt_spread16(x) | (pt_spread16(y) << 1u)), 0u);
        let index = pt_shl64_any(morton, pt_params.log2_spp) | vec2u(sample, 0u);
        s.reversed = pt_reverse64(pt_shl64_any(index, pt_params.unused_bits));
    } else if PT_SAMPLER == PT_SAMPLER_SOBOL {
        let seed = vec2u(pt_params.seed_lo, pt_params.seed_hi);
        s.pixel = pt_mix64(seed ^ pt_mix64(vec2u(y, x)));
        if pt_params.unused_bits < 64u {
            s.reversed = pt_reverse64(pt_shl64_any(vec2u(sample, 0u), pt_params.unused_bits));
        }
    } else {
        s.rng = pt_rng_for_sample(pixel, sample);
    }
    return s;
}

// The current dimension's Sobol index and value seed, advancing by `dims`.
fn pt_sobol_draw(s: ptr<function, PtSampler>, dims: u32) -> array<vec2u, 2> {
    let d = vec2u((*s).dimension, 0u);
    (*s).dimension += dims;
    if PT_SAMPLER == PT_SAMPLER_ZSOBOL {
        // `ZSobolLayout::seeds`: the render's table, hashed beyond it.
        var index_seed: vec2u;
        var value_seed: vec2u;
        if d.x < PT_SEED_DIMENSIONS {
            let e = pt_dims[d.x];
            index_seed = e.xy;
            value_seed = e.zw;
        } else {
            let seed = vec2u(pt_params.zseed_lo, pt_params.zseed_hi);
            index_seed = pt_mix64(seed ^ pt_mul64(d, PT_DIMENSION_MUL));
            value_seed = pt_mix64(vec2u(0u, d.x) ^ seed ^ PT_VALUE_SEED_KEY);
        }
        let index = pt_shr64_any(pt_reverse64(pt_laine_karras_64((*s).reversed, index_seed)), pt_params.unused_bits);
        return array<vec2u, 2>(index, value_seed);
    }
    let h = pt_mix64((*s).pixel ^ pt_mul64(d, PT_DIMENSION_MUL));
    var index = vec2u(0u);
    if pt_params.unused_bits < 64u {
        index = pt_shr64_any(pt_reverse64(pt_laine_karras_64((*s).reversed, h)), pt_params.unused_bits);
    }
    return array<vec2u, 2>(index, pt_mix64(h));
}

fn pt_next_1d(s: ptr<function, PtSampler>) -> f32 {
    if PT_SAMPLER == PT_SAMPLER_INDEPENDENT {
        // Through a local copy: naga 30's SPIR-V writer rejects a pointer to a member of a
        // pointer argument.
        var r = (*s).rng;
        let v = pt_rng_f32(&r);
        (*s).rng = r;
        return v;
    }
    let dr = pt_sobol_draw(s, 1u);
    return pt_to_unit(reverseBits(pt_laine_karras(dr[0].x, dr[1].x)));
}

fn pt_next_2d(s: ptr<function, PtSampler>) -> vec2f {
    if PT_SAMPLER == PT_SAMPLER_INDEPENDENT {
        // `Pcg32::next_2d`: two values in order.
        let a = pt_next_1d(s);
        let b = pt_next_1d(s);
        return vec2f(a, b);
    }
    let dr = pt_sobol_draw(s, 2u);
    let a = pt_to_unit(reverseBits(pt_laine_karras(dr[0].x, dr[1].x)));
    let b = pt_to_unit(pt_scrambled_sobol_1(dr[0].x, dr[1].y));
    return vec2f(a, b);
}

// `Sampler::camera`: (wavelength value, or 0 without a sampled wavelength, jitter). The
// independent sampler draws the wavelength first; the Sobol samplers give their best
// stratified first pair to the jitter.
fn pt_camera(s: ptr<function, PtSampler>, wavelength: bool) -> vec3f {
    if PT_SAMPLER == PT_SAMPLER_INDEPENDENT {
        var u = 0.0;
        if wavelength {
            u = pt_next_1d(s);
        }
        let j = pt_next_2d(s);
        return vec3f(u, j);
    }
    let j = pt_next_2d(s);
    var u = 0.0;
    if wavelength {
        u = pt_next_1d(s);
    }
    return vec3f(u, j);
}
