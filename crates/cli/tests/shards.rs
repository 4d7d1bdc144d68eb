//! Sharded, time-budgeted and resumed renders end to end: `render --shard K/N` and
//! `merge` give the unsharded render's bytes; killed and stopped renders resume to the
//! same bytes; damaged, foreign or incomplete partials are refused with their names.

mod common;

use common::*;
use std::path::{Path, PathBuf};
use std::process::Output;

const SIZE: (u32, u32, u32) = (24, 20, 12);

fn ok(o: Output) -> Output {
    assert!(o.status.success(), "spt failed: {}", stderr(&o));
    o
}

fn refused(o: &Output) -> String {
    assert!(!o.status.success(), "spt should have refused: {}", stderr(o));
    stderr(o)
}

fn bytes(p: &Path) -> Vec<u8> {
    std::fs::read(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Renders shards 1..=n of `split` into `dir` and returns their paths.
fn shards(scene: &Path, dir: &Path, n: u32, split: &str, extra: &[&str]) -> Vec<PathBuf> {
    (1..=n)
        .map(|k| {
            let out = dir.join(format!("{split}-{k}-of-{n}.partial"));
            let spec = format!("{k}/{n}");
            ok(render_small(scene, SIZE, &out, &[&["--shard", &spec, "--shard-by", split], extra].concat()));
            out
        })
        .collect()
}

fn merge(parts: &[PathBuf], out: &Path, extra: &[&str]) -> Output {
    let mut args = vec!["merge"];
    args.extend(parts.iter().map(|p| s(p)));
    args.extend(["-o", s(out)]);
    args.extend(extra);
    spt(&args)
}

#[test]
fn sample_and_tile_shards_merge_to_the_unsharded_bytes() {
    let dir = temp_dir("shards-equal");
    let scene = write_scene(&dir, OBJ);
    let (full, full_se) = (dir.join("full.exr"), dir.join("full-se.exr"));
    ok(render_small(&scene, SIZE, &full, &["--stderr", s(&full_se)]));
    for (split, n) in [("samples", 4), ("tiles", 4), ("samples", 5), ("tiles", 3)] {
        let parts = shards(&scene, &dir, n, split, &[]);
        let (out, se) = (dir.join(format!("{split}{n}.exr")), dir.join(format!("{split}{n}-se.exr")));
        let o = ok(merge(&parts, &out, &["--stderr", s(&se)]));
        assert!(stderr(&o).contains(&format!("merged {n} partials")), "{}", stderr(&o));
        assert!(bytes(&out) == bytes(&full), "{n} shards by {split}: the merged image differs");
        assert!(bytes(&se) == bytes(&full_se), "{n} shards by {split}: the merged standard error differs");
        // Any order of the partials on the command line.
        let mut reversed = parts.clone();
        reversed.reverse();
        let again = dir.join(format!("{split}{n}-reversed.png"));
        ok(merge(&reversed, &again, &[]));
        let png = dir.join("full.png");
        if !png.exists() {
            ok(render_small(&scene, SIZE, &png, &[]));
        }
        assert!(bytes(&again) == bytes(&png));
    }
    // Samples of the whole image are one file per shard; tiles hold only their rows.
    let sample_part = std::fs::metadata(dir.join("samples-1-of-4.partial")).unwrap().len();
    let tile_part = std::fs::metadata(dir.join("tiles-1-of-4.partial")).unwrap().len();
    assert!(tile_part < sample_part / 3, "{tile_part} vs {sample_part}");
    // Shards are planned by the render's spp: a shard with nothing to do is refused.
    let msg = refused(&render_small(&scene, (8, 8, 3), &dir.join("x.partial"), &["--shard", "4/4"]));
    assert!(msg.contains("--shard-by tiles"), "{msg}");
}

#[test]
fn merge_refuses_gaps_duplicates_foreign_and_damaged_partials() {
    let dir = temp_dir("shards-refuse");
    let scene = write_scene(&dir, OBJ);
    let parts = shards(&scene, &dir, 4, "samples", &[]);
    let out = dir.join("merged.exr");

    let msg = refused(&merge(&[parts[0].clone(), parts[1].clone(), parts[3].clone()], &out, &[]));
    assert!(msg.contains("samples 6..9") && msg.contains("missing shard 3/4 by samples"), "{msg}");
    let msg = refused(&merge(&[&parts[..], &parts[1..2]].concat(), &out, &[]));
    assert!(msg.contains("duplicate") && msg.contains("samples-2-of-4.partial"), "{msg}");
    let tiles = shards(&scene, &dir, 2, "tiles", &[]);
    let msg = refused(&merge(&[parts[0].clone(), tiles[1].clone()], &out, &[]));
    assert!(msg.contains("overlap"), "{msg}");
    let msg = refused(&merge(&tiles[..1], &out, &[]));
    assert!(msg.contains("rows 10..20") && msg.contains("missing shard 2/2 by tiles"), "{msg}");

    // Another seed is another render: named, with the field that differs.
    let other = dir.join("other-seed.partial");
    ok(render_small(&scene, SIZE, &other, &["--shard", "3/4", "--seed", "9"]));
    let msg = refused(&merge(&[parts[0].clone(), parts[1].clone(), other, parts[3].clone()], &out, &[]));
    assert!(msg.contains("different renders") && msg.contains("seed: 0 ≠ 9"), "{msg}");
    // So is another Russian roulette scale.
    let other = dir.join("other-roulette.partial");
    ok(render_small(&scene, SIZE, &other, &["--shard", "3/4", "--rr-scale", "1"]));
    let msg = refused(&merge(&[parts[0].clone(), parts[1].clone(), other, parts[3].clone()], &out, &[]));
    assert!(msg.contains("different renders") && msg.contains("rr_scale: 2.0 ≠ 1.0"), "{msg}");

    // Truncated, altered and foreign files are refused by name; nothing is written.
    let damaged = dir.join("damaged.partial");
    let good = bytes(&parts[2]);
    let cases: [(&str, Vec<u8>); 4] = [
        ("truncated", good[..good.len() - 100].to_vec()),
        ("SHA-256", {
            let mut b = good.clone();
            let i = b.len() - 500;
            b[i] ^= 1;
            b
        }),
        ("magic number", b"P3\n1 1\n255\n0 0 0\n".to_vec()),
        ("manifest is not valid", [&good[..8], &13u32.to_le_bytes()[..], b"{\"format\": 1}"].concat()),
    ];
    for (expected, content) in cases {
        std::fs::write(&damaged, content).unwrap();
        let msg = refused(&merge(&[parts[0].clone(), parts[1].clone(), damaged.clone(), parts[3].clone()], &out, &[]));
        assert!(msg.contains("damaged.partial") && msg.contains(expected), "{expected}: {msg}");
        assert!(!out.exists());
    }
    let msg = refused(&merge(&[parts[0].clone(), dir.join("absent.partial")], &out, &[]));
    assert!(msg.contains("absent.partial"), "{msg}");

    // Nothing is overwritten without --force.
    ok(merge(&parts, &out, &[]));
    let msg = refused(&merge(&parts, &out, &[]));
    assert!(msg.contains("merged.exr: exists") && msg.contains("--force"), "{msg}");
    ok(merge(&parts, &out, &["--force"]));
    let check = ok(spt(&[&["merge", "--check"], &parts.iter().map(|p| s(p)).collect::<Vec<_>>()[..]].concat()));
    let lines = String::from_utf8_lossy(&check.stdout).lines().count();
    assert_eq!(lines, 4, "one manifest per partial");
}

#[test]
fn an_existing_partial_of_another_render_is_not_overwritten() {
    let dir = temp_dir("shards-force");
    let scene = write_scene(&dir, OBJ);
    let out = dir.join("piece.partial");
    ok(render_small(&scene, SIZE, &out, &["--shard", "1/2"]));
    let before = bytes(&out);
    // The same command again: the piece is complete, its bytes stay.
    let o = ok(render_small(&scene, SIZE, &out, &["--shard", "1/2"]));
    assert!(stderr(&o).contains("resuming"), "{}", stderr(&o));
    assert!(bytes(&out) == before);
    let msg = refused(&render_small(&scene, SIZE, &out, &["--shard", "2/2"]));
    assert!(msg.contains("another piece") && msg.contains("--force"), "{msg}");
    let msg = refused(&render_small(&scene, (24, 20, 16), &out, &["--shard", "1/2"]));
    assert!(msg.contains("spp: 12 ≠ 16"), "{msg}");
    assert!(bytes(&out) == before);
    ok(render_small(&scene, (24, 20, 16), &out, &["--shard", "1/2", "--force"]));
    assert!(bytes(&out) != before);
    // Options that do not fit together.
    let msg = refused(&render_small(&scene, SIZE, &dir.join("x.png"), &["--shard", "1/2"]));
    assert!(msg.contains("NAME.partial"), "{msg}");
    let msg = refused(&render_small(&scene, SIZE, &dir.join("x.partial"), &[]));
    assert!(msg.contains("--shard"), "{msg}");
    for bad in ["0/2", "3/2", "two/4"] {
        let msg = refused(&render_small(&scene, SIZE, &dir.join("x.partial"), &["--shard", bad]));
        assert!(msg.contains("K/N"), "{msg}");
    }
    let msg = refused(&render_small(&scene, SIZE, &dir.join("x.png"), &["--time", "0"]));
    assert!(msg.contains("positive"), "{msg}");
}

/// Reads a partial's manifest through `spt merge --check` (which prints it).
fn done_of(partial: &Path) -> (u64, u64) {
    let o = spt(&["merge", "--check", s(partial)]);
    let line = String::from_utf8_lossy(&o.stdout).lines().next().unwrap_or_default().to_string();
    let v: serde_json::Value = serde_json::from_str(&line).unwrap_or_else(|e| panic!("{e}: {line}"));
    let m = &v["manifest"];
    (m["done"].as_u64().unwrap(), m["work"]["samples"]["end"].as_u64().unwrap())
}

#[test]
fn a_killed_shard_rerun_with_the_same_arguments_writes_the_same_bytes() {
    let dir = temp_dir("shards-kill");
    let scene = write_scene(&dir, OBJ);
    // Long enough (a second on one thread, here) to be killed between checkpoints.
    let size = (48, 48, 8192);
    let extra = ["--shard", "2/2", "--threads", "1", "--write-partial", "0.02"];
    let killed = dir.join("killed.partial");
    let (w, h, n) = (size.0.to_string(), size.1.to_string(), size.2.to_string());
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_spt"))
        .args(["render", s(&scene), "--width", &w, "--height", &h, "--spp", &n, "-o", s(&killed)])
        .args(extra)
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let start = std::time::Instant::now();
    while !killed.exists() && start.elapsed().as_secs() < 60 {
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let (done, end) = done_of(&killed);
    assert!(done < end, "the shard finished ({done} of {end}) before it could be killed: lengthen the render");
    let o = ok(render_small(&scene, size, &killed, &extra));
    assert!(stderr(&o).contains("resuming"), "{}", stderr(&o));
    let whole = dir.join("whole.partial");
    ok(render_small(&scene, size, &whole, &["--shard", "2/2"]));
    assert!(bytes(&killed) == bytes(&whole), "the resumed shard's bytes differ from an uninterrupted one's");
}

#[test]
fn a_render_stopped_by_its_time_budget_continues_to_the_same_bytes() {
    let dir = temp_dir("shards-time");
    let scene = write_scene(&dir, OBJ);
    let size = (48, 48, 8192);
    let out = dir.join("timed.exr");
    let o = ok(render_small(&scene, size, &out, &["--threads", "1", "--time", "0.15s"]));
    assert!(stderr(&o).contains("stopped at the time budget"), "{}", stderr(&o));
    let partial = dir.join("timed.exr.partial");
    let (done, end) = done_of(&partial);
    assert!(0 < done && done < end, "{done} of {end}");
    // The image of what was done is written too.
    assert!(out.exists());
    let o = ok(render_small(&scene, size, &out, &["--threads", "1", "--partial", s(&partial)]));
    assert!(stderr(&o).contains("resuming"), "{}", stderr(&o));
    assert_eq!(done_of(&partial).0, end);
    let whole = dir.join("whole.exr");
    ok(render_small(&scene, size, &whole, &[]));
    assert!(bytes(&out) == bytes(&whole), "the continued render differs from an uninterrupted one");
}

/// Bidirectional path tracing's splats travel in partials (the whole image's splat sums,
/// and the light paths that made them): sample shards merge to the unsharded bytes, and
/// a render stopped by its time budget continues to them. Tile shards are refused.
#[test]
fn bdpt_shards_and_resumes_to_the_same_bytes() {
    let dir = temp_dir("shards-bdpt");
    let scene = write_scene(&dir, OBJ);
    let bdpt = ["--integrator", "bdpt"];
    let full = dir.join("full.exr");
    ok(render_small(&scene, SIZE, &full, &bdpt));
    let parts = shards(&scene, &dir, 3, "samples", &bdpt);
    let out = dir.join("merged.exr");
    ok(merge(&parts, &out, &[]));
    assert!(bytes(&out) == bytes(&full), "bdpt shards merged differ from the unsharded render");
    // A partial without light paths is the old format, byte for byte: none carry splats.
    let path_part = dir.join("path.partial");
    ok(render_small(&scene, SIZE, &path_part, &["--shard", "1/3"]));
    let (bdpt_len, path_len) = (bytes(&parts[0]).len(), bytes(&path_part).len());
    let splat_bytes = (SIZE.0 * SIZE.1) as usize * 48;
    assert!(
        bdpt_len > path_len + splat_bytes - 64 && bdpt_len < path_len + splat_bytes + 256,
        "{bdpt_len} vs {path_len}"
    );

    let size = (32, 32, 4096);
    let timed = dir.join("timed.exr");
    let o = ok(render_small(&scene, size, &timed, &[&bdpt[..], &["--threads", "1", "--time", "0.15s"]].concat()));
    assert!(stderr(&o).contains("stopped at the time budget"), "{}", stderr(&o));
    let partial = dir.join("timed.exr.partial");
    ok(render_small(&scene, size, &timed, &[&bdpt[..], &["--threads", "1", "--partial", s(&partial)]].concat()));
    let whole = dir.join("whole.exr");
    ok(render_small(&scene, size, &whole, &bdpt));
    assert!(bytes(&timed) == bytes(&whole), "the continued bdpt render differs from an uninterrupted one");
}

/// `path-caustics` splats its light paths too: on a floor lit off a mirror, sample shards
/// merge to the unsharded bytes (that its light paths splat at all is the `tests` crate's
/// `caustics.rs`), tile shards are refused, and the GPU backend, which has no such
/// integrator, says so.
#[test]
fn path_caustics_shards_to_the_same_bytes_and_is_refused_where_it_cannot_run() {
    let dir = temp_dir("shards-path-caustics");
    std::fs::write(dir.join("mirror.mtl"), format!("{MTL}newmtl mirror\nbsdf mirror\n")).unwrap();
    // The scene's floor and lamp, and a mirror standing on the floor beside the lamp.
    let obj = OBJ.replace("mtllib scene.mtl", "mtllib mirror.mtl")
        + "v 0.6 0 -0.8\nv 0.6 0 0.8\nv 0.9 1.2 0.8\nv 0.9 1.2 -0.8\nusemtl mirror\nf 9 10 11 12\n";
    let scene = dir.join("mirror.obj");
    std::fs::write(&scene, obj).unwrap();
    let caustics = ["--integrator", "path-caustics"];
    let full = dir.join("full.exr");
    ok(render_small(&scene, SIZE, &full, &caustics));
    let parts = shards(&scene, &dir, 3, "samples", &caustics);
    let out = dir.join("merged.exr");
    ok(merge(&parts, &out, &[]));
    assert!(bytes(&out) == bytes(&full), "path-caustics shards merged differ from the unsharded render");
    let tiles = dir.join("tiles.partial");
    let msg = refused(&render_small(
        &scene,
        SIZE,
        &tiles,
        &[&caustics[..], &["--shard", "1/2", "--shard-by", "tiles"]].concat(),
    ));
    assert!(msg.contains("--integrator path-caustics splats") && msg.contains("shard it by samples"), "{msg}");
    let msg = refused(&render_small(&scene, SIZE, &full, &[&caustics[..], &["--backend", "gpu"]].concat()));
    assert!(msg.contains("no path-caustics integrator"), "{msg}");
}

/// The recipes in deploy/ as a scheduler would run them: the local script (N processes
/// and the merge), and the shard entry point with each scheduler's index variable
/// (Kubernetes' 0-based JOB_COMPLETION_INDEX, Slurm's SLURM_ARRAY_TASK_ID through the
/// array script) — each merging to the unsharded render's bytes.
#[test]
fn deploy_recipes_run_locally_and_merge_to_the_same_bytes() {
    let deploy = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../deploy");
    let dir = temp_dir("shards-deploy");
    let scene = write_scene(&dir, OBJ);
    let full = dir.join("full.exr");
    ok(render_small(&scene, SIZE, &full, &[]));
    let (w, h, n) = (SIZE.0.to_string(), SIZE.1.to_string(), SIZE.2.to_string());
    let render_args = [s(&scene), "--width", &w, "--height", &h, "--spp", &n];
    // Run as executables, by their own interpreter lines (sh or bash).
    let sh = |script: &str, env: &[(&str, &str)], args: &[&str]| {
        let o = std::process::Command::new(deploy.join(script))
            .args(args)
            .envs(env.iter().copied())
            .env("SPT", env!("CARGO_BIN_EXE_spt"))
            .output()
            .unwrap();
        assert!(o.status.success(), "{script}: {}", stderr(&o));
    };

    let local = dir.join("local.exr");
    sh("local/render-shards.sh", &[("THREADS", "1")], &[&["3", s(&local)], &render_args[..]].concat());
    assert!(bytes(&local) == bytes(&full), "deploy/local/render-shards.sh");

    for (variable, first) in [("JOB_COMPLETION_INDEX", 0), ("SLURM_ARRAY_TASK_ID", 1)] {
        let parts = dir.join(variable);
        for k in 0..4 {
            let index = (first + k).to_string();
            let env = [("SHARDS", "4"), ("OUT_DIR", s(&parts)), (variable, &index), ("SPT_DEPLOY", s(&deploy))];
            let script = if first == 1 { "slurm/render-array.sh" } else { "shard-entry.sh" };
            sh(script, &env, &render_args);
        }
        let partials: Vec<PathBuf> = (1..=4).map(|k| parts.join(format!("shard-{k}-of-4.partial"))).collect();
        let out = dir.join(format!("{variable}.exr"));
        ok(merge(&partials, &out, &[]));
        assert!(bytes(&out) == bytes(&full), "{variable}");
    }
    // No index at all is a clear error.
    let o = std::process::Command::new(deploy.join("shard-entry.sh"))
        .env("SHARDS", "4")
        .env_remove("JOB_COMPLETION_INDEX")
        .env_remove("SLURM_ARRAY_TASK_ID")
        .env_remove("SHARD_INDEX")
        .output()
        .unwrap();
    assert!(!o.status.success() && stderr(&o).contains("no shard index"), "{}", stderr(&o));
}

/// deploy/check.sh: shellcheck on the scripts, the Kubernetes manifests against the API's
/// schemas, the shard counts in agreement. Skips with a message where shellcheck or
/// kubernetes-validate is missing, unless `SPT_REQUIRE_LINTERS` is set (CI sets it and
/// installs both).
#[test]
fn deploy_recipes_pass_their_linters() {
    let have =
        |tool: &str| std::process::Command::new(tool).arg("--version").output().is_ok_and(|o| o.status.success());
    if !(have("shellcheck") && have("kubernetes-validate")) {
        assert!(
            std::env::var_os("SPT_REQUIRE_LINTERS").is_none(),
            "SPT_REQUIRE_LINTERS is set but shellcheck or kubernetes-validate is missing"
        );
        eprintln!("skipped: install shellcheck (apt) and kubernetes-validate (pip) to lint deploy/");
        return;
    }
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../deploy/check.sh");
    let o = std::process::Command::new(script).output().unwrap();
    assert!(o.status.success(), "deploy/check.sh: {}{}", String::from_utf8_lossy(&o.stdout), stderr(&o));
}
