//! Helpers shared by the CLI's end-to-end tests: run `spt`, temporary directories, a
//! small lit scene.
#![allow(dead_code)] // each test file uses its own subset

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

pub fn spt(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_spt")).args(args).output().expect("spt runs")
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

pub fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("spt-cli-test-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

pub const MTL: &str = "newmtl white\nKd 0.8 0.8 0.8\nnewmtl lamp\nKd 0.5 0.5 0.5\nKe 10 10 10\n";
pub const OBJ: &str = "mtllib scene.mtl\n\
v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\n\
v -0.3 1 -0.3\nv -0.3 1 0.3\nv 0.3 1 0.3\nv 0.3 1 -0.3\n\
usemtl white\nf 4 3 2 1\nusemtl lamp\nf 8 7 6 5\n";

pub fn write_scene(dir: &Path, obj: &str) -> PathBuf {
    std::fs::write(dir.join("scene.mtl"), MTL).unwrap();
    let path = dir.join("scene.obj");
    std::fs::write(&path, obj).unwrap();
    path
}

/// `spt render SCENE` at `width`×`height` and `spp` to `out`, with `extra` options.
pub fn render_small(scene: &Path, (width, height, spp): (u32, u32, u32), out: &Path, extra: &[&str]) -> Output {
    let (w, h, n) = (width.to_string(), height.to_string(), spp.to_string());
    let args =
        ["render", scene.to_str().unwrap(), "--width", &w, "--height", &h, "--spp", &n, "-o", out.to_str().unwrap()];
    spt(&[&args[..], extra].concat())
}
