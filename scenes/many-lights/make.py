#!/usr/bin/env python3
"""Writes many-lights.obj and many-lights.mtl: a 24 x 24 m hall with a floor and a back wall,
an 8 x 8 grid of small lamps (0.25 m squares) 1.5 m above the floor facing down, of four
colours and powers that vary fourfold, and 20 pillars among them. 64 lamps, 128 emissive
triangles: from any point of the floor a few lamps overhead give most of the light, which
is what choosing lights by a light tree (`spt render --light-sampler tree`) is for and what
choosing them by power alone (`--light-sampler power`) spends most of its shadow rays
beside. Deterministic (no random numbers): run it again to get the same files.

Also writes ../many-point-lights.toml: the same hall built of boxes, lit by point lights
and spots aimed down (alternating) where the lamps hang, each of the intensity its lamp
sends straight down — the light tree's case for punctual lights.

    python3 scenes/many-lights/make.py   # from the repository root
    spt render scenes/many-lights.toml -o many-lights.png
    spt render scenes/many-point-lights.toml -o many-point-lights.png
"""
import argparse, os

ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter)
ap.add_argument("--grid", type=int, default=8, help="lamps per side of the grid (8: the committed files)")
ap.add_argument("--out", help="folder to write to, with the same file names (default: beside this script)")
a = ap.parse_args()
here = a.out or os.path.dirname(os.path.abspath(__file__))
os.makedirs(here, exist_ok=True)
v, f = [], []  # vertices, faces as (material, [1-based vertex indices])


def quad(corners, material):
    """A quad of four corners, counter-clockwise seen from its front."""
    base = len(v)
    v.extend(corners)
    f.append((material, [base + 1, base + 2, base + 3, base + 4]))


def box(x0, z0, x1, z1, height, material):
    """A pillar: four sides and a top (the floor closes it)."""
    a, b, c, d = (x0, z0), (x1, z0), (x1, z1), (x0, z1)
    for (p, q) in ((a, b), (b, c), (c, d), (d, a)):
        quad([(p[0], 0, p[1]), (p[0], height, p[1]), (q[0], height, q[1]), (q[0], 0, q[1])], material)
    quad([(x0, height, z0), (x0, height, z1), (x1, height, z1), (x1, height, z0)], material)


quad([(-12, 0, -12), (-12, 0, 12), (12, 0, 12), (12, 0, -12)], "floor")
quad([(-12, 0, -12), (12, 0, -12), (12, 4, -12), (-12, 4, -12)], "wall")
n = a.grid
pillars = []  # (x0, z0, x1, z1, height)
punctual = []  # (kind, x, z, material)
for i in range(n):
    for j in range(n):
        # The grid spans the hall whatever its size: lamps 24/n apart.
        x, z, h = -12 + 24 * (i + 0.5) / n, -12 + 24 * (j + 0.5) / n, 0.125
        material = f"lamp{(i + 2 * j) % 4}_{(i * 3 + j) % 4}"
        quad([(x - h, 1.5, z - h), (x + h, 1.5, z - h), (x + h, 1.5, z + h), (x - h, 1.5, z + h)], material)
        punctual.append(("point" if (i + j) % 2 == 0 else "spot", x, z, material))
for k in range(20):
    i, j = (k * 7) % 9, (k * 4 + k // 3) % 9
    x, z = -12 + 3 * i, -12 + 3 * j
    box(x - 0.2, z - 0.2, x + 0.2, z + 0.2, 2.0, "pillar")
    pillars.append((x - 0.2, z - 0.2, x + 0.2, z + 0.2, 2.0))

colours = [(1.0, 0.75, 0.45), (0.55, 0.7, 1.0), (1.0, 0.45, 0.35), (0.6, 1.0, 0.6)]
with open(os.path.join(here, "many-lights.mtl"), "w") as m:
    m.write("# Written by make.py.\n")
    m.write("newmtl floor\nKd 0.6 0.6 0.6\n\nnewmtl wall\nKd 0.5 0.45 0.4\n\nnewmtl pillar\nKd 0.7 0.7 0.7\n")
    for c in range(4):
        for p in range(4):
            s = 20.0 * (1 + p)
            r, g, b = colours[c]
            m.write(f"\nnewmtl lamp{c}_{p}\nKd 0 0 0\nKe {r * s:g} {g * s:g} {b * s:g}\n")
with open(os.path.join(here, "many-lights.obj"), "w") as o:
    o.write("# Written by make.py: a hall lit by 64 small lamps.\nmtllib many-lights.mtl\n")
    for p in v:
        o.write("v %g %g %g\n" % p)
    current = None
    for material, idx in f:
        if material != current:
            o.write(f"usemtl {material}\n")
            current = material
        o.write("f " + " ".join(map(str, idx)) + "\n")

# The punctual variant: a lamp of side 2h and radiance Ke sends I = Ke·(2h)² straight down.
lamp_intensity = {}
for c in range(4):
    for p in range(4):
        s = 20.0 * (1 + p) * (2 * 0.125) ** 2
        lamp_intensity[f"lamp{c}_{p}"] = [x * s for x in colours[c]]
toml = os.path.join(here, "many-point-lights.toml") if a.out else os.path.join(here, "..", "many-point-lights.toml")
fmt = lambda xs: "[" + ", ".join(f"{x:g}" for x in xs) + "]"
with open(toml, "w") as t:
    t.write("# Written by scenes/many-lights/make.py: the hall of many-lights.toml built of boxes and lit\n"
            f"# by {len(punctual)} point lights and spots instead of its lamps. Next-event estimation chooses\n"
            "# them by a light tree here (the default from 8 lights); compare\n"
            "#   spt render scenes/many-point-lights.toml --light-sampler power -o power.png\n"
            "#   spt render scenes/many-point-lights.toml --light-sampler tree -o tree.png\n\n")
    t.write("[camera]\neye = [0.0, 1.0, 11.5]\ncenter = [0.0, 0.7, 0.0]\nfov = 55\n\n")
    for name, rgb in (("floor", (0.6, 0.6, 0.6)), ("wall", (0.5, 0.45, 0.4)), ("pillar", (0.7, 0.7, 0.7))):
        t.write(f"[materials.{name}]\nmodel = \"lambert\"\nreflectance = {fmt(rgb)}\n\n")
    boxes = [((-12, -0.1, -12), (12, 0, 12), "floor"), ((-12, 0, -12.1), (12, 4, -12), "wall")]
    boxes += [((x0, 0, z0), (x1, hgt, z1), "pillar") for (x0, z0, x1, z1, hgt) in pillars]
    for lo, hi, material in boxes:
        t.write(f"[[shape]]\ntype = \"box\"\nmin = {fmt(lo)}\nmax = {fmt(hi)}\nmaterial = \"{material}\"\n\n")
    for kind, x, z, material in punctual:
        t.write(f"[[light]]\ntype = \"{kind}\"\nposition = {fmt((x, 1.5, z))}\n")
        if kind == "spot":
            t.write("direction = [0, -1, 0]\ninner = 30\nouter = 50\n")
        t.write(f"intensity = {fmt(lamp_intensity[material])}\n\n")
    t.write("[render]\nwidth = 320\nheight = 240\nspp = 16\n")
