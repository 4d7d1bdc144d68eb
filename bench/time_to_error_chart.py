#!/usr/bin/env python3
"""Chart of equal-error efficiency against Mitsuba 3, run by run (docs/time-to-error.csv).

Each row of the CSV is one configuration measured by bench/time_to_error.py; `ratio` is its
efficiency (1 / (relMSE x sampling time)) divided by that of Mitsuba 3's best sampler in
the same run, so rows of different runs compare. Draws horizontal bars grouped by run,
with parity (1.0) and the issue's goal (2.0) marked, to PNG (and SVG with --svg).

Usage (pip install matplotlib):

    python3 bench/time_to_error_chart.py [docs/time-to-error.csv] [-o docs/time-to-error] [--svg]
"""
import argparse, csv, os

HERE = os.path.dirname(os.path.abspath(__file__))
DOCS = os.path.normpath(os.path.join(HERE, "..", "docs"))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("csv", nargs="?", default=os.path.join(DOCS, "time-to-error.csv"))
    ap.add_argument("-o", "--out", default=os.path.join(DOCS, "time-to-error"), help="output path without extension")
    ap.add_argument("--svg", action="store_true", help="also write an SVG")
    a = ap.parse_args()
    with open(a.csv, newline="", encoding="utf-8") as f:
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    if not rows:
        raise SystemExit(f"{a.csv}: no rows")
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    labels = [f"{r['date']}: {r['configuration']}" for r in rows]
    ratios = [float(r["ratio"]) for r in rows]
    colours = ["#888888" if r["configuration"].startswith("Mitsuba") else "#1f77b4" for r in rows]
    fig, ax = plt.subplots(figsize=(12, 0.42 * len(rows) + 1.6))
    y = range(len(rows))[::-1]
    ax.barh(list(y), ratios, color=colours)
    for yi, v in zip(y, ratios):
        ax.text(v + 0.02, yi, f"{v:.2f}", va="center", fontsize=8)
    ax.set_yticks(list(y))
    ax.set_yticklabels(labels, fontsize=8)
    ax.axvline(1.0, color="black", linewidth=0.8)
    ax.axvline(2.0, color="#d62728", linewidth=0.8, linestyle="--")
    ax.text(2.0, len(rows) - 0.4, " goal: 2x", color="#d62728", fontsize=8, va="bottom")
    ax.set_xlim(0, max(2.3, max(ratios) + 0.3))
    ax.set_xlabel("equal-error efficiency / Mitsuba 3's best\nin the same run (higher is better)")
    # Over the whole figure: the axes are narrower than the title beside the long labels.
    fig.suptitle("Cornell box 256², 64 spp, 2 threads: time to equal error against Mitsuba 3", fontsize=10)
    fig.tight_layout()
    for ext in ("png", "svg") if a.svg else ("png",):
        fig.savefig(f"{a.out}.{ext}", dpi=110)
        print(f"wrote {a.out}.{ext}")


if __name__ == "__main__":
    main()
