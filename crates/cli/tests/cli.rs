//! The `spt` binary end to end: renders, and clear errors for bad input.

mod common;

use common::*;
use std::path::{Path, PathBuf};

/// The shared Cornell box (`CornellBox-Original.obj`), or `None`, with a message, where
/// the shared scenes are absent (the test is then skipped).
fn shared_cornell_box() -> Option<PathBuf> {
    let scene =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/scenes/cornell-box/CornellBox-Original.obj");
    if scene.exists() {
        Some(scene)
    } else {
        eprintln!("SKIPPED: {} is absent", scene.display());
        None
    }
}

#[test]
fn renders_png_exr_and_standard_error() {
    let dir = temp_dir("ok");
    let scene = write_scene(&dir, OBJ);
    let png = dir.join("out.png");
    let exr = dir.join("out.exr");
    let se = dir.join("se.exr");
    for (out, mode) in [(&png, "hero"), (&exr, "rgb")] {
        let o = spt(&[
            "render",
            scene.to_str().unwrap(),
            "--width",
            "24",
            "--height",
            "16",
            "--spp",
            "4",
            "--spectral",
            mode,
            "--eye",
            "0,0.5,3",
            "--center",
            "0,0.3,0",
            "-o",
            out.to_str().unwrap(),
            "--stderr",
            se.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(stderr(&o).contains("NaN/Inf samples dropped"), "{}", stderr(&o));
    }
    let img = image::open(&png).unwrap();
    assert_eq!((img.width(), img.height()), (24, 16));
    let lit = img.to_rgb8().pixels().filter(|p| p.0.iter().any(|&c| c > 0)).count();
    assert!(lit > 40, "the lit floor should be visible: {lit} non-black pixels");
    let exr_img = image::open(&exr).unwrap().into_rgb32f();
    assert!(exr_img.pixels().any(|p| p.0[1] > 0.0));
    assert!(image::open(&se).is_ok());
}

#[test]
fn renders_the_shared_cornell_box_with_defaults_but_small() {
    let Some(scene) = shared_cornell_box() else { return };
    let out = temp_dir("cornell").join("cornell.png");
    let o = spt(&[
        "render",
        scene.to_str().unwrap(),
        "--width",
        "32",
        "--height",
        "32",
        "--spp",
        "2",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("36 triangles, 0 shapes, 2 emissive"), "{}", stderr(&o));
    // Diffuse triangles: the path tracer runs in lanes, and says so, unless told not to.
    assert!(stderr(&o).contains("cpu backend (lanes)"), "{}", stderr(&o));
    assert!(out.exists());
    let o = spt(&["render", scene.to_str().unwrap(), "--width", "8", "--height", "8", "--spp", "1", "--no-lanes"]
        .into_iter()
        .chain(["-o", out.to_str().unwrap()])
        .collect::<Vec<_>>());
    assert!(o.status.success() && !stderr(&o).contains("(lanes)"), "{}", stderr(&o));
}

/// The box's walls, floor and ceiling (its hull's faces) are left out of shadow rays; a
/// point light above the ceiling keeps the ceiling in, which stands between it and the room.
#[test]
fn shadow_rays_leave_out_the_cornell_boxs_walls_but_not_a_wall_a_light_is_behind() {
    let Some(scene) = shared_cornell_box() else { return };
    let out = temp_dir("hull").join("hull.png");
    let render = |extra: &[&str]| {
        let mut a = vec!["render", scene.to_str().unwrap(), "--width", "8", "--height", "8", "--spp", "1"];
        a.extend_from_slice(extra);
        a.extend(["-o", out.to_str().unwrap()]);
        let o = spt(&a);
        assert!(o.status.success(), "{}", stderr(&o));
        stderr(&o)
    };
    // Floor, ceiling and three walls: 10 triangles (this file's boxes have no bottoms).
    let msg = render(&[]);
    assert!(msg.contains("(10 on the hull left out of shadow rays)"), "{msg}");
    let msg = render(&["--light", "point:0,3,5:1"]);
    assert!(msg.contains("(8 on the hull left out of shadow rays)"), "{msg}");
}

/// Point, spot and directional lights keep a scene of diffuse triangles in the lanes,
/// whose image is the general loop's to the byte; a sun disk (which escaping paths see)
/// sends it to the general loop.
#[test]
fn punctual_lights_render_in_lanes_as_in_the_general_loop() {
    let Some(scene) = shared_cornell_box() else { return };
    let dir = temp_dir("punctual-lanes");
    let lights = [
        "--light",
        "point:0.2,1.5,0.3:0.8,0.6,0.4",
        "--light",
        "spot:-0.5,1.7,0.5:0.2,-1,-0.3:15,30:5",
        "--light",
        "sun:0,-1,-1:2",
    ];
    let render = |name: &str, extra: &[&str]| {
        let out = dir.join(name);
        let mut a = vec!["render", scene.to_str().unwrap(), "--width", "24", "--height", "24", "--spp", "4"];
        a.extend_from_slice(&lights);
        a.extend_from_slice(extra);
        a.extend(["-o", out.to_str().unwrap()]);
        let o = spt(&a);
        assert!(o.status.success(), "{}", stderr(&o));
        (stderr(&o), std::fs::read(out).unwrap())
    };
    let (msg, lanes) = render("lanes.exr", &[]);
    assert!(msg.contains("2 emissive + 3 punctual") && msg.contains("cpu backend (lanes)"), "{msg}");
    let (msg, general) = render("general.exr", &["--no-lanes"]);
    assert!(!msg.contains("(lanes)"), "{msg}");
    assert!(lanes == general, "the lanes' image differs from the general loop's");
    let (msg, _) = render("sun.exr", &["--light", "sun:0,-1,-1:2:0.53"]);
    assert!(!msg.contains("(lanes)"), "a sun disk: {msg}");
}

#[test]
fn missing_file_is_a_clear_error() {
    let o = spt(&["render", "/nonexistent/scene.obj", "-o", "/tmp/x.png"]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(e.contains("/nonexistent/scene.obj") && e.to_lowercase().contains("no such file"), "{e}");
}

#[test]
fn malformed_obj_names_file_and_line() {
    let dir = temp_dir("bad");
    let bad = OBJ.replace("v 1 0 1\n", "v 1 zero 1\n");
    let scene = write_scene(&dir, &bad);
    let o = spt(&["render", scene.to_str().unwrap(), "-o", dir.join("x.png").to_str().unwrap()]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(e.contains("scene.obj:4:") && e.contains("'zero' is not a number"), "{e}");

    let bad = OBJ.replace("f 8 7 6 5", "f 9 7 6 5");
    let scene = write_scene(&dir, &bad);
    let o = spt(&["render", scene.to_str().unwrap(), "-o", dir.join("x.png").to_str().unwrap()]);
    let e = stderr(&o);
    assert!(!o.status.success() && e.contains("scene.obj:13:") && e.contains("out of range"), "{e}");
}

#[test]
fn malformed_mtl_names_file_and_line() {
    let dir = temp_dir("badmtl");
    let scene = write_scene(&dir, OBJ);
    std::fs::write(dir.join("scene.mtl"), MTL.replace("Ke 10 10 10", "Ke 10 ten 10")).unwrap();
    let o = spt(&["render", scene.to_str().unwrap(), "-o", dir.join("x.png").to_str().unwrap()]);
    let e = stderr(&o);
    assert!(!o.status.success() && e.contains("scene.mtl:5:"), "{e}");
}

#[test]
fn out_of_range_colours_name_the_material() {
    let dir = temp_dir("range");
    let scene = write_scene(&dir, OBJ);
    std::fs::write(dir.join("scene.mtl"), MTL.replace("Kd 0.8 0.8 0.8", "Kd 1.8 0.8 0.8")).unwrap();
    let o = spt(&["render", scene.to_str().unwrap(), "-o", dir.join("x.png").to_str().unwrap()]);
    let e = stderr(&o);
    assert!(!o.status.success() && e.contains("material 'white'") && e.contains("[0, 1]"), "{e}");
}

#[test]
fn absurd_settings_are_rejected() {
    let dir = temp_dir("settings");
    let scene = write_scene(&dir, OBJ);
    let s = scene.to_str().unwrap();
    let out = dir.join("x.png");
    let o = out.to_str().unwrap();
    for (args, needle) in [
        (vec!["render", s, "--spp", "0", "-o", o], "samples per pixel"),
        (vec!["render", s, "--width", "0", "-o", o], "image size"),
        (vec!["render", s, "--width", "100000", "-o", o], "image size"),
        (vec!["render", s, "--fov", "200", "-o", o], "field of view"),
        (vec!["render", s, "--eye", "0,0,0", "--center", "0,0,0", "-o", o], "coincide"),
        (vec!["render", s, "-o", dir.join("x.jpg").to_str().unwrap()], "unsupported image extension"),
        (vec!["render", s, "--stderr", dir.join("se.png").to_str().unwrap(), "-o", o], "must be an .exr"),
        (vec!["render", s, "--eye", "1,2", "-o", o], "expected x,y,z"),
        (vec!["render", s, "--spectral", "cmyk", "-o", o], "unknown spectral mode"),
        (vec!["render", s, "--rr-scale", "0", "-o", o], "Russian roulette scale 0 must be above 0 and at most 100"),
        (vec!["render", s, "--rr-scale", "-1", "-o", o], "Russian roulette scale -1 must be above 0"),
        (vec!["render", s, "--rr-scale", "inf", "-o", o], "Russian roulette scale inf must be above 0"),
        (vec!["render", s, "--rr-scale", "NaN", "-o", o], "Russian roulette scale NaN must be above 0"),
        (vec!["render", dir.join("scene.fbx").to_str().unwrap(), "-o", o], "unsupported scene format"),
    ] {
        let r = spt(&args);
        assert!(!r.status.success(), "{args:?} should fail");
        assert!(stderr(&r).contains(needle), "{args:?}: {}", stderr(&r));
    }
}

#[test]
fn renders_built_in_shape_scenes_and_rejects_unknown_ones() {
    let out = temp_dir("flake").join("flake.png");
    let o = spt(&[
        "render",
        "builtin:sphereflake:2",
        "--width",
        "24",
        "--height",
        "16",
        "--spp",
        "2",
        "--triangle-test",
        "moller-trumbore",
        "--shading-normals",
        "face-forward",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("0 triangles, 93 shapes, 1 emissive"), "{}", stderr(&o));
    assert!(stderr(&o).contains(" 0 NaN/Inf"), "{}", stderr(&o));
    assert_eq!(image::open(&out).unwrap().width(), 24);
    let o = spt(&["render", "builtin:teapot", "-o", out.to_str().unwrap()]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("unknown built-in scene 'teapot'"), "{}", stderr(&o));
    let o = spt(&["render", "builtin:sphereflake:x", "-o", out.to_str().unwrap()]);
    assert!(!o.status.success() && stderr(&o).contains("not a whole number"), "{}", stderr(&o));
    let o = spt(&["render", "builtin:sphereflake:1", "--triangle-test", "fast", "-o", out.to_str().unwrap()]);
    assert!(!o.status.success() && stderr(&o).contains("unknown triangle test 'fast'"), "{}", stderr(&o));
}

#[test]
fn gpu_backend_renders_through_the_same_command_or_explains_itself() {
    let Some(scene) = shared_cornell_box() else { return };
    let out = temp_dir("gpu").join("cornell.png");
    let args = ["render", scene.to_str().unwrap(), "--backend", "gpu", "--width", "16", "--height", "16"];
    let o = spt(&[&args[..], &["--spp", "2", "-o", out.to_str().unwrap()]].concat());
    if gpu::require_gpu().is_none() {
        assert!(!o.status.success());
        assert!(stderr(&o).contains("--backend cpu"), "{}", stderr(&o));
        return;
    }
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("gpu backend") && stderr(&o).contains(" 0 NaN/Inf"), "{}", stderr(&o));
    assert_eq!(image::open(&out).unwrap().width(), 16);
    // What the GPU cannot do is an error that names the way out.
    let o = spt(&[&args[..], &["--max-depth", "1000", "-o", out.to_str().unwrap()]].concat());
    assert!(
        !o.status.success() && stderr(&o).contains("--backend cpu") && stderr(&o).contains("256"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn every_sampler_renders_and_unknown_ones_are_named() {
    let dir = temp_dir("samplers");
    let scene = write_scene(&dir, OBJ);
    let mut images = Vec::new();
    for sampler in ["independent", "sobol", "zsobol"] {
        let out = dir.join(format!("{sampler}.exr"));
        let o = render_small(&scene, (16, 16, 8), &out, &["--sampler", sampler]);
        assert!(o.status.success(), "{sampler}: {}", stderr(&o));
        images.push(std::fs::read(&out).unwrap());
    }
    assert!(images[0] != images[1] && images[1] != images[2], "the samplers draw different values");
    let o = spt(&["render", scene.to_str().unwrap(), "--sampler", "halton"]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(e.contains("unknown sampler 'halton'") && e.contains("zsobol"), "{e}");
}

/// Reads a hits file: (triangle or u32::MAX, t) per ray, t as its bits (NaN for misses
/// and shadow rays).
fn read_hits(path: &Path) -> Vec<(u32, u32)> {
    let bytes = std::fs::read(path).unwrap();
    assert_eq!(bytes.len() % 16, 0, "{}", path.display());
    bytes
        .chunks_exact(16)
        .map(|r| (u32::from_le_bytes(r[0..4].try_into().unwrap()), u32::from_le_bytes(r[4..8].try_into().unwrap())))
        .collect()
}

/// `spt rays export SCENE --out SETS` at `width`×`height`, with `extra` options.
fn export_rays(scene: &Path, sets: &Path, (width, height): (u32, u32), extra: &[&str]) -> std::process::Output {
    let (w, h) = (width.to_string(), height.to_string());
    let args =
        ["rays", "export", scene.to_str().unwrap(), "--out", sets.to_str().unwrap(), "--width", &w, "--height", &h];
    spt(&[&args[..], extra].concat())
}

#[test]
fn ray_sets_export_and_trace_with_both_widths_alike() {
    let dir = temp_dir("rays");
    let scene = write_scene(&dir, OBJ);
    let sets = dir.join("sets");
    let o = export_rays(&scene, &sets, (32, 24), &["--subdivide", "1"]);
    assert!(o.status.success(), "{}", stderr(&o));
    // Two quads = four triangles, subdivided once: 16.
    assert_eq!(std::fs::metadata(sets.join("triangles.f32")).unwrap().len(), 16 * 36);
    assert_eq!(std::fs::metadata(sets.join("primary.rays")).unwrap().len(), 32 * 24 * 32);
    let mut hits = Vec::new();
    for (width, accel) in [("4", "bvh4"), ("8", "bvh8")] {
        let o =
            spt(&["rays", "trace", sets.to_str().unwrap(), "--bvh-width", width, "--passes", "1", "--threads", "2"]);
        assert!(o.status.success(), "{}", stderr(&o));
        let json = String::from_utf8_lossy(&o.stdout);
        assert!(json.contains(&format!(r#""tracer": "{accel}""#)) && json.contains(r#""triangles": 16"#), "{json}");
        let primary = read_hits(&sets.join(format!("primary.{accel}.hits")));
        assert_eq!(primary.len(), 32 * 24);
        let hit = primary.iter().filter(|h| h.0 != u32::MAX).count();
        assert!(
            hit > 100 && primary.iter().all(|h| h.0 == u32::MAX || (h.0 < 16 && f32::from_bits(h.1) > 0.0)),
            "{hit} hits"
        );
        let diffuse = read_hits(&sets.join(format!("diffuse.{accel}.hits")));
        let shadow = read_hits(&sets.join(format!("shadow.{accel}.hits")));
        assert_eq!((diffuse.len(), shadow.len()), (hit, hit), "one secondary ray per primary hit");
        hits.push((primary, diffuse, shadow));
    }
    assert!(hits[0] == hits[1], "4- and 8-wide trees find the same hits");
    // Every set in packets of 16: the same answers.
    for (width, accel) in [("4", "bvh4"), ("8", "bvh8")] {
        let o = spt(&["rays", "trace", sets.to_str().unwrap(), "--bvh-width", width, "--passes", "1", "--packet"]);
        assert!(o.status.success(), "{}", stderr(&o));
        let set = |name: &str| read_hits(&sets.join(format!("{name}.{accel}.hits")));
        assert!((set("primary"), set("diffuse"), set("shadow")) == hits[0], "{width}-wide packets");
    }
    // Counted: work per ray in each set's JSON.
    let o = spt(&["rays", "trace", sets.to_str().unwrap(), "--passes", "1", "--no-write", "--count"]);
    let json = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success() && json.matches(r#""nodes_per_ray": "#).count() == 3, "{json}");
    // A truncated ray file is refused with its name.
    let rays = std::fs::read(sets.join("diffuse.rays")).unwrap();
    std::fs::write(sets.join("diffuse.rays"), &rays[..rays.len() - 3]).unwrap();
    let o = spt(&["rays", "trace", sets.to_str().unwrap(), "--passes", "1"]);
    assert!(!o.status.success() && stderr(&o).contains("diffuse.rays"), "{}", stderr(&o));
    let o = spt(&["rays", "trace", dir.join("nowhere").to_str().unwrap()]);
    assert!(!o.status.success() && stderr(&o).contains("triangles.f32"), "{}", stderr(&o));
}

#[test]
fn ray_sets_trace_with_pre_split_long_triangles() {
    // 64 small triangles on a floor and one long diagonal triangle across the scene, which
    // `--presplit` cuts into references: more leaf entries, the same hits.
    let dir = temp_dir("presplit");
    let mut obj = String::new();
    for i in 0..8 {
        for j in 0..8 {
            let (x, y) = (i as f32, j as f32);
            obj += &format!("v {x} {y} 0\nv {} {y} 0\nv {x} {} 0\n", x + 0.5, y + 0.5);
        }
    }
    obj += "v 0 0 0.5\nv 8 8 4\nv 8 8 4.5\n";
    for k in 0..65 {
        obj += &format!("f {} {} {}\n", 3 * k + 1, 3 * k + 2, 3 * k + 3);
    }
    let scene = dir.join("long.obj");
    std::fs::write(&scene, obj).unwrap();
    let sets = dir.join("sets");
    let o = export_rays(&scene, &sets, (48, 48), &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let references = |extra: &[&str]| {
        let o =
            spt(&[&["rays", "trace", sets.to_str().unwrap(), "--bvh-width", "8", "--passes", "1"][..], extra].concat());
        assert!(o.status.success(), "{}", stderr(&o));
        let json = String::from_utf8_lossy(&o.stdout).to_string();
        let n: usize = json.split(r#""references": "#).nth(1).and_then(|s| s.split(',').next()?.parse().ok()).unwrap();
        (n, read_hits(&sets.join("primary.bvh8.hits")), json)
    };
    let (whole, hits, json) = references(&[]);
    assert_eq!(whole, 65, "{json}");
    let (split, split_hits, json) = references(&["--presplit", "0.5"]);
    assert!(split > 65, "{split} references with pre-splitting: {json}");
    assert!(split_hits == hits, "pre-splitting changed the primary hits");
    let o = spt(&["rays", "trace", sets.to_str().unwrap(), "--presplit", "5"]);
    assert!(!o.status.success() && stderr(&o).contains("between 0 and 4"), "{}", stderr(&o));
}

#[test]
fn bvh_width_is_chosen_or_refused_with_the_way_out() {
    let dir = temp_dir("width");
    let scene = write_scene(&dir, OBJ);
    let mut images = Vec::new();
    for width in ["4", "8", "auto"] {
        let out = dir.join(format!("w{width}.exr"));
        let o = render_small(&scene, (16, 12, 4), &out, &["--bvh-width", width]);
        assert!(o.status.success(), "{}", stderr(&o));
        images.push(std::fs::read(&out).unwrap());
    }
    assert!(images[0] == images[1] && images[1] == images[2], "the width changes speed, not the image");
    let o = spt(&["render", scene.to_str().unwrap(), "--bvh-width", "16"]);
    assert!(!o.status.success() && stderr(&o).contains("unknown BVH width '16'"), "{}", stderr(&o));
    // The binary tree is the GPU's: the CPU refuses it and names the ways out.
    let o = render_small(&scene, (16, 12, 4), &dir.join("w2.exr"), &["--bvh-width", "2"]);
    let err = stderr(&o);
    assert!(!o.status.success() && err.contains("2-wide") && err.contains("--backend gpu"), "{err}");
    // The wavefront is the GPU path tracer's schedule: the CPU refuses it by name.
    let o = render_small(&scene, (16, 12, 4), &dir.join("wf.exr"), &["--wavefront"]);
    let err = stderr(&o);
    assert!(!o.status.success() && err.contains("wavefront") && err.contains("--backend gpu"), "{err}");
}

#[test]
fn simd_levels_render_the_same_image_and_a_level_the_cpu_lacks_is_refused() {
    let dir = temp_dir("simd");
    let scene = write_scene(&dir, OBJ);
    // The same detection as the binary's (the cli crate's own dependency).
    let has = |level: &str| bvh::isa::Isa::ALL.iter().any(|i| i.name() == level && *i <= bvh::isa::detected());
    let mut images = Vec::new();
    for (level, tree) in [("baseline", "4-wide BVH"), ("avx2", "8-wide BVH (AVX2)"), ("avx512", "8-wide BVH (AVX-512)")]
    {
        let out = dir.join(format!("{level}.exr"));
        let o = render_small(&scene, (16, 12, 8), &out, &["--simd", level, "--bvh-width", "auto"]);
        if has(level) {
            assert!(o.status.success() && stderr(&o).contains(tree), "{level}: {}", stderr(&o));
            images.push(std::fs::read(&out).unwrap());
        } else {
            let e = stderr(&o);
            assert!(!o.status.success() && e.contains(&format!("--simd {level}: this CPU runs at most")), "{e}");
            println!("this CPU has no {level}: only its refusal is checked");
        }
    }
    // The lanes' builds are bit-identical (the lanes' own test); the trees of either width
    // find the same hits on this scene.
    assert!(images.windows(2).all(|w| w[0] == w[1]), "the vector width changes speed, not the image");
    let o = spt(&["render", scene.to_str().unwrap(), "--simd", "neon"]);
    assert!(!o.status.success() && stderr(&o).contains("invalid value 'neon'"), "{}", stderr(&o));
}

/// `--light-sampler`: the hall of 64 lamps renders with the tree and by power to the
/// same mean, a value that is not one is refused, and the GPU (where there is one) takes
/// the tree too, says so and renders the CPU's image (its paths follow the CPU's for the
/// same seed: tested pixel by pixel in the gpu crate's equivalence tests), while its bdpt,
/// which chooses by power, refuses it with the way out.
#[test]
fn light_samplers_render_the_same_light_on_both_backends() {
    let dir = temp_dir("light-sampler");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/many-lights.toml");
    let mut means = Vec::new();
    for sampler in ["tree", "power"] {
        let out = dir.join(format!("{sampler}.exr"));
        let o = render_small(&scene, (32, 24, 64), &out, &["--light-sampler", sampler, "--seed", "3"]);
        assert!(o.status.success(), "{sampler}: {}", stderr(&o));
        assert_eq!(stderr(&o).contains("chosen by a light tree"), sampler == "tree", "{}", stderr(&o));
        means.push(exr_means(&out));
    }
    for c in 0..3 {
        // Image means of 49,152 samples each, measured 0.3 % apart at most (the
        // pixel-by-pixel test is tests/tests/light_tree.rs; this is the CLI's path to it).
        let (a, b) = (means[0][c], means[1][c]);
        assert!((a - b).abs() < 0.025 * b, "channel {c}: tree {a}, power {b}");
    }
    let o = spt(&["render", scene.to_str().unwrap(), "--light-sampler", "nearest"]);
    assert!(!o.status.success() && stderr(&o).contains("auto, power or tree"), "{}", stderr(&o));
    if gpu::require_gpu().is_some() {
        let out = dir.join("gpu.exr");
        let o =
            render_small(&scene, (32, 24, 64), &out, &["--backend", "gpu", "--light-sampler", "tree", "--seed", "3"]);
        assert!(o.status.success() && stderr(&o).contains("chosen by a light tree"), "{}", stderr(&o));
        let gpu = exr_means(&out);
        for c in 0..3 {
            // The same seed: the CPU's paths, to rounding (measured 10⁻⁵ apart).
            assert!((gpu[c] - means[0][c]).abs() < 0.002 * means[0][c], "channel {c}: gpu {gpu:?}, cpu {:?}", means[0]);
        }
        let bdpt = ["--backend", "gpu", "--integrator", "bdpt", "--light-sampler", "tree"];
        let o = render_small(&scene, (8, 6, 1), &dir.join("bdpt.exr"), &bdpt);
        let err = stderr(&o);
        assert!(!o.status.success() && err.contains("light tree") && err.contains("--light-sampler"), "{err}");
    }
}

/// Point lights and spots join the tree: the hall of 64 of them renders with the tree by
/// default (`auto`) and says so, lit (a tree that dropped them would leave it black),
/// and by power on request; the tree on the GPU too where one is usable (its same-seed
/// paths are `the_light_tree_chooses_as_on_the_cpu`'s, crates/gpu/tests/equivalence.rs).
#[test]
fn point_and_spot_lights_are_chosen_by_the_light_tree() {
    let dir = temp_dir("point-lights");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/many-point-lights.toml");
    let gpu = gpu::require_gpu().is_some();
    let cases = [("cpu", "auto", true), ("cpu", "power", false), ("gpu", "auto", true)];
    for (backend, sampler, tree) in cases.into_iter().filter(|&(b, ..)| b == "cpu" || gpu) {
        let out = dir.join(format!("{backend}-{sampler}.exr"));
        let args = ["--backend", backend, "--light-sampler", sampler];
        let o = render_small(&scene, (16, 12, 4), &out, &args);
        let err = stderr(&o);
        assert!(o.status.success() && err.contains("0 emissive + 64 punctual"), "{backend}, {sampler}: {err}");
        assert_eq!(err.contains("(chosen by a light tree)"), tree, "{backend}, {sampler}: {err}");
        assert!(exr_means(&out)[1] > 0.01, "{backend}, {sampler}: a dark hall");
    }
}

/// Mean of each channel of a linear EXR.
fn exr_means(path: &Path) -> [f64; 3] {
    let img = image::open(path).unwrap().into_rgb32f();
    let n = (img.width() * img.height()) as f64;
    let mut sum = [0.0f64; 3];
    for p in img.pixels() {
        for c in 0..3 {
            sum[c] += p[c] as f64;
        }
    }
    sum.map(|s| s / n)
}

/// A 2×2 square of grey (ρ 0.5) at z = 0 facing +z, with no light: `DIR/square.obj`.
fn grey_square(dir: &Path) -> PathBuf {
    std::fs::write(dir.join("grey.mtl"), "newmtl grey\nKd 0.5 0.5 0.5\n").unwrap();
    let scene = dir.join("square.obj");
    std::fs::write(&scene, "mtllib grey.mtl\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nusemtl grey\nf 1 2 3 4\n")
        .unwrap();
    scene
}

/// A scene without lights (here a grey square, as most downloaded OBJs are unlit) is lit
/// by the documented default — a uniform white sky of luminance 1, under which a
/// Lambertian surface of albedo ρ has radiance ρ — with a warning; `--sky none` leaves it
/// black (and says so), `--sky white:L` scales it.
#[test]
fn scenes_without_lights_get_the_white_sky_unless_told_otherwise() {
    let dir = temp_dir("sky");
    let scene = grey_square(&dir);
    let out = dir.join("square.exr");
    for (sky, expected) in [(None, 0.5), (Some("white"), 0.5), (Some("white:2"), 1.0), (Some("none"), 0.0)] {
        // Close enough that the square fills the frame.
        let mut extra = vec!["--eye", "0,0,1", "--center", "0,0,0"];
        extra.extend(sky.map(|s| ["--sky", s]).into_iter().flatten());
        let o = render_small(&scene, (24, 16, 16), &out, &extra);
        assert!(o.status.success(), "{}", stderr(&o));
        let means = exr_means(&out);
        for m in means {
            assert!((m - expected).abs() < 0.02 * expected.max(0.05), "--sky {sky:?}: {means:?}, expected {expected}");
        }
        let warned = stderr(&o);
        match sky {
            None => assert!(warned.contains("lit by a uniform white sky"), "{warned}"),
            Some("none") => assert!(warned.contains("the image will be black"), "{warned}"),
            _ => assert!(!warned.contains("warning"), "{warned}"),
        }
    }
    for bad in ["purple", "white:0", "white:-1", "white:x"] {
        let o = render_small(&scene, (4, 4, 1), &out, &["--sky", bad]);
        assert!(!o.status.success() && stderr(&o).contains("unknown sky"), "{bad}: {}", stderr(&o));
    }
}

/// `--light`: a sun shining straight at a grey square (ρ 0.5) gives it the radiance
/// ρ/π · E everywhere, with no default sky added; a point light lights it too; malformed
/// lights are refused with the syntax, and the GPU refuses lights it cannot sample.
#[test]
fn lights_from_the_command_line() {
    let dir = temp_dir("lights");
    let scene = grey_square(&dir);
    let out = dir.join("sun.exr");
    let o =
        render_small(&scene, (24, 16, 16), &out, &["--eye", "0,0,1", "--center", "0,0,0", "--light", "sun:0,0,-1:2"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stderr(&o).contains("warning"), "{}", stderr(&o));
    let expected = 0.5 / std::f64::consts::PI * 2.0;
    for m in exr_means(&out) {
        assert!((m - expected).abs() < 0.02 * expected, "sun: {:?}, expected {expected}", exr_means(&out));
    }
    let o = render_small(
        &scene,
        (8, 8, 4),
        &out,
        &[
            "--eye",
            "0,0,1",
            "--center",
            "0,0,0",
            "--light",
            "point:0,0,0.5:1,0.5,0.25",
            "--light=spot:0,0,1:0,0,-1:5,10:1",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let means = exr_means(&out);
    assert!(means[0] > means[1] && means[1] > means[2] && means[2] > 0.0, "{means:?}");
    for (bad, says) in [("torch:0,0,0:1", "unknown light kind"), ("point:0,0,0:x", "not a number")] {
        let o = render_small(&scene, (4, 4, 1), &out, &["--light", bad]);
        let msg = stderr(&o);
        assert!(!o.status.success() && msg.contains(says) && msg.contains("point:X,Y,Z:I"), "{bad}: {msg}");
    }
    // The GPU samples punctual lights too: the sun's closed form again.
    if gpu::require_gpu().is_some() {
        let sun = ["--eye", "0,0,1", "--center", "0,0,0", "--light", "sun:0,0,-1:2", "--backend", "gpu"];
        let o = render_small(&scene, (24, 16, 16), &out, &sun);
        assert!(o.status.success(), "{}", stderr(&o));
        let expected = 0.5 / std::f64::consts::PI * 2.0;
        for m in exr_means(&out) {
            assert!((m - expected).abs() < 0.02 * expected, "gpu sun: {:?}, expected {expected}", exr_means(&out));
        }
    }
}

/// `--integrator path|direct|ao` from the command line: each renders; ao of the open
/// scene is grey and grows as its reach shrinks, direct of the lit scene is darker than path
/// (no indirect light) but not black; unknown names, bad distances and a backend without
/// the integrator are refused with the way out.
#[test]
fn integrators_are_chosen_by_name() {
    let dir = temp_dir("integrators");
    let scene = write_scene(&dir, OBJ);
    let mut means = Vec::new();
    for name in ["path", "direct", "ao", "whitted", "bdpt", "atlas"] {
        let out = dir.join(format!("{name}.exr"));
        let o = render_small(&scene, (16, 16, 32), &out, &["--integrator", name, "--spectral", "rgb"]);
        assert!(o.status.success(), "{name}: {}", stderr(&o));
        means.push(exr_means(&out)[1]);
    }
    let (path, direct, ao, whitted, bdpt, atlas) = (means[0], means[1], means[2], means[3], means[4], means[5]);
    // One bounce of indirect light: more than direct light alone, less than all bounces.
    assert!(direct < atlas && atlas < path * 1.05, "atlas {atlas} vs direct {direct} and path {path}");
    // Bidirectional path tracing estimates what path tracing does (tests/tests/bdpt.rs
    // tests it pixel by pixel; here the image mean of a tiny render).
    assert!((bdpt / path - 1.0).abs() < 0.1, "bdpt {bdpt} vs path {path}");
    assert!(0.0 < direct && direct < path, "direct {direct} vs path {path}");
    // Whitted sees direct light only on this scene's diffuse surfaces.
    assert!(0.0 < whitted && whitted < path, "whitted {whitted} vs path {path}");
    assert!(ao > 0.0 && ao <= 1.0, "ao {ao}");
    // A short reach sees fewer occluders.
    let near = dir.join("near.exr");
    let o = render_small(
        &scene,
        (16, 16, 32),
        &near,
        &["--integrator", "ao", "--ao-distance", "0.01", "--spectral", "rgb"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(exr_means(&near)[1] >= ao, "{} vs {ao}", exr_means(&near)[1]);
    let out = dir.join("x.png");
    for (extra, expected) in [
        (vec!["--integrator", "mlt"], "invalid value 'mlt'"),
        (vec!["--integrator", "ao", "--ao-distance=-1"], "positive distance"),
        (vec!["--integrator", "ao", "--ao-distance", "0"], "positive distance"),
        (vec!["--integrator", "atlas", "--atlas-samples", "0"], "atlas samples 0"),
        (vec!["--integrator", "atlas", "--atlas-resolution", "4"], "atlas resolution 4"),
    ] {
        let o = render_small(&scene, (4, 4, 1), &out, &extra);
        let msg = stderr(&o);
        assert!(!o.status.success() && msg.contains(expected), "{extra:?}: {msg}");
    }
    // Its splats land anywhere on the image: a band of rows cannot be a shard.
    let partial = dir.join("x.partial");
    let o =
        render_small(&scene, (4, 4, 1), &partial, &["--integrator", "bdpt", "--shard", "1/2", "--shard-by", "tiles"]);
    let msg = stderr(&o);
    assert!(!o.status.success() && msg.contains("shard it by samples"), "{msg}");
    // The GPU runs direct, ao, whitted, atlas and bdpt too (its equivalence tests compare
    // them with the CPU's).
    if gpu::require_gpu().is_some() {
        for integrator in ["direct", "ao", "whitted", "atlas"] {
            let o = render_small(&scene, (8, 8, 4), &out, &["--integrator", integrator, "--backend", "gpu"]);
            assert!(o.status.success(), "{integrator}: {}", stderr(&o));
        }
        // Whitted's recursion is bounded by the kernel's stack.
        let o = render_small(
            &scene,
            (8, 8, 4),
            &out,
            &["--integrator", "whitted", "--backend", "gpu", "--max-depth", "17"],
        );
        assert!(!o.status.success() && stderr(&o).contains("at most 16"), "{}", stderr(&o));
        // Bidirectional path tracing, light tracing's splats included, on the device.
        let gpu_bdpt = dir.join("gpu-bdpt.exr");
        let o = render_small(
            &scene,
            (16, 16, 32),
            &gpu_bdpt,
            &["--integrator", "bdpt", "--spectral", "rgb", "--backend", "gpu"],
        );
        assert!(o.status.success(), "gpu bdpt: {}", stderr(&o));
        let m = exr_means(&gpu_bdpt)[1];
        assert!((m / path - 1.0).abs() < 0.1, "gpu bdpt {m} vs path {path}");
        // Its splats too land anywhere: no band of rows as a shard on the device either.
        let o = render_small(
            &scene,
            (4, 4, 1),
            &partial,
            &["--integrator", "bdpt", "--backend", "gpu", "--shard", "1/2", "--shard-by", "tiles"],
        );
        let msg = stderr(&o);
        assert!(!o.status.success() && msg.contains("--integrator bdpt splats"), "{msg}");
        // The GPU's path tracer builds its tree by any split method and at any width, and
        // limits diffuse bounces as the CPU's does; other integrators refuse the limit on
        // both backends.
        for extra in [["--bvh-builder", "midpoint"], ["--bvh-width", "8"], ["--max-diffuse-depth", "2"]] {
            let o = render_small(&scene, (8, 8, 4), &out, &[&["--backend", "gpu"][..], &extra].concat());
            assert!(o.status.success(), "{extra:?}: {}", stderr(&o));
        }
        let o = render_small(
            &scene,
            (8, 8, 4),
            &out,
            &["--backend", "gpu", "--integrator", "ao", "--max-diffuse-depth", "2"],
        );
        assert!(!o.status.success() && stderr(&o).contains("--max-diffuse-depth"), "{}", stderr(&o));
    }
}

/// `spt compare` end to end: a rendered reference, six configurations at 1, 2, 4, 8 spp,
/// a CSV row per render with falling error for the unbiased one, and both charts; a
/// reference of the wrong size and unknown configurations are refused.
#[test]
fn compare_charts_error_against_time() {
    let dir = temp_dir("compare");
    let scene = write_scene(&dir, OBJ);
    let out = dir.join("cmp");
    let args = ["compare", scene.to_str().unwrap(), "--width", "24", "--height", "16", "--spp-max", "8"];
    let o = spt(
        &[&args[..], &["--reference-spp", "256", "--configs", "integrators", "-o", out.to_str().unwrap()]].concat()
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let csv = std::fs::read_to_string(out.join("compare.csv")).unwrap();
    let rows: Vec<Vec<&str>> = csv.lines().skip(1).map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 24, "{csv}");
    let error = |config: &str, spp: &str| -> f64 {
        rows.iter().find(|r| r[0] == config && r[1] == spp).unwrap()[4].parse().unwrap()
    };
    assert!(error("path", "8") < error("path", "1"), "{csv}");
    assert!(error("bdpt", "8") < error("bdpt", "1"), "{csv}");
    for r in &rows {
        let (ssim, flip): (f64, f64) = (r[5].parse().unwrap(), r[6].parse().unwrap());
        assert!(ssim > 0.0 && ssim <= 1.0 && (0.0..1.0).contains(&flip), "{csv}");
    }
    let flip = |config: &str, spp: &str| -> f64 {
        rows.iter().find(|r| r[0] == config && r[1] == spp).unwrap()[6].parse().unwrap()
    };
    assert!(flip("path", "8") < flip("path", "1"), "{csv}");
    assert!(std::fs::metadata(out.join("compare.svg")).unwrap().len() > 1000);
    assert!(image::open(out.join("compare.png")).is_ok());
    // A convergence strip per configuration (a 16-pixel crop at 1, 2, 4, 8 spp and the
    // reference) and a heat map of its error at the largest budget.
    for config in ["path", "path-caustics", "bdpt", "atlas", "direct", "whitted"] {
        let strip = image::open(out.join(format!("strip-{config}.png"))).unwrap();
        assert_eq!((strip.width(), strip.height()), (5 * 16, 16), "{config}");
        let heat = image::open(out.join(format!("heat-{config}.png"))).unwrap().into_rgb8();
        assert_eq!(heat.dimensions(), (24, 16), "{config}");
    }
    // The strip ends with the reference's centred crop (columns 4..20), sRGB-encoded.
    let reference = image::open(out.join("reference.exr")).unwrap().into_rgb32f();
    let strip = image::open(out.join("strip-path.png")).unwrap().into_rgb8();
    for (x, y) in [(0, 0), (7, 9), (15, 15)] {
        let expected = reference.get_pixel(4 + x, y).0.map(spectral::srgb_to_u8);
        assert_eq!(strip.get_pixel(4 * 16 + x, y).0, expected, "strip pixel ({x}, {y})");
    }
    let heat = image::open(out.join("heat-path.png")).unwrap().into_rgb8();
    assert!(heat.pixels().any(|p| p.0 != [0, 0, 0]), "8 spp leave some error");
    assert!(String::from_utf8_lossy(&o.stdout).contains("efficiency"));

    let small = dir.join("small.exr");
    assert!(render_small(&scene, (8, 8, 1), &small, &[]).status.success());
    let o = spt(&[&args[..], &["--reference", small.to_str().unwrap(), "-o", out.to_str().unwrap()]].concat());
    assert!(!o.status.success() && stderr(&o).contains("the reference is 8×8"), "{}", stderr(&o));
    let o = spt(&[&args[..], &["--configs", "colours", "-o", out.to_str().unwrap()]].concat());
    assert!(!o.status.success() && stderr(&o).contains("neither a preset"), "{}", stderr(&o));
}

/// `spt view --backend gpu` keeps its statistics on the device and draws its frames onto
/// the window from there, through a wgpu surface (lavapipe presents to Xvfb): the window
/// shows, within one 8-bit step, the image `spt render --spp 6` writes with the same
/// settings — read from Xvfb's own framebuffer (`-fbdir`, XWD format) while the viewer,
/// done refining at `--max-spp 6`, holds it; all three frames were drawn from the device
/// (the render thread waits for the window's surface before its first frame, so none went
/// through the CPU framebuffer). SIGTERM then quits it as its window would, with status
/// 130, writing `--save`'s image: byte for byte the render's (its exact film is assembled
/// from the device's accumulators on saving).
#[test]
fn the_gpu_viewer_shows_and_saves_the_image_a_render_of_its_samples_gives() {
    let Some(scene) = shared_cornell_box() else { return };
    if gpu::require_gpu().is_none() {
        return;
    }
    if std::process::Command::new("xvfb-run").arg("--help").output().is_err() {
        assert!(std::env::var_os("SPT_REQUIRE_DISPLAY").is_none(), "SPT_REQUIRE_DISPLAY is set but xvfb-run is absent");
        eprintln!("skipping: xvfb-run is not on PATH");
        return;
    }
    let dir = temp_dir("gpu-view");
    let (viewed, rendered) = (dir.join("viewed.exr"), dir.join("rendered.exr"));
    let (framebuffers, done) = (dir.join("fb"), dir.join("done"));
    let _ = std::fs::remove_dir_all(&framebuffers);
    let _ = std::fs::remove_file(&done);
    std::fs::create_dir_all(&framebuffers).unwrap();
    let (width, height) = (48u32, 32u32);
    let common = ["--backend", "gpu", "--width", "48", "--height", "32", "--seed", "5"];
    let o = spt(&[
        &["render", scene.to_str().unwrap(), "--sampler", "independent"],
        &common[..],
        &["--spp", "6", "-o", rendered.to_str().unwrap()],
    ]
    .concat());
    assert!(o.status.success(), "{}", stderr(&o));
    // What the window should show: the render's linear values, sRGB-encoded to 8 bits
    // (IEC 61966-2-1, as `Film::display_pixels`).
    let srgb = |linear: f32| {
        let v = linear.clamp(0.0, 1.0);
        let encoded = if v <= 0.003_130_8 { 12.92 * v } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 };
        (encoded * 255.0 + 0.5) as u8
    };
    let expected: Vec<[u8; 3]> =
        image::open(&rendered).unwrap().into_rgb32f().pixels().map(|p| p.0.map(srgb)).collect();
    assert!(expected.iter().any(|p| p.iter().any(|&c| c > 20)), "the Cornell box is not black");

    // The viewer in the background of a shell that ends it (SIGTERM) once `done` exists,
    // or after 300 s.
    let hold = r#"SPT="$1"; shift; "$SPT" "$@" & pid=$!; i=0
while [ ! -e "$0" ] && [ $i -lt 3000 ] && kill -0 $pid 2>/dev/null; do sleep 0.1; i=$((i+1)); done
kill -TERM $pid 2>/dev/null; wait $pid"#;
    let server = format!("-screen 0 320x240x24 -fbdir {}", framebuffers.display());
    let mut viewer = std::process::Command::new("xvfb-run")
        .args(["-a", "-s", &server, "sh", "-c", hold, done.to_str().unwrap(), env!("CARGO_BIN_EXE_spt")])
        .args(["view", scene.to_str().unwrap()])
        .args(common)
        .args(["--spp-per-frame", "2", "--max-spp", "6", "--save", viewed.to_str().unwrap()])
        .env_remove("WAYLAND_DISPLAY")
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Should an assertion below fail, the shell still ends the viewer (and xvfb-run its
    // server) at once instead of after 300 s.
    struct EndViewer<'a>(&'a Path);
    impl Drop for EndViewer<'_> {
        fn drop(&mut self) {
            let _ = std::fs::write(self.0, b"");
        }
    }
    let end_viewer = EndViewer(&done);

    // The window (placed at the screen's corner: Xvfb runs no window manager) until it
    // shows the 6-spp image, or the viewer ends, or 300 s pass.
    let screen = framebuffers.join("Xvfb_screen0");
    let start = std::time::Instant::now();
    let mut worst = None;
    while start.elapsed() < std::time::Duration::from_secs(300) && viewer.try_wait().unwrap().is_none() {
        std::thread::sleep(std::time::Duration::from_millis(200));
        let Some(shown) = std::fs::read(&screen).ok().and_then(|xwd| xwd_corner(&xwd, width, height)) else {
            continue;
        };
        let step = shown
            .iter()
            .zip(&expected)
            .flat_map(|(a, b)| (0..3).map(move |c| a[c].abs_diff(b[c])))
            .max()
            .unwrap_or(u8::MAX);
        worst = Some(step);
        if step <= 1 {
            break;
        }
    }
    drop(end_viewer);
    let o = viewer.wait_with_output().unwrap();
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(130), "ended by SIGTERM, after saving: {err}");
    assert!(err.contains("frames drawn from the GPU's device through a wgpu surface"), "{err}");
    assert!(
        worst.is_some_and(|w| w <= 1),
        "the window's pixels differ from the render's by {worst:?} 8-bit steps (None: no window)\n{err}"
    );
    assert!(err.contains("interrupted") && err.contains("3 frames (3 drawn from the GPU's device), 6 spp"), "{err}");
    let (a, b) = (std::fs::read(&viewed).unwrap(), std::fs::read(&rendered).unwrap());
    assert!(a == b, "the viewer's 6 spp differ from the render's");
}

/// The top-left `width × height` pixels of an Xvfb framebuffer file (XWD: a big-endian
/// header, a colour map, then ZPixmap rows), as RGB; `None` until the file is complete.
fn xwd_corner(xwd: &[u8], width: u32, height: u32) -> Option<Vec<[u8; 3]>> {
    let field = |i: usize| Some(u32::from_be_bytes(xwd.get(4 * i..4 * i + 4)?.try_into().ok()?) as usize);
    let (header, bits_per_pixel, bytes_per_line, colours) = (field(0)?, field(11)?, field(12)?, field(19)?);
    let (little_endian, masks) = (field(7)? == 0, [field(14)?, field(15)?, field(16)?]);
    if field(1)? != 7 {
        return None;
    }
    assert!(bits_per_pixel == 32 && masks.iter().all(|m| m.count_ones() == 8), "an XWD file of 32-bit RGB pixels");
    let pixels = xwd.get(header + 12 * colours..)?;
    let mut out = Vec::with_capacity((width * height) as usize);
    for y in 0..height as usize {
        for x in 0..width as usize {
            let bytes: [u8; 4] = pixels.get(y * bytes_per_line + 4 * x..)?.get(..4)?.try_into().ok()?;
            let word = if little_endian { u32::from_le_bytes(bytes) } else { u32::from_be_bytes(bytes) } as usize;
            out.push(masks.map(|m| ((word & m) >> m.trailing_zeros()) as u8));
        }
    }
    Some(out)
}

/// `spt render --reference REF.exr` prints the relMSE after passes ending at 1, 2, 4, …
/// spp (falling as the render converges), writes the image a render without it writes,
/// and refuses a reference of another size or a sharded render by name.
#[test]
fn render_measures_its_error_against_a_reference_as_it_goes() {
    let dir = temp_dir("reference");
    let scene = write_scene(&dir, OBJ);
    let (reference, measured, plain) = (dir.join("ref.exr"), dir.join("measured.exr"), dir.join("plain.exr"));
    assert!(render_small(&scene, (16, 12, 256), &reference, &["--seed", "99"]).status.success());
    let o = render_small(&scene, (16, 12, 16), &measured, &["--reference", reference.to_str().unwrap()]);
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    let rows: Vec<(u32, f64)> = err
        .lines()
        .filter_map(|l| {
            let mut f = l.split_whitespace();
            Some((f.next()?.parse().ok()?, f.next()?.parse().ok()?))
        })
        .collect();
    assert_eq!(rows.iter().map(|r| r.0).collect::<Vec<_>>(), [1, 2, 4, 8, 16], "{err}");
    assert!(rows[4].1 < rows[0].1 / 4.0, "the error falls with the samples: {rows:?}");
    assert!(render_small(&scene, (16, 12, 16), &plain, &[]).status.success());
    assert!(std::fs::read(&measured).unwrap() == std::fs::read(&plain).unwrap(), "the same image either way");
    let o = render_small(&scene, (8, 8, 4), &measured, &["--reference", reference.to_str().unwrap()]);
    assert!(!o.status.success() && stderr(&o).contains("the reference is 16×12, the render 8×8"), "{}", stderr(&o));
    let sharded = dir.join("piece.partial");
    let o = spt(&[
        "render",
        scene.to_str().unwrap(),
        "--reference",
        reference.to_str().unwrap(),
        "--shard",
        "1/2",
        "-o",
        sharded.to_str().unwrap(),
    ]);
    assert!(!o.status.success() && stderr(&o).contains("does not combine with --shard"), "{}", stderr(&o));
}

/// `spt info` lists what a scene holds: its triangles, its materials under their models,
/// its lights (or that it has none and will get the white sky), and names a missing file.
#[test]
fn info_lists_geometry_materials_and_lights() {
    let dir = temp_dir("info");
    let scene = write_scene(&dir, OBJ);
    let o = spt(&["info", scene.to_str().unwrap()]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(out.contains("geometry: 4 triangles, 8 vertices"), "{out}");
    assert!(out.contains("lambert: white, lamp"), "{out}");
    assert!(out.contains("lights: 2 emissive triangles, 0 emissive shapes (1 emissive materials: lamp)"), "{out}");
    assert!(!out.contains("no light"), "{out}");
    // A mesh copied per lamp repeats its material: each name once, with its count.
    let hall = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/many-lights.toml");
    let o = spt(&["info", hall.to_str().unwrap()]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("(64 emissive materials: lamp0_0 ×4, lamp2_1 ×4,"), "{out}");
    assert_eq!(out.matches("lamp0_0").count(), 2, "once among the materials, once among the lights: {out}");
    let dark = dir.join("dark.obj");
    std::fs::write(&dark, OBJ.replace("usemtl lamp\n", "usemtl white\n")).unwrap();
    let o = spt(&["info", dark.to_str().unwrap()]);
    assert!(String::from_utf8_lossy(&o.stdout).contains("no light: renders get the default white sky"));
    let o = spt(&["info", dir.join("missing.obj").to_str().unwrap()]);
    assert!(!o.status.success() && stderr(&o).contains("missing.obj"), "{}", stderr(&o));
}

#[test]
fn gltf_scenes_render_through_their_cameras_and_report_what_they_ignore() {
    let shared = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/scenes");
    let (glass, cornell) = (
        shared.join("gltf-transmission-test/TransmissionTest.glb"),
        shared.join("cornell-box/CornellBox-Original.obj"),
    );
    if !glass.exists() || !cornell.exists() {
        eprintln!("SKIPPED: {} or {} is absent", glass.display(), cornell.display());
        return;
    }
    let o = spt(&["info", glass.to_str().unwrap()]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(out.contains("geometry: 128775 triangles"), "{out}");
    assert!(out.contains("camera 0 (render_camera): eye [-0.077, 0.339, 1.803]"), "{out}");
    assert!(out.contains("roughdielectric: ") && out.contains("metallicroughness: "), "{out}");
    // Its textures are read (base colours tint the glass, roughness maps roughen it,
    // masks cut out); the label's emissive texture glows but is not a light.
    assert!(out.contains("textures: 8 images") && out.contains("7 base colour") && out.contains("6 alpha"), "{out}");
    assert!(out.contains("LabelMaterial (textured: seen, not sampled)"), "{out}");
    assert!(stderr(&o).contains("transmission texture is not applied"), "{}", stderr(&o));

    let dir = temp_dir("gltf");
    let png = dir.join("glass.png");
    let args = |camera: &str| {
        let mut a = vec!["render", glass.to_str().unwrap(), "--width", "12", "--height", "8", "--spp", "1"];
        a.extend(["--camera", camera, "-o", png.to_str().unwrap()]);
        a.into_iter().map(String::from).collect::<Vec<_>>()
    };
    let run = |a: Vec<String>| spt(&a.iter().map(String::as_str).collect::<Vec<_>>());
    let o = run(args("render_camera"));
    assert!(o.status.success() && png.exists(), "{}", stderr(&o));
    let o = run(args("7"));
    assert!(!o.status.success() && stderr(&o).contains("no camera '7'") && stderr(&o).contains("0 (render_camera)"));
    let o = spt(&["render", cornell.to_str().unwrap(), "--camera", "0", "-o", png.to_str().unwrap()]);
    assert!(!o.status.success() && stderr(&o).contains("has no cameras (only glTF scenes do)"), "{}", stderr(&o));
    let broken = dir.join("broken.glb");
    std::fs::write(&broken, &std::fs::read(&glass).unwrap()[..1000]).unwrap();
    let o = spt(&["render", broken.to_str().unwrap(), "-o", png.to_str().unwrap()]);
    assert!(!o.status.success() && stderr(&o).contains("broken.glb: not a valid glTF file"), "{}", stderr(&o));
}

#[test]
fn scene_files_render_and_their_errors_name_line_and_column() {
    let dir = temp_dir("scene-file");
    let scene = dir.join("spheres.toml");
    std::fs::write(
        &scene,
        "[camera]\neye = [0, 1, 4]\ncenter = [0, 0.5, 0]\n\n[materials.white]\nmodel = \"lambert\"\nreflectance = 0.7\n\n\
         [[shape]]\ntype = \"sphere\"\ncenter = [0, 0.5, 0]\nradius = 0.5\nmaterial = \"white\"\n\n\
         [[light]]\ntype = \"point\"\nposition = [0, 3, 2]\nintensity = 10\n",
    )
    .unwrap();
    let out = dir.join("spheres.exr");
    let o = render_small(&scene, (16, 16, 4), &out, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stderr(&o).contains("no light"), "{}", stderr(&o));
    assert!(exr_means(&out).iter().all(|&m| m > 0.0 && m.is_finite()), "{:?}", exr_means(&out));
    let o = spt(&["info", scene.to_str().unwrap()]);
    let info = String::from_utf8_lossy(&o.stdout);
    assert!(info.contains("1 analytic shapes") && info.contains("lambert: white"), "{info}");
    // --set changes the file's values before it is read: a darker sphere.
    let bright = exr_means(&out);
    let o = render_small(&scene, (16, 16, 4), &out, &["--set", "materials.white.reflectance=0.07"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let dark = exr_means(&out);
    assert!((dark[0] / bright[0] - 0.1).abs() < 0.02, "{dark:?} vs {bright:?}");
    let o = spt(&["render", "builtin:glass-torus", "--set", "camera.fov=30", "-o", out.to_str().unwrap()]);
    assert!(!o.status.success() && stderr(&o).contains("--set applies to .toml scene files"), "{}", stderr(&o));
    let bad = dir.join("bad.toml");
    std::fs::write(&bad, "[materials.white]\nmodel = \"lambert\"\nreflectance = 1.7\n").unwrap();
    let o = spt(&["render", bad.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert!(!o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("bad.toml:3:15: ") && stderr(&o).contains("reflectance = 1.7"), "{}", stderr(&o));
}

/// `spt compare`'s other axes: BVH builders under a time budget (each configuration
/// stops after the first render that takes the budget), and a configuration file that
/// changes a material of a scene file (a BSDF variant), the shading normals and the depth.
#[test]
fn compare_takes_time_budgets_builders_and_scene_changes() {
    let dir = temp_dir("compare-axes");
    let scene = write_scene(&dir, OBJ);
    let out = dir.join("builders");
    let size = ["--width", "16", "--height", "12", "--reference-spp", "64"];
    let o = spt(&[
        &["compare", scene.to_str().unwrap()][..],
        &size,
        &["--configs", "bvh-builders", "--spp-max", "8", "--time-max", "1e-9", "--end-to-end"],
        &["-o", out.to_str().unwrap()],
    ]
    .concat());
    assert!(o.status.success(), "{}", stderr(&o));
    let csv = std::fs::read_to_string(out.join("compare.csv")).unwrap();
    let configs: Vec<&str> = csv.lines().skip(1).map(|l| l.split(',').next().unwrap()).collect();
    assert_eq!(configs, ["binned_sah", "sweep_sah", "midpoint", "hybrid"], "one render each: {csv}");
    assert!(String::from_utf8_lossy(&o.stdout).contains("total_s"));

    let toml = dir.join("room.toml");
    std::fs::write(
        &toml,
        "[materials.glass]\nmodel = \"dielectric\"\nior = 1.5\n\
         [materials.lamp]\nmodel = \"lambert\"\nreflectance = 0\nemission = 5\n\
         [[shape]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 0.5\nmaterial = \"glass\"\n\
         [[shape]]\ntype = \"sphere\"\ncenter = [0, 2, 0]\nradius = 0.3\nmaterial = \"lamp\"\n\
         [camera]\neye = [0, 0.5, 3]\ncenter = [0, 0.5, 0]\n",
    )
    .unwrap();
    let configs = dir.join("variants.json");
    std::fs::write(
        &configs,
        r#"[{"name": "exact"}, {"name": "schlick", "set": ["materials.glass.schlick=true"]},
            {"name": "flat", "shading_normals": "geometric", "max_depth": 3},
            {"name": "long paths", "rr_scale": 3}]"#,
    )
    .unwrap();
    let out = dir.join("variants");
    let o = spt(&[
        &["compare", toml.to_str().unwrap()][..],
        &size,
        &["--configs", configs.to_str().unwrap(), "--spp-max", "2", "-o", out.to_str().unwrap()],
    ]
    .concat());
    assert!(o.status.success(), "{}", stderr(&o));
    let csv = std::fs::read_to_string(out.join("compare.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 4 * 2, "{csv}");
    // Bad configurations are refused by name; a configuration's roulette reaches the
    // render's settings (and their check).
    let bad = dir.join("bad.json");
    for (json, needle) in [
        (r#"[{"name": "x", "bvh_builder": "octree"}]"#, "'x': bvh_builder"),
        (r#"[{"name": "y", "rr_scale": 0}]"#, "Russian roulette scale 0"),
    ] {
        std::fs::write(&bad, json).unwrap();
        let o = spt(&[
            &["compare", scene.to_str().unwrap()][..],
            &size,
            &["--configs", bad.to_str().unwrap(), "-o", out.to_str().unwrap()],
        ]
        .concat());
        assert!(!o.status.success() && stderr(&o).contains(needle), "{}", stderr(&o));
    }
}

/// Every preset runs end to end at a tiny size (CI's run of the charts docs/ shows full
/// size): a row per configuration and budget, and both charts.
#[test]
fn every_compare_preset_runs() {
    let dir = temp_dir("compare-presets");
    let scene = write_scene(&dir, OBJ);
    let reference = dir.join("reference.exr");
    let o = spt(&[
        "render",
        scene.to_str().unwrap(),
        "--width",
        "8",
        "--height",
        "6",
        "--spp",
        "16",
        "-o",
        reference.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    for preset in
        ["spectral", "samplers", "integrators", "triangle-tests", "bvh-widths", "bvh-builders", "shading-normals"]
    {
        let out = dir.join(preset);
        let o = spt(&[
            "compare",
            scene.to_str().unwrap(),
            "--width",
            "8",
            "--height",
            "6",
            "--reference",
            reference.to_str().unwrap(),
            "--spp-max",
            "2",
            "--configs",
            preset,
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{preset}: {}", stderr(&o));
        let rows = std::fs::read_to_string(out.join("compare.csv")).unwrap().lines().count() - 1;
        assert!(rows >= 4 && rows.is_multiple_of(2), "{preset}: {rows} rows");
        assert!(out.join("compare.png").exists() && out.join("compare.svg").exists(), "{preset}");
    }
}

/// `spt atlas`: a row per resolution × count with its times, and the atlas's images.
#[test]
fn atlas_tables_its_gather_and_writes_its_images() {
    let dir = temp_dir("atlas");
    let scene = write_scene(&dir, OBJ);
    let out = dir.join("img");
    let o = spt(&[
        "atlas",
        scene.to_str().unwrap(),
        "--counts",
        "4,8",
        "--resolutions",
        "32,48",
        "--threads",
        "1",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let table = String::from_utf8_lossy(&o.stdout).to_string();
    let rows: Vec<&str> = table.lines().filter(|l| !l.starts_with('#') && !l.starts_with("resolution")).collect();
    assert_eq!(rows.len(), 4, "{table}");
    assert!(rows[0].trim_start().starts_with("32x32") && rows[3].trim_start().starts_with("48x48"), "{table}");
    for what in ["normal", "position", "direct", "indirect"] {
        let img = image::open(out.join(format!("atlas-{what}.png"))).unwrap();
        assert_eq!((img.width(), img.height()), (48, 48), "{what}");
    }
    let o = spt(&["atlas", scene.to_str().unwrap(), "--counts", "0", "--resolutions", "32"]);
    assert!(!o.status.success() && stderr(&o).contains("atlas samples 0"), "{}", stderr(&o));
}

#[test]
fn the_example_scene_files_load() {
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
    let shared = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/scenes");
    if !shared.exists() {
        eprintln!("SKIPPED: {} is absent (the example scenes use its meshes)", shared.display());
        return;
    }
    let mut n = 0;
    for entry in std::fs::read_dir(&scenes).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            let o = spt(&["info", path.to_str().unwrap()]);
            assert!(o.status.success(), "{}: {}", path.display(), stderr(&o));
            n += 1;
        }
    }
    assert!(n >= 5, "{n} example scene files");
}

/// Every example scene renders on the GPU with no NaN/Inf — the implicit surface of
/// `cornell-spheres.toml` too, where the device has f64 in shaders (lavapipe and desktop GPUs
/// do); on a device without, it is refused before any work with the reason and the way out.
#[test]
fn example_scenes_render_on_the_gpu_or_say_why() {
    let Some(ctx) = gpu::require_gpu() else {
        eprintln!("SKIPPED: no GPU adapter");
        return;
    };
    let shader_f64 = ctx.shader_f64();
    drop(ctx);
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
    let shared = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/scenes");
    if !shared.exists() {
        eprintln!("SKIPPED: {} is absent (the example scenes use its meshes)", shared.display());
        return;
    }
    let out = temp_dir("gpu-examples").join("x.png");
    let mut rendered = Vec::new();
    for entry in std::fs::read_dir(&scenes).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "toml") {
            continue;
        }
        let name = path.file_stem().unwrap().to_string_lossy().to_string();
        let o = render_small(&path, (8, 6, 2), &out, &["--backend", "gpu", "--max-depth", "4"]);
        let msg = stderr(&o);
        if o.status.success() {
            assert!(msg.contains(" 0 NaN/Inf"), "{name}: {msg}");
            rendered.push(name);
        } else {
            let reason = msg.contains("implicit surface") && msg.contains("SHADER_F64");
            assert!(!shader_f64 && reason && msg.contains("--backend cpu"), "{name}: {msg}");
        }
    }
    rendered.sort();
    let implicit = ["cornell-spheres"].into_iter().filter(|_| shader_f64);
    for must in ["bunnies", "caustics", "helmet", "materials", "prism", "sponza"].into_iter().chain(implicit) {
        assert!(rendered.iter().any(|r| r == must), "{must} did not render on the GPU (rendered: {rendered:?})");
    }
}

#[test]
fn spec_files_colour_materials_and_light_the_sky() {
    let example = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/thesis/metal.obj");
    let dir = temp_dir("spec");
    let out = dir.join("metal.exr");
    let render = |extra: &[&str]| {
        let mut a = vec!["render", example.to_str().unwrap(), "--width", "12", "--height", "12", "--spp", "4"];
        a.extend_from_slice(extra);
        a.extend(["-o", out.to_str().unwrap()]);
        let o = spt(&a);
        assert!(o.status.success(), "{}", stderr(&o));
        (stderr(&o), exr_means(&out))
    };
    // The SPEC file beside the OBJ is applied: its D65 sky lights the scene (no default
    // sky warning) and the golden sphere is warmer than it is grey.
    let (log, golden) = render(&["--eye", "0,0.5,1.2", "--center", "0,0.5,0"]);
    assert!(log.contains("applying") && log.contains("metal.spec") && !log.contains("no light"), "{log}");
    assert!(golden[0] > 1.2 * golden[2], "{golden:?}");
    // Another SPEC file replaces it; --sky FILE.spec takes only its sky.
    let grey = dir.join("grey.spec");
    std::fs::write(
        &grey,
        r#"{ "materials": { "Metal": { "diff": "grey", "spec": "grey" } }, "spectra": { "grey": { "380": 0.5, "775": 0.5 } } }"#,
    )
    .unwrap();
    let (_, greyed) =
        render(&["--eye", "0,0.5,1.2", "--center", "0,0.5,0", "--spec", grey.to_str().unwrap(), "--sky", "white"]);
    assert!((greyed[0] / greyed[2] - 1.0).abs() < 0.05, "{greyed:?}");
    let o = spt(&["render", example.to_str().unwrap(), "--sky", grey.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert!(!o.status.success() && stderr(&o).contains("the SPEC file names no sky"), "{}", stderr(&o));
    std::fs::write(&grey, r#"{ "materials": { "Gold": { "diff": "g" } }, "spectra": { "g": { "400": 0.5 } } }"#)
        .unwrap();
    let o = spt(&["render", example.to_str().unwrap(), "--spec", grey.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert!(!o.status.success() && stderr(&o).contains("materials.Gold: no such material"), "{}", stderr(&o));
}

#[test]
fn a_scene_files_render_table_sets_defaults_that_options_override() {
    let dir = temp_dir("render-table");
    let scene = dir.join("s.toml");
    let text = "[camera]\neye = [0, 1, 4]\ncenter = [0, 0.5, 0]\n[materials.w]\nmodel = \"lambert\"\n\
                [[shape]]\ntype = \"sphere\"\ncenter = [0, 0.5, 0]\nradius = 0.5\nmaterial = \"w\"\n\
                [render]\nwidth = 20\nheight = 10\nspp = 3\nspectral = \"rgb\"\n";
    std::fs::write(&scene, text).unwrap();
    let out = dir.join("s.png");
    let o = spt(&["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert!(o.status.success() && stderr(&o).contains("20×10 at 3 spp, rgb mode"), "{}", stderr(&o));
    // A global option before the subcommand's name does not move where the table's
    // defaults go.
    let o = spt(&["--simd", "baseline", "render", scene.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert!(o.status.success() && stderr(&o).contains("20×10 at 3 spp, rgb mode"), "{}", stderr(&o));
    let o =
        spt(&["render", scene.to_str().unwrap(), "--height", "6", "--spectral", "hero", "-o", out.to_str().unwrap()]);
    assert!(o.status.success() && stderr(&o).contains("20×6 at 3 spp, hero mode"), "{}", stderr(&o));
    assert_eq!(image::open(&out).unwrap().height(), 6);
    std::fs::write(&scene, text.replace("\"rgb\"", "\"cmyk\"")).unwrap();
    let o = spt(&["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert!(!o.status.success() && stderr(&o).contains("[render] table: invalid value 'cmyk'"), "{}", stderr(&o));
    std::fs::write(&scene, text.replace("spp = 3", "samples = 3")).unwrap();
    let o = spt(&["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert!(!o.status.success() && stderr(&o).contains("unknown field `samples`"), "{}", stderr(&o));
    // Russian roulette's scale reaches the render from the table (an absurd one is
    // refused there); the command line's wins.
    std::fs::write(&scene, text.replace("spp = 3", "spp = 3\nrr_scale = -2")).unwrap();
    let o = spt(&["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert!(!o.status.success() && stderr(&o).contains("Russian roulette scale -2 must be"), "{}", stderr(&o));
    let o = spt(&["render", scene.to_str().unwrap(), "--rr-scale", "2.5", "-o", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
}

#[test]
fn textured_obj_scenes_render_and_a_missing_texture_is_a_clear_error() {
    let dir = temp_dir("textures");
    // The floor with texture coordinates.
    let with_uvs =
        OBJ.replace("usemtl white\nf 4 3 2 1", "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl white\nf 4/4 3/3 2/2 1/1");
    assert_ne!(with_uvs, OBJ);
    let obj = write_scene(&dir, &with_uvs);
    // The floor gets a red checkerboard; the lamp stays as it is.
    let checker = image::RgbImage::from_fn(8, 8, |x, y| {
        image::Rgb(if (x + y).is_multiple_of(2) { [255, 0, 0] } else { [40; 3] })
    });
    checker.save(dir.join("checker.png")).unwrap();
    std::fs::write(dir.join("scene.mtl"), MTL.replace("Kd 0.8 0.8 0.8", "Kd 1 1 1\nmap_Kd checker.png")).unwrap();
    let out = dir.join("textured.exr");
    let o = render_small(&obj, (16, 16, 8), &out, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let info = spt(&["info", obj.to_str().unwrap()]);
    let text = String::from_utf8_lossy(&info.stdout);
    assert!(text.contains("textures: 1 images") && text.contains("1 base colour"), "{text}");
    // --no-textures: the factor alone (white), beside which the textured floor is red.
    let plain = dir.join("plain.exr");
    let o = render_small(&obj, (16, 16, 8), &plain, &["--no-textures"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let ([r, g, _], [pr, pg, _]) = (exr_means(&out), exr_means(&plain));
    assert!(g < 0.9 * pg && r / g > 1.2 * pr / pg, "textured {r} {g}, plain {pr} {pg}");
    // A missing image: exit status 1, the material and the file named.
    std::fs::write(dir.join("scene.mtl"), MTL.replace("Kd 0.8 0.8 0.8", "map_Kd textures/gone.png")).unwrap();
    let o = render_small(&obj, (16, 16, 8), &out, &[]);
    let e = stderr(&o);
    assert!(!o.status.success() && e.contains("material 'white'") && e.contains("gone.png"), "{e}");
}

#[test]
fn an_environment_map_lights_a_scene_from_the_command_line() {
    let dir = temp_dir("envmap");
    let obj = write_scene(&dir, OBJ);
    let sky = dir.join("sky.exr");
    image::Rgb32FImage::from_fn(16, 8, |_, y| image::Rgb(if y < 4 { [0.2, 0.4, 1.0] } else { [0.0; 3] }))
        .save(&sky)
        .unwrap();
    let (dim, bright) = (dir.join("dim.exr"), dir.join("bright.exr"));
    let map = sky.to_str().unwrap().to_string();
    let o = render_small(&obj, (16, 16, 16), &dim, &["--sky", &map]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = render_small(&obj, (16, 16, 16), &bright, &["--sky", &format!("{map}:4")]);
    assert!(o.status.success(), "{}", stderr(&o));
    // A blue sky: the scaled one adds light, bluer than red.
    let (d, b) = (exr_means(&dim), exr_means(&bright));
    assert!(b[2] > d[2] + 0.05 && (b[2] - d[2]) > 2.0 * (b[0] - d[0]), "{d:?} {b:?}");
    let o = render_small(&obj, (16, 16, 16), &dim, &["--sky", &format!("{map}:0")]);
    assert!(!o.status.success() && stderr(&o).contains("scale 0 must be positive"), "{}", stderr(&o));
    let o = render_small(&obj, (16, 16, 16), &dim, &["--sky", "nowhere/sky.hdr"]);
    assert!(!o.status.success() && stderr(&o).contains("nowhere/sky.hdr"), "{}", stderr(&o));
}

#[test]
fn a_closed_pipe_ends_spt_quietly() {
    // `spt info … | true`: the reader is gone before spt has loaded the scene, so its first
    // line meets a closed pipe; that panicked before SIGPIPE's default action was restored.
    let dir = temp_dir("pipe");
    let obj = write_scene(&dir, OBJ);
    let spt = env!("CARGO_BIN_EXE_spt");
    let o = std::process::Command::new("sh")
        .arg("-c")
        .arg(format!("'{spt}' info '{}' | true", obj.display()))
        .output()
        .expect("sh runs");
    assert!(!stderr(&o).contains("panicked"), "{}", stderr(&o));
}

/// `spt bench --frames N` times viewer frames (a row per mode with frames/s and the frame
/// count), and `--frames-on-device` is refused, by name, where frames cannot stay on a GPU.
#[test]
fn bench_times_viewer_frames_and_refuses_device_frames_on_the_cpu() {
    let dir = temp_dir("bench-frames");
    let scene = write_scene(&dir, OBJ);
    let args = ["bench", scene.to_str().unwrap(), "--backend", "cpu", "--width", "8", "--height", "6"];
    let o = spt(&[&args[..], &["--spp", "1", "--frames", "3", "--modes", "rgb,hero"]].concat());
    let out = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(o.status.success(), "{}", stderr(&o));
    let rows: Vec<Vec<&str>> = out.lines().map(|l| l.split_whitespace().collect()).collect();
    let row = |mode: &str| rows.iter().find(|r| r.first() == Some(&mode)).unwrap_or_else(|| panic!("{out}"));
    for mode in ["rgb", "hero"] {
        let r = row(mode);
        assert_eq!(r.last(), Some(&"3"), "three frames: {out}");
        assert!(r[1].parse::<f64>().is_ok_and(|fps| fps > 0.0), "frames/s: {out}");
    }
    let o = spt(&[&args[..], &["--frames", "2", "--frames-on-device"]].concat());
    assert!(!o.status.success() && stderr(&o).contains("--frames-on-device needs --backend gpu"), "{}", stderr(&o));
    let o = spt(&[&args[..], &["--frames-on-device"]].concat());
    assert!(!o.status.success() && stderr(&o).contains("--frames"), "{}", stderr(&o));
    // The GPU's wavefront has no 40-bin mode: by default bench times the modes it has, and
    // refuses the one asked for by name.
    if gpu::require_gpu().is_some() {
        let args =
            ["bench", scene.to_str().unwrap(), "--backend", "gpu", "--wavefront", "--width", "8", "--height", "6"];
        let o = spt(&[&args[..], &["--spp", "1", "--repeats", "1"]].concat());
        let out = String::from_utf8_lossy(&o.stdout).into_owned();
        let modes: Vec<&str> =
            out.lines().filter_map(|l| l.split_whitespace().next()).filter(|w| !w.starts_with('#')).collect();
        assert!(o.status.success() && modes == ["mode", "hero", "rgb"], "{out}{}", stderr(&o));
        let o = spt(&[&args[..], &["--spp", "1", "--repeats", "1", "--modes", "hero,bins40"]].concat());
        assert!(!o.status.success() && stderr(&o).contains("'bins40' spectral mode"), "{}", stderr(&o));
    }
}
