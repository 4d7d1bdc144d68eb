#!/usr/bin/env python3
"""Writes a finer copy of a triangle OBJ: each triangle split into four at its edge
midpoints, N times (×4ᴺ triangles), for GPU and CPU figures on a mesh of a million
triangles or more (the Stanford bunny's 69 451 → 1 111 216 at N = 2). Positions only:
normals and texture coordinates are dropped, faces are fanned into triangles, shared
edges keep shared midpoints (the surface stays watertight).

    python3 bench/gpu/subdivide_obj.py IN.obj OUT.obj [N]
"""
import sys


def read_obj(path):
    positions, faces = [], []
    with open(path) as f:
        for line in f:
            parts = line.split()
            if not parts:
                continue
            if parts[0] == "v":
                positions.append(tuple(float(x) for x in parts[1:4]))
            elif parts[0] == "f":
                idx = []
                for p in parts[1:]:
                    i = int(p.split("/")[0])
                    idx.append(i - 1 if i > 0 else len(positions) + i)
                for k in range(1, len(idx) - 1):
                    faces.append((idx[0], idx[k], idx[k + 1]))
    return positions, faces


def subdivide(positions, faces):
    midpoints = {}

    def mid(a, b):
        key = (a, b) if a < b else (b, a)
        i = midpoints.get(key)
        if i is None:
            pa, pb = positions[a], positions[b]
            positions.append(tuple((x + y) * 0.5 for x, y in zip(pa, pb)))
            i = midpoints[key] = len(positions) - 1
        return i

    out = []
    for a, b, c in faces:
        ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
        out += [(a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca)]
    return out


def main():
    if len(sys.argv) not in (3, 4):
        sys.exit(__doc__)
    positions, faces = read_obj(sys.argv[1])
    for _ in range(int(sys.argv[3]) if len(sys.argv) == 4 else 2):
        faces = subdivide(positions, faces)
    with open(sys.argv[2], "w") as f:
        f.write("# %d triangles, subdivided from %s\n" % (len(faces), sys.argv[1]))
        f.writelines("v %.7g %.7g %.7g\n" % p for p in positions)
        f.writelines("f %d %d %d\n" % (a + 1, b + 1, c + 1) for a, b, c in faces)
    print("%s: %d triangles" % (sys.argv[2], len(faces)), file=sys.stderr)


if __name__ == "__main__":
    main()
