#!/usr/bin/env python3
"""Writes the glowing room of tests/tests/analytic.rs as an OBJ and its MTL: a flat-shaded
UV sphere of radius 1 (24 rings, 48 segments) facing inwards, Lambertian with albedo RHO
that emits LE everywhere, so its radiance is LE / (1 - RHO) at every point and in every
direction. For checking a backend or integrator by hand from the CLI, e.g.:

    python3 bench/glowing_room_obj.py /tmp/room 0.8 0.5
    spt render /tmp/room/room.obj --integrator bdpt --spectral rgb --width 12 --height 12 \\
      --spp 512 --eye 0.1,0.2,0.3 --center 0,0,-1 --fov 90 --sky none -o room.exr

Usage: python3 bench/glowing_room_obj.py DIR [RHO] [LE]   (defaults 0.8 and 0.5)
"""
import os, sys

from uv_sphere import write_uv_sphere


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    out = sys.argv[1]
    rho = float(sys.argv[2]) if len(sys.argv) > 2 else 0.8
    le = float(sys.argv[3]) if len(sys.argv) > 3 else 0.5
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, "room.obj"), "w") as f:
        f.write("mtllib room.mtl\nusemtl wall\n")
        write_uv_sphere(f, (0.0, 0.0, 0.0), 1.0, rings=24, segments=48, smooth=False, inward=True)
    with open(os.path.join(out, "room.mtl"), "w") as f:
        f.write(f"newmtl wall\nKd {rho} {rho} {rho}\nKe {le} {le} {le}\n")
    print(f"wrote {out}/room.obj: radiance {le / (1 - rho):g} everywhere")


if __name__ == "__main__":
    main()
