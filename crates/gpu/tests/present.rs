//! Frames shown from the device (`gpu::present`): what the present pipeline draws into a
//! colour target is, byte for byte, the display words it was given — in RGBA, BGRA and
//! sRGB targets, at the frame's size and scaled by nearest neighbour as the viewer's CPU
//! path scales — and a [`DeviceAccumulation`]'s device frame is what its `display` reads
//! back. Skipped (with a message) where no adapter exists, unless `SPT_REQUIRE_GPU` is set.

use gpu::GpuContext;
use gpu::accumulation::DeviceAccumulation;
use gpu::present::{DeviceFrame, Presenter};
use std::path::Path;
use std::sync::Arc;
use tracer::render::{RenderSettings, SceneOptions};
use tracer::{Accumulation, SpectralMode};

const CORNELL: &str =
    concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/scenes/cornell-box/CornellBox-Original.obj");

/// Draws `frame` into a fresh `width × height` texture of `format` and reads it back as
/// 0x00RRGGBB words (the target's bytes reordered from RGBA or BGRA).
fn draw(ctx: &GpuContext, frame: &DeviceFrame, format: wgpu::TextureFormat, width: u32, height: u32) -> Vec<u32> {
    let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("present test target"),
        size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let presenter = Presenter::new(ctx, format).unwrap();
    presenter.draw(ctx, frame, &texture.create_view(&Default::default()), width, height);
    let row = (width * 4).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
    let readback = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("present test read-back"),
        size: (row * height) as u64,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    encoder.copy_texture_to_buffer(
        texture.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &readback,
            layout: wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(row), rows_per_image: None },
        },
        wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
    );
    ctx.queue.submit([encoder.finish()]);
    readback.map_async(wgpu::MapMode::Read, .., |r| r.unwrap());
    ctx.device.poll(wgpu::PollType::wait_indefinitely()).unwrap();
    let bytes = readback.get_mapped_range(..).unwrap().to_vec();
    let bgra = matches!(format, wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb);
    (0..height as usize)
        .flat_map(|y| {
            let bytes = &bytes;
            (0..width as usize).map(move |x| {
                let p = &bytes[y * row as usize + 4 * x..][..4];
                let (r, g, b) = if bgra { (p[2], p[1], p[0]) } else { (p[0], p[1], p[2]) };
                u32::from_be_bytes([0, r, g, b])
            })
        })
        .collect()
}

/// The viewer's CPU scaling (`App::show`): target pixel (x, y) shows source
/// (x · w / W, y · h / H).
fn nearest(src: &[u32], (w, h): (usize, usize), (tw, th): (usize, usize)) -> Vec<u32> {
    (0..th).flat_map(|y| (0..tw).map(move |x| src[(y * h / th) * w + x * w / tw])).collect()
}

#[test]
fn the_present_pipeline_draws_the_display_words_unchanged() {
    let Some(ctx) = gpu::require_gpu() else { return };
    // Every value of every channel, each channel's values in another order.
    let (w, h) = (256u32, 3u32);
    let words: Vec<u32> = (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let r = x;
            let g = (x * 97 + y * 31) % 256;
            let b = 255 - (x * 13 + y) % 256;
            (r << 16) | (g << 8) | b
        })
        .collect();
    let frame = DeviceFrame::upload(&ctx, w, h, &words).unwrap();
    for format in
        [wgpu::TextureFormat::Rgba8Unorm, wgpu::TextureFormat::Bgra8Unorm, wgpu::TextureFormat::Rgba8UnormSrgb]
    {
        let shown = draw(&ctx, &frame, format, w, h);
        let wrong = shown.iter().zip(&words).filter(|(a, b)| a != b).count();
        assert_eq!(wrong, 0, "{format:?}: {wrong} of {} pixels differ", words.len());
    }

    // Scaled up (a preview) and down, by nearest neighbour as the CPU path scales.
    let (sw, sh) = (5usize, 4usize);
    let small: Vec<u32> = (0..(sw * sh) as u32).map(|i| i * 0x0a_0b_0c).collect();
    let frame = DeviceFrame::upload(&ctx, sw as u32, sh as u32, &small).unwrap();
    for (tw, th) in [(19, 13), (3, 2), (5, 4)] {
        let shown = draw(&ctx, &frame, wgpu::TextureFormat::Rgba8Unorm, tw as u32, th as u32);
        assert_eq!(shown, nearest(&small, (sw, sh), (tw, th)), "{sw}×{sh} shown at {tw}×{th}");
    }

    assert!(DeviceFrame::upload(&ctx, 4, 4, &[0; 15]).is_err(), "15 words for 16 pixels");
}

#[test]
fn device_frames_are_what_the_display_reads_back_and_stay_while_held() {
    let Some(ctx) = gpu::require_gpu() else { return };
    if !Path::new(CORNELL).exists() {
        eprintln!("skipping: {CORNELL} is absent");
        return;
    }
    let scene = tracer::obj::load_obj(Path::new(CORNELL)).unwrap();
    let scene =
        Arc::new(gpu::GpuBackend::with_context(ctx.clone()).prepare_gpu(scene, &SceneOptions::default()).unwrap());
    let s = RenderSettings { width: 16, height: 12, spp: 64, seed: 3, mode: SpectralMode::Hero, ..Default::default() };
    let mut acc = DeviceAccumulation::new(scene, &s).unwrap();
    let format = wgpu::TextureFormat::Rgba8Unorm;

    acc.add(3).unwrap();
    let mut three = vec![0; 16 * 12];
    acc.display(&mut three).unwrap();
    assert!(three.iter().any(|&p| p != 0), "the Cornell box is not black");
    let held = acc.display_frame().unwrap();
    assert_eq!((held.width, held.height), (16, 12));
    assert_eq!(draw(&ctx, &held, format, 16, 12), three, "the device frame at 3 spp");

    // While the window holds that frame, the next ones are made elsewhere: it still shows
    // 3 spp after 2 more samples (and the newer frame the 5).
    acc.add(2).unwrap();
    let mut five = vec![0; 16 * 12];
    acc.display(&mut five).unwrap();
    assert_ne!(five, three);
    let newer = acc.display_frame().unwrap();
    assert_eq!(draw(&ctx, &held, format, 16, 12), three, "a held frame is not written again");
    assert_eq!(draw(&ctx, &newer, format, 16, 12), five, "the device frame at 5 spp");

    // After a resize, frames have the new size.
    drop((held, newer));
    acc.restart(&RenderSettings { width: 7, height: 5, ..s.clone() }).unwrap();
    acc.add(1).unwrap();
    let mut small = vec![0; 7 * 5];
    acc.display(&mut small).unwrap();
    let frame = acc.display_frame().unwrap();
    assert_eq!((frame.width, frame.height), (7, 5));
    assert_eq!(draw(&ctx, &frame, format, 7, 5), small);
}
