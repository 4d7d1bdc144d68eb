// Draws a frame of display pixels (0x00RRGGBB, sRGB-encoded, the display kernel's and
// `Film::display_pixels`' layout) onto a window's surface or any colour target, scaled
// to the target by nearest neighbour as the viewer's CPU path scales previews
// (crates/viewer/src/lib.rs, `App::show`: source column x · w_src / w_dst).

struct PtPresentParams {
    src_width: u32,
    src_height: u32,
    dst_width: u32,
    dst_height: u32,
    // 1 where the target stores linear values and encodes sRGB itself (an *Srgb format):
    // the shader then decodes, and the target's encoding gives back the same bytes.
    decode_srgb: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
}

@group(0) @binding(0) var<uniform> pt_present: PtPresentParams;
@group(0) @binding(1) var<storage, read> pt_present_pixels: array<u32>;

// One triangle that covers the whole target (clip space (-1,-1), (3,-1), (-1,3)).
@vertex
fn pt_present_vertex(@builtin(vertex_index) i: u32) -> @builtin(position) vec4f {
    let corner = vec2f(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4f(corner * 2.0 - 1.0, 0.0, 1.0);
}

fn pt_srgb_decode(encoded: f32) -> f32 {
    if encoded <= 0.04045 {
        return encoded / 12.92;
    }
    return pow((encoded + 0.055) / 1.055, 2.4);
}

@fragment
fn pt_present_fragment(@builtin(position) position: vec4f) -> @location(0) vec4f {
    // Framebuffer coordinates: the pixel's centre, origin top left, as the image's rows.
    let x = min(u32(position.x), pt_present.dst_width - 1u);
    let y = min(u32(position.y), pt_present.dst_height - 1u);
    let sx = min(x * pt_present.src_width / pt_present.dst_width, pt_present.src_width - 1u);
    let sy = min(y * pt_present.src_height / pt_present.dst_height, pt_present.src_height - 1u);
    let word = pt_present_pixels[sy * pt_present.src_width + sx];
    var rgb = vec3f(f32((word >> 16u) & 255u), f32((word >> 8u) & 255u), f32(word & 255u)) / 255.0;
    if pt_present.decode_srgb != 0u {
        rgb = vec3f(pt_srgb_decode(rgb.x), pt_srgb_decode(rgb.y), pt_srgb_decode(rgb.z));
    }
    return vec4f(rgb, 1.0);
}
