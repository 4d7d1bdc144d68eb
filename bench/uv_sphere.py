"""A UV sphere written as OBJ text, shared by bench/time_to_error.py (the glass and mirror
spheres in the box) and bench/glowing_room_obj.py (the analytic glowing room)."""
import math


def write_uv_sphere(f, centre, radius, rings=64, segments=128, smooth=True, inward=False):
    """Writes to the open file `f` a UV sphere of 2·segments·(rings−1) triangles (the pole
    rings' quads are single triangles): with a normal per vertex where `smooth` (else flat
    shaded), facing outwards, or inwards (winding and normals reversed) where `inward`."""
    sign = -1.0 if inward else 1.0
    for i in range(rings + 1):
        theta = math.pi * i / rings
        for j in range(segments):
            phi = 2 * math.pi * j / segments
            n = (math.sin(theta) * math.cos(phi), math.cos(theta), math.sin(theta) * math.sin(phi))
            f.write("v %.7f %.7f %.7f\n" % tuple(c + radius * x for c, x in zip(centre, n)))
            if smooth:
                f.write("vn %.7f %.7f %.7f\n" % tuple(sign * x for x in n))
    vid = lambda i, j: i * segments + (j % segments) + 1
    corner = (lambda v: f"{v}//{v}") if smooth else str
    for i in range(rings):
        for j in range(segments):
            a, b, c, d = vid(i, j), vid(i, j + 1), vid(i + 1, j), vid(i + 1, j + 1)
            for tri, keep in (((a, b, c), i > 0), ((b, d, c), i < rings - 1)):
                if keep:
                    tri = tri[::-1] if inward else tri
                    f.write("f " + " ".join(corner(v) for v in tri) + "\n")
