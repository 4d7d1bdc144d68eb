// The viewer's display conversion on the device, mirroring crates/tracer/src/film.rs
// (`Film::display_pixels`: each pixel's running mean packed as 0x00RRGGBB) and
// crates/spectral/src/colour.rs (`srgb_encode`, `srgb_to_u8`). The mean combines the
// samples already folded into the CPU's exact film (`pt_folded`: mean and count) with
// those still in the device's accumulators (`pt_block`).

struct PtDisplayParams {
    width: u32,
    height: u32,
    pad0: u32,
    pad1: u32,
}

struct PtFilmView {
    header: array<u32, 4>,
    pixels: array<PtPixel>,
}

@group(0) @binding(0) var<uniform> pt_display: PtDisplayParams;
@group(0) @binding(1) var<storage, read> pt_block: PtFilmView;
@group(0) @binding(2) var<storage, read> pt_folded: array<vec4f>;
@group(0) @binding(3) var<storage, read_write> pt_display_out: array<u32>;

fn pt_srgb_to_u8(linear: f32) -> u32 {
    let curve = 1.055 * pow(max(linear, 0.0031308), 1.0 / 2.4) - 0.055;
    let encoded = select(curve, 12.92 * max(linear, 0.0), linear <= 0.0031308);
    return u32(clamp(encoded, 0.0, 1.0) * 255.0 + 0.5);
}

@compute @workgroup_size(8, 8, 1)
fn pt_display_main(@builtin(global_invocation_id) gid: vec3u) {
    if gid.x >= pt_display.width || gid.y >= pt_display.height {
        return;
    }
    let i = gid.y * pt_display.width + gid.x;
    let block = pt_block.pixels[i];
    let folded = pt_folded[i];
    let nb = f32(block.count);
    let n = folded.w + nb;
    var mean = vec3f(0.0);
    if n > 0.0 {
        mean = (folded.w * folded.xyz + nb * block.mean) / n;
    }
    pt_display_out[i] = (pt_srgb_to_u8(mean.x) << 16u) | (pt_srgb_to_u8(mean.y) << 8u) | pt_srgb_to_u8(mean.z);
}
