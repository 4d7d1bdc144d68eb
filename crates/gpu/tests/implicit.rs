//! Implicit surfaces on the GPU (`wgsl/implicit.wgsl`, in f64) against the CPU's
//! `Implicit::intersect`, ray for ray: hit or miss, t, point and normal, for every root
//! solver (closed forms for degrees 2–4, Laguerre with and without polishing, the closed-form
//! solver's Laguerre fall-back for degrees 5 and 6), rays from outside and from inside the
//! bounds and segments that end before the surface. Skipped (with a message) where no adapter
//! exists, unless `SPT_REQUIRE_GPU` is set; a device without `SHADER_F64` must refuse them.

use glam::Vec3;
use rng::Pcg32;
use shapes::implicit::{Implicit, Poly3, parse};
use shapes::roots::RootSolver;
use shapes::{Aabb, Ray, Shape};
use tracer::ShapeKind;
use wgpu::util::DeviceExt;

/// The test kernel's bindings and entry point (with `gpu::kernel::SHAPE_HIT_SOURCE` and the
/// implicit surfaces' source): per ray 9 words (the record's offset as bits, origin,
/// direction, t_min, t_max), per result 8 (hit 0/1, t, point, normal).
const TEST_KERNEL: &str = r#"
@group(0) @binding(0) var<storage, read> pt_tables: array<f32>;
@group(0) @binding(1) var<storage, read> rays: array<f32>;
@group(0) @binding(2) var<storage, read_write> results: array<f32>;

const PT_MISS: f32 = 3.4e38;

@compute @workgroup_size(64)
fn test_implicit(@builtin(global_invocation_id) id: vec3u) {
    let i = id.x;
    if i >= arrayLength(&rays) / 9u {
        return;
    }
    let r = 9u * i;
    let o = vec3f(rays[r + 1u], rays[r + 2u], rays[r + 3u]);
    let d = vec3f(rays[r + 4u], rays[r + 5u], rays[r + 6u]);
    let h = pt_implicit_hit(bitcast<u32>(rays[r]), o, d, rays[r + 7u], rays[r + 8u]);
    let w = 8u * i;
    results[w] = select(0.0, 1.0, h.hit);
    results[w + 1u] = h.t;
    for (var k = 0u; k < 3u; k++) {
        results[w + 2u + k] = h.p[k];
        results[w + 5u + k] = h.n[k];
    }
}
"#;

const LAGUERRE: RootSolver = RootSolver::Laguerre { polish: true };
const LAGUERRE_PLAIN: RootSolver = RootSolver::Laguerre { polish: false };

fn cube(h: f32) -> Aabb {
    Aabb { min: Vec3::splat(-h), max: Vec3::splat(h) }
}

/// Surfaces of degree 2 to 6 under each solver, named.
fn surfaces() -> Vec<(&'static str, Implicit)> {
    let ball = parse("(x + 0.45)^2 + (y - 0.3)^2 + (z - 0.55)^2 - 0.09").unwrap();
    let ball_box = Aabb { min: Vec3::new(-0.76, -0.01, 0.24), max: Vec3::new(-0.14, 0.61, 0.86) };
    let monkey = parse("x^3 - 3 x y^2 + z^2 - 0.3").unwrap();
    let quintic = parse("3 x^3 y - 2.5 x y z^2 + 0.25 z^5 - x + 7").unwrap();
    let surface = |poly: &Poly3, bounds, solver| Implicit::new(poly.clone(), bounds, solver).unwrap();
    vec![
        ("sphere, closed form", surface(&ball, ball_box, RootSolver::ClosedForm)),
        ("sphere, Laguerre", surface(&ball, ball_box, LAGUERRE)),
        ("ellipsoid, Laguerre unpolished", surface(&Poly3::ellipsoid(1.0, 2.0, 0.5), cube(2.0), LAGUERRE_PLAIN)),
        ("monkey saddle (cubic), closed form", surface(&monkey, cube(1.0), RootSolver::ClosedForm)),
        ("torus, closed form", Implicit::torus(0.8, 0.3, RootSolver::ClosedForm).unwrap()),
        ("torus, Laguerre", Implicit::torus(0.8, 0.3, LAGUERRE).unwrap()),
        ("torus, Laguerre unpolished", Implicit::torus(0.8, 0.3, LAGUERRE_PLAIN).unwrap()),
        ("tangle cube, closed form", surface(&Poly3::tangle_cube(), cube(2.3), RootSolver::ClosedForm)),
        ("quintic, closed form (Laguerre)", surface(&quintic, cube(2.0), RootSolver::ClosedForm)),
        ("heart, closed form (Laguerre)", Implicit::heart(RootSolver::ClosedForm).unwrap()),
        ("heart, Laguerre unpolished", Implicit::heart(LAGUERRE_PLAIN).unwrap()),
    ]
}

/// Rays at a surface's bounds: from outside aimed at a point inside, from inside in any
/// direction (as secondary rays leave a surface), and segments cut short.
fn rays_for(bounds: Aabb, n: usize, rng: &mut Pcg32) -> Vec<Ray> {
    let centre = 0.5 * (bounds.min + bounds.max);
    let half = 0.5 * (bounds.max - bounds.min);
    let diag = (bounds.max - bounds.min).length();
    let inside = |rng: &mut Pcg32| {
        centre + half * Vec3::new(rng.range_f32(-1.0, 1.0), rng.range_f32(-1.0, 1.0), rng.range_f32(-1.0, 1.0))
    };
    (0..n)
        .map(|k| {
            let dir = rng.unit_vector().as_vec3();
            match k % 4 {
                0 | 1 => {
                    let o = centre + 1.5 * diag * dir;
                    Ray::new(o, (inside(rng) - o) * rng.range_f32(0.2, 3.0))
                }
                2 => Ray::new(inside(rng), dir),
                _ => {
                    let o = centre + diag * dir;
                    Ray::segment(o, inside(rng) - o, 0.3, rng.range_f32(0.5, 1.2))
                }
            }
        })
        .collect()
}

/// The device's intersections of `rays` with the records at `records` (one per ray).
fn trace_on_device(ctx: &gpu::GpuContext, coeffs: u32, tables: &[f32], rays: &[(u32, Ray)]) -> Vec<[f32; 8]> {
    let device = &ctx.device;
    let source = format!("{}{}{TEST_KERNEL}", gpu::kernel::SHAPE_HIT_SOURCE, gpu::kernel::implicit_source(coeffs));
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("implicit test"),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("implicit test"),
        layout: None,
        module: &module,
        entry_point: Some("test_implicit"),
        compilation_options: Default::default(),
        cache: None,
    });
    if let Some(e) = pollster::block_on(scope.pop()) {
        panic!("the implicit-surface test kernel does not compile: {e}");
    }
    let words: Vec<f32> = rays
        .iter()
        .flat_map(|&(rec, r)| {
            let mut w = vec![f32::from_bits(rec)];
            w.extend(r.origin.to_array());
            w.extend(r.dir.to_array());
            w.extend([r.t_min, r.t_max.min(3.0e38)]);
            w
        })
        .collect();
    let input = |label: &str, data: &[f32]| {
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: bytemuck::cast_slice(data),
            usage: wgpu::BufferUsages::STORAGE,
        })
    };
    let (tables, rays_buffer) = (input("tables", tables), input("rays", &words));
    let size = (rays.len() * 8 * 4) as u64;
    let buffer =
        |usage| device.create_buffer(&wgpu::BufferDescriptor { label: None, size, usage, mapped_at_creation: false });
    let results = buffer(wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC);
    let readback = buffer(wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST);
    let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry { binding: 0, resource: tables.as_entire_binding() },
            wgpu::BindGroupEntry { binding: 1, resource: rays_buffer.as_entire_binding() },
            wgpu::BindGroupEntry { binding: 2, resource: results.as_entire_binding() },
        ],
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind, &[]);
        pass.dispatch_workgroups((rays.len() as u32).div_ceil(64), 1, 1);
    }
    encoder.copy_buffer_to_buffer(&results, 0, &readback, 0, size);
    ctx.queue.submit([encoder.finish()]);
    readback.map_async(wgpu::MapMode::Read, .., |r| r.expect("map"));
    device.poll(wgpu::PollType::wait_indefinitely()).expect("poll");
    let out: Vec<f32> = bytemuck::cast_slice(&readback.get_mapped_range(..).expect("mapped")).to_vec();
    out.chunks_exact(8).map(|c| c.try_into().unwrap()).collect()
}

/// How the device's hits for one surface compare with the CPU's.
#[derive(Debug, Default)]
struct Agreement {
    rays: usize,
    cpu_hits: usize,
    /// Rays that hit on one side only.
    hit_or_miss: usize,
    /// Common hits whose t differs by more than 10⁻⁵ relative, or whose point or normal
    /// differ (10⁻⁵ of the diagonal, 10⁻⁴ in the normal's direction).
    differ: usize,
    worst_t: f64,
}

fn agreement(surface: &Implicit, rays: &[Ray], device: &[[f32; 8]]) -> Agreement {
    let diag = (surface.bounds.max - surface.bounds.min).length();
    let mut a = Agreement { rays: rays.len(), ..Default::default() };
    for (ray, g) in rays.iter().zip(device) {
        let cpu = surface.intersect(ray);
        a.cpu_hits += cpu.is_some() as usize;
        match (cpu, g[0] == 1.0) {
            (Some(h), true) => {
                let (t, p, n) = (g[1], Vec3::new(g[2], g[3], g[4]), Vec3::new(g[5], g[6], g[7]));
                let dt = ((t - h.t).abs() / h.t.abs().max(1e-3)) as f64;
                a.worst_t = a.worst_t.max(dt);
                if dt > 1e-5 || (p - h.p).length() > 1e-5 * diag || n.dot(h.n) < 1.0 - 1e-4 {
                    a.differ += 1;
                }
            }
            (None, false) => {}
            _ => a.hit_or_miss += 1,
        }
    }
    a
}

#[test]
fn implicit_surfaces_are_hit_where_the_cpu_hits_them() {
    let Some(ctx) = gpu::require_gpu() else { return };
    if !ctx.shader_f64() {
        assert!(std::env::var_os("SPT_REQUIRE_GPU").is_none(), "{} lacks SHADER_F64", ctx.info.name);
        eprintln!("skipping: {} lacks SHADER_F64", ctx.info.name);
        return;
    }
    let surfaces = surfaces();
    let mut tables = Vec::new();
    let mut rays = Vec::new();
    let mut rng = Pcg32::seed_from_u64(2026);
    let per_surface = 2048;
    for (k, (_, s)) in surfaces.iter().enumerate() {
        let rec = tables.len() as u32;
        tables.extend(gpu::backend::shape_record(&ShapeKind::Implicit(s.clone()), 0, 0.0, k as u32));
        rays.extend(rays_for(s.bounds(), per_surface, &mut rng).into_iter().map(|r| (rec, r)));
    }
    let coeffs = surfaces.iter().map(|(_, s)| s.poly.degree() + 1).max().unwrap().max(5);
    let device = trace_on_device(&ctx, coeffs, &tables, &rays);
    let mut failures = Vec::new();
    for (k, (name, surface)) in surfaces.iter().enumerate() {
        let range = k * per_surface..(k + 1) * per_surface;
        let own: Vec<Ray> = rays[range.clone()].iter().map(|&(_, r)| r).collect();
        let a = agreement(surface, &own, &device[range]);
        println!("{name}: {a:?}");
        // Every surface is hit by a good share of the rays; all but a few grazing ones agree.
        if a.cpu_hits < a.rays / 8 || a.hit_or_miss + a.differ > a.rays / 500 {
            failures.push(format!("{name}: {a:?}"));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}
