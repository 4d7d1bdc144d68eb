//! `spt stability`: the adversarial accuracy/speed suite of the `shapes` routines
//! ([`suite`]) as a table on stdout, a CSV file and one scatter plot per family (speed
//! against failure rate, one point per method).

mod suite;

use anyhow::{Context, Result, anyhow, bail};
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::{FontStyle, register_font};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use suite::{FAMILIES, Row, Scale, run_family};

/// The font the plots' text is drawn with, unless `SPT_FONT` names another TrueType file.
const DEFAULT_FONT: &str = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";

/// Point colours: dark enough to read as text on white.
pub(crate) const COLOURS: [RGBColor; 8] = [
    RGBColor(0, 90, 181),
    RGBColor(220, 50, 32),
    RGBColor(0, 140, 70),
    RGBColor(150, 60, 170),
    RGBColor(200, 110, 0),
    RGBColor(0, 130, 140),
    RGBColor(120, 80, 40),
    RGBColor(60, 60, 60),
];

/// Zero failure rates are drawn at this rate (a log axis has no 0) and labelled "0".
const RATE_FLOOR: f64 = 1e-7;

/// Arguments of `spt stability`.
#[derive(clap::Args)]
pub struct StabilityArgs {
    /// Output directory for stability.csv and the per-family PNG plots.
    #[arg(short, long, default_value = "stability")]
    out: PathBuf,
    /// Small case sets (the unit tests' size) instead of the full ones.
    #[arg(long)]
    quick: bool,
    /// Families to run, comma-separated (default: all): spheres, polynomials, triangles,
    /// slabs, self_intersection.
    #[arg(long, value_delimiter = ',')]
    families: Vec<String>,
}

/// Runs the suite, prints the table, writes `OUT/stability.csv` and `OUT/<family>.png`.
/// Without a usable font the plots are skipped with a warning (the CSV is still written).
pub fn run(args: StabilityArgs) -> Result<()> {
    let families = select_families(&args.families)?;
    let scale = if args.quick { Scale::Quick } else { Scale::Full };
    std::fs::create_dir_all(&args.out).with_context(|| format!("creating {}", args.out.display()))?;

    let mut rows = Vec::new();
    for family in &families {
        eprintln!("running {family} …");
        rows.extend(run_family(family, scale).ok_or_else(|| anyhow!("unknown family {family}"))?);
    }
    print!("{}", table(&rows));

    let csv_path = args.out.join("stability.csv");
    std::fs::write(&csv_path, csv(&rows)).with_context(|| format!("writing {}", csv_path.display()))?;
    eprintln!("wrote {}", csv_path.display());

    if !load_font() {
        return Ok(());
    }
    for family in &families {
        let family_rows: Vec<&Row> = rows.iter().filter(|r| r.family == *family).collect();
        let path = args.out.join(format!("{family}.png"));
        plot_family(&path, family, &aggregate(&family_rows)).with_context(|| format!("plotting {}", path.display()))?;
        eprintln!("wrote {}", path.display());
    }
    Ok(())
}

/// The requested families in suite order (all if none), `-` accepted for `_`.
fn select_families(requested: &[String]) -> Result<Vec<&'static str>> {
    if requested.is_empty() {
        return Ok(FAMILIES.to_vec());
    }
    let mut chosen = Vec::new();
    for name in requested {
        let norm = name.trim().replace('-', "_");
        let Some(f) = FAMILIES.iter().find(|f| **f == norm) else {
            bail!("unknown family {name:?}; choose from {}", FAMILIES.join(", "));
        };
        if !chosen.contains(f) {
            chosen.push(*f);
        }
    }
    chosen.sort_by_key(|f| FAMILIES.iter().position(|g| g == f));
    Ok(chosen)
}

/// The fixed-width table printed to stdout.
fn table(rows: &[Row]) -> String {
    let header = ["family", "method", "case", "tests", "failures", "rate", "not conv.", "ns/test"];
    let cells: Vec<[String; 8]> = rows
        .iter()
        .map(|r| {
            [
                r.family.to_string(),
                r.method.clone(),
                r.case.clone(),
                r.tests.to_string(),
                r.failures.to_string(),
                format_rate(r.failure_rate()),
                r.not_converged.to_string(),
                format!("{:.1}", r.ns_per_test),
            ]
        })
        .collect();
    let mut width = header.map(|h| h.chars().count());
    for c in &cells {
        for (w, s) in width.iter_mut().zip(c) {
            *w = (*w).max(s.chars().count());
        }
    }
    let line = |c: &[String]| {
        let mut s = String::new();
        for (i, (cell, w)) in c.iter().zip(width).enumerate() {
            let pad = w - cell.chars().count();
            if i >= 3 {
                s.push_str(&" ".repeat(pad));
                s.push_str(cell);
            } else {
                s.push_str(cell);
                s.push_str(&" ".repeat(pad));
            }
            s.push_str(if i + 1 < c.len() { "  " } else { "\n" });
        }
        s
    };
    let mut out = line(&header.map(String::from));
    out.push_str(&line(&width.map(|w| "-".repeat(w))));
    for c in &cells {
        out.push_str(&line(c));
    }
    out
}

/// A failure rate for people: "0", or three significant digits.
fn format_rate(rate: f64) -> String {
    if rate == 0.0 { "0".into() } else { format!("{rate:.3e}") }
}

/// A CSV field, quoted if it contains a comma, quote or line break.
fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) { format!("\"{}\"", s.replace('"', "\"\"")) } else { s.to_string() }
}

/// Header and one line per row.
fn csv(rows: &[Row]) -> String {
    let mut out = String::from("family,method,case,tests,failures,failure_rate,not_converged,ns_per_test\n");
    for r in rows {
        let _ = writeln!(
            out,
            "{},{},{},{},{},{},{},{:.3}",
            csv_field(r.family),
            csv_field(&r.method),
            csv_field(&r.case),
            r.tests,
            r.failures,
            r.failure_rate(),
            r.not_converged,
            r.ns_per_test
        );
    }
    out
}

/// One plotted point: a method over all cases of its family.
struct Point {
    method: String,
    /// Mean ns per test, weighted by tests.
    ns: f64,
    /// Total failures / total tests.
    rate: f64,
}

/// Per method (in first-appearance order): total failures / total tests and the mean
/// time weighted by tests.
fn aggregate(rows: &[&Row]) -> Vec<Point> {
    let mut methods: Vec<&str> = Vec::new();
    for r in rows {
        if !methods.contains(&r.method.as_str()) {
            methods.push(&r.method);
        }
    }
    methods
        .into_iter()
        .map(|m| {
            let (mut tests, mut failures, mut ns) = (0u64, 0u64, 0f64);
            for r in rows.iter().filter(|r| r.method == m) {
                tests += r.tests;
                failures += r.failures;
                ns += r.ns_per_test * r.tests as f64;
            }
            let t = tests.max(1) as f64;
            Point { method: m.to_string(), ns: ns / t, rate: failures as f64 / t }
        })
        .collect()
}

/// Registers the plots' font ("sans-serif"); false (with a warning) if there is none.
pub(crate) fn load_font() -> bool {
    let path = std::env::var_os("SPT_FONT").map(PathBuf::from).unwrap_or_else(|| PathBuf::from(DEFAULT_FONT));
    let bytes = match std::fs::read(&path) {
        Ok(b) => b,
        Err(e) => {
            eprintln!(
                "warning: cannot read the font {} ({e}): install the Debian package fonts-dejavu-core or set \
                 SPT_FONT to a .ttf file; skipping the PNG plots",
                path.display()
            );
            return false;
        }
    };
    // plotters keeps the font for the life of the process.
    let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
    if register_font("sans-serif", FontStyle::Normal, bytes).is_err() {
        eprintln!("warning: {} is not a usable font; skipping the PNG plots", path.display());
        return false;
    }
    true
}

/// The scatter plot of one family: x = ns per test (log if the values span more than
/// 10×), y = failure rate on a log axis with zero drawn at [`RATE_FLOOR`] as "0".
fn plot_family(path: &Path, family: &str, points: &[Point]) -> Result<()> {
    let ns: Vec<f64> = points.iter().map(|p| p.ns.max(1e-3)).collect();
    let lo = ns.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = ns.iter().copied().fold(0.0, f64::max);
    if !(lo.is_finite() && hi.is_finite()) {
        bail!("no points to plot");
    }
    if hi / lo > 10.0 {
        draw(path, family, points, (lo / 1.6..hi * 1.6).log_scale())
    } else {
        let span = (hi - lo).max(0.1 * hi);
        draw(path, family, points, (lo - 0.4 * span).max(0.0)..hi + 0.4 * span)
    }
}

fn draw<X>(path: &Path, family: &str, points: &[Point], x: X) -> Result<()>
where
    X: AsRangedCoord<Value = f64>,
    X::CoordDescType: ValueFormatter<f64>,
{
    let err = |e: &dyn std::fmt::Display| anyhow!("{e}");
    let root = BitMapBackend::new(path, (960, 640)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(family, ("sans-serif", 30))
        .margin(24)
        .x_label_area_size(56)
        .y_label_area_size(80)
        .build_cartesian_2d(x, (RATE_FLOOR / 2.0..2.0).log_scale())
        .map_err(|e| err(&e))?;
    chart
        .configure_mesh()
        .x_desc("ns per test (mean over cases, weighted by tests)")
        .y_desc("failure rate (all cases)")
        .x_label_formatter(&|v: &f64| match v.abs() {
            a if a >= 10.0 || a == 0.0 => format!("{v:.0}"),
            a if a >= 1.0 => format!("{v:.1}"),
            _ => format!("{v:.2}"),
        })
        .y_label_formatter(&|v: &f64| if *v <= RATE_FLOOR * 1.001 { "0".into() } else { format!("{v:.0e}") })
        .label_style(("sans-serif", 16))
        .axis_desc_style(("sans-serif", 18))
        .draw()
        .map_err(|e| err(&e))?;
    for (i, p) in points.iter().enumerate() {
        let colour = COLOURS[i % COLOURS.len()];
        let at = (p.ns.max(1e-3), if p.rate > 0.0 { p.rate.max(RATE_FLOOR) } else { RATE_FLOOR });
        let label = format!("{}: {}", p.method, format_rate(p.rate));
        // Labels of points in the right half go to their left; labels of points at the
        // same height are staggered so they do not overlap.
        let right_half = chart.backend_coord(&at).0 > 560;
        let (dx, hpos) = if right_half { (-10, HPos::Right) } else { (10, HPos::Left) };
        let dy = -6 - 18 * (i as i32 % 3);
        let style = ("sans-serif", 16).into_font().color(&colour).pos(Pos::new(hpos, VPos::Bottom));
        chart
            .draw_series(std::iter::once(
                EmptyElement::at(at) + Circle::new((0, 0), 6, colour.filled()) + Text::new(label, (dx, dy), style),
            ))
            .map_err(|e| err(&e))?;
    }
    root.present().map_err(|e| err(&e))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(method: &str, tests: u64, failures: u64, ns: f64) -> Row {
        Row {
            family: "spheres",
            method: method.into(),
            case: "c, with comma".into(),
            tests,
            failures,
            not_converged: 0,
            ns_per_test: ns,
        }
    }

    #[test]
    fn families_are_validated_and_ordered() {
        assert_eq!(select_families(&[]).unwrap(), FAMILIES.to_vec());
        let picked = select_families(&["slabs".into(), "self-intersection".into(), "spheres".into()]).unwrap();
        assert_eq!(picked, vec!["spheres", "slabs", "self_intersection"]);
        assert!(select_families(&["nope".into()]).is_err());
    }

    #[test]
    fn csv_quotes_and_aggregates_weight_by_tests() {
        let rows = [row("a", 100, 0, 10.0), row("a", 300, 3, 20.0), row("b", 10, 5, 1.0)];
        let text = csv(&rows);
        assert!(text.starts_with("family,method,case,"));
        assert_eq!(text.lines().count(), 4);
        assert!(text.contains("\"c, with comma\""));
        let refs: Vec<&Row> = rows.iter().collect();
        let pts = aggregate(&refs);
        assert_eq!(pts.len(), 2);
        assert!((pts[0].ns - 17.5).abs() < 1e-9 && (pts[0].rate - 3.0 / 400.0).abs() < 1e-12);
        assert!((pts[1].rate - 0.5).abs() < 1e-12);
        let t = table(&rows);
        assert_eq!(t.lines().count(), 5);
        assert!(t.contains("7.500e-3") || t.contains("1.000e-2"));
    }
}
