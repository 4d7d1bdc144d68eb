//! `spt stability --quick` end to end: the CSV covers every family and the plots are
//! PNG files.

use std::path::{Path, PathBuf};
use std::process::Command;

const FAMILIES: [&str; 5] = ["spheres", "polynomials", "triangles", "slabs", "self_intersection"];

fn out_dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("spt-stability-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// The font the command uses (the same rule: `SPT_FONT`, else DejaVu Sans).
fn font_available() -> bool {
    let path = std::env::var_os("SPT_FONT")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf"));
    path.is_file()
}

/// True if `bytes` start like a PNG file with a non-empty image (signature, IHDR).
fn is_png(bytes: &[u8]) -> bool {
    const SIGNATURE: [u8; 8] = [0x89, b'P', b'N', b'G', b'\r', b'\n', 0x1a, b'\n'];
    if bytes.len() < 24 || bytes[..8] != SIGNATURE || &bytes[12..16] != b"IHDR" {
        return false;
    }
    let width = u32::from_be_bytes(bytes[16..20].try_into().unwrap());
    let height = u32::from_be_bytes(bytes[20..24].try_into().unwrap());
    width > 0 && height > 0
}

#[test]
fn quick_run_writes_csv_for_every_family_and_png_plots() {
    let dir = out_dir("quick");
    let out = Command::new(env!("CARGO_BIN_EXE_spt"))
        .args(["stability", "--quick", "--out", dir.to_str().unwrap()])
        .output()
        .expect("spt runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "spt stability failed: {stderr}");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.lines().next().is_some_and(|l| l.starts_with("family") && l.contains("ns/test")), "{stdout}");

    let csv = std::fs::read_to_string(dir.join("stability.csv")).expect("stability.csv written");
    let mut lines = csv.lines();
    assert_eq!(
        lines.next(),
        Some("family,method,case,tests,failures,failure_rate,not_converged,ns_per_test"),
        "CSV header"
    );
    let rows: Vec<&str> = lines.collect();
    for family in FAMILIES {
        let n = rows.iter().filter(|l| l.starts_with(&format!("{family},"))).count();
        assert!(n >= 4, "{family}: {n} CSV rows");
    }
    // Every row: a positive number of tests and no more failures than tests (the last
    // five fields never contain commas).
    for line in &rows {
        let fields: Vec<&str> = line.rsplitn(6, ',').collect();
        let tests: u64 = fields[4].parse().unwrap_or_else(|_| panic!("tests in {line}"));
        let failures: u64 = fields[3].parse().unwrap_or_else(|_| panic!("failures in {line}"));
        assert!(tests > 0 && failures <= tests, "{line}");
    }

    if !font_available() {
        println!("skipping the PNG checks: no font (install fonts-dejavu-core or set SPT_FONT)");
        assert!(stderr.contains("fonts-dejavu-core"), "the missing font is reported: {stderr}");
        return;
    }
    for family in FAMILIES {
        let png = dir.join(format!("{family}.png"));
        let bytes = std::fs::read(&png).unwrap_or_else(|e| panic!("{}: {e}", png.display()));
        assert!(is_png(&bytes), "{} is not a PNG", png.display());
    }
}

#[test]
fn selected_families_only_and_unknown_ones_rejected() {
    let dir = out_dir("slabs");
    let out = Command::new(env!("CARGO_BIN_EXE_spt"))
        .args(["stability", "--quick", "--families", "slabs", "--out", dir.to_str().unwrap()])
        .output()
        .expect("spt runs");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let csv = std::fs::read_to_string(dir.join("stability.csv")).unwrap();
    assert!(csv.lines().skip(1).all(|l| l.starts_with("slabs,")), "{csv}");
    assert!(!dir.join("spheres.png").exists());

    let out = Command::new(env!("CARGO_BIN_EXE_spt"))
        .args(["stability", "--quick", "--families", "cubes", "--out", dir.to_str().unwrap()])
        .output()
        .expect("spt runs");
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("unknown family"));
}
