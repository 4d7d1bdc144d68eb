//! Runs the viewer in a real window under Xvfb (`xvfb-run`): three frames of the
//! material sphere, saved as a PNG that must have the window's size and not be black.
//! Without `xvfb-run` on PATH the window test is skipped with a message, unless
//! `SPT_REQUIRE_DISPLAY` is set, when it fails. Also checks that refining stops at the
//! maximum spp and the error without a display.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Mutex;

const BIN: &str = env!("CARGO_BIN_EXE_view-smoke");

fn on_path(program: &str) -> bool {
    std::env::var_os("PATH").is_some_and(|paths| std::env::split_paths(&paths).any(|d| d.join(program).is_file()))
}

fn out_dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Runs `view-smoke OUT ARGS…` under `xvfb-run`; `None` (after saying why) where there is
/// no `xvfb-run` and `SPT_REQUIRE_DISPLAY` is not set. Returns stdout and stderr.
fn under_xvfb(out: &Path, args: &[&str]) -> Option<(String, String)> {
    // `xvfb-run -a` picks a free display number racily: start one server at a time.
    static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());
    let _guard = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    if !on_path("xvfb-run") {
        assert!(
            std::env::var_os("SPT_REQUIRE_DISPLAY").is_none(),
            "SPT_REQUIRE_DISPLAY is set but xvfb-run is not on PATH (apt-get install xvfb xauth)"
        );
        eprintln!("skipped: xvfb-run is not on PATH (apt-get install xvfb xauth to run the window test)");
        return None;
    }
    let _ = std::fs::remove_file(out);
    let output = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 640x480x24", BIN])
        .arg(out)
        .args(args)
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("WAYLAND_SOCKET")
        .env("RUST_BACKTRACE", "0")
        .output()
        .expect("xvfb-run starts");
    let stdout = String::from_utf8_lossy(&output.stdout).into_owned();
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert!(output.status.success(), "view-smoke failed: {}\n{stdout}\n{stderr}", output.status);
    Some((stdout, stderr))
}

#[test]
fn viewer_renders_frames_in_a_window_under_xvfb() {
    let png = out_dir("xvfb").join("view-smoke.png");
    let Some((stdout, stderr)) = under_xvfb(&png, &["3", "64", "48", "2"]) else { return };
    assert!(stdout.contains("frames 3 spp 6 "), "{stdout}");
    let image = image::open(&png).unwrap_or_else(|e| panic!("{}: {e}\n{stderr}", png.display())).into_rgb8();
    assert_eq!(image.dimensions(), (64, 48));
    let bright = image.pixels().filter(|p| p.0.iter().any(|&c| c > 20)).count();
    assert!(bright > 64 * 48 / 2, "mostly black image: {bright} lit pixels");
}

#[test]
fn refining_stops_at_max_spp_and_the_viewer_then_quits() {
    let exr = out_dir("xvfb-max").join("view-smoke.exr");
    let Some((stdout, _)) = under_xvfb(&exr, &["100", "40", "30", "3", "4"]) else { return };
    // 3 + 1 samples per pixel: two frames, the second cut to reach the maximum.
    assert!(stdout.contains("frames 2 spp 4 "), "{stdout}");
    let image = image::open(&exr).unwrap().into_rgb32f();
    assert_eq!(image.dimensions(), (40, 30));
    assert!(image.pixels().any(|p| p.0[0] > 0.05), "black EXR");
}

#[test]
fn without_a_display_the_error_says_what_to_do() {
    let output = Command::new(BIN)
        .arg(out_dir("no-display").join("never.png"))
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("WAYLAND_SOCKET")
        .env("RUST_BACKTRACE", "0")
        .output()
        .expect("view-smoke starts");
    assert!(!output.status.success());
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(stderr.contains("cannot open a window"), "{stderr}");
    assert!(stderr.contains("xvfb-run"), "{stderr}");
}
