#!/usr/bin/env python3
"""Error of a render against a converged reference: relMSE and mean |z|.

    python3 bench/compare_error.py REF.exr IMAGE.exr [IMAGE.exr ...]

relMSE = mean over pixel-channels of (img - ref)^2 / (ref^2 + 1e-2), the metric the
Mitsuba references' README quotes (and Rousselle et al. use). Prints one line per image.
"""
import re
import subprocess
import sys

import numpy as np
import OpenEXR


def read_exr(path):
    """An EXR's RGB channels as a float64 array (height, width, 3)."""
    with OpenEXR.File(path) as f:
        px = f.parts[0].channels
        if "RGB" in px:
            return np.asarray(px["RGB"].pixels, dtype=np.float64)
        return np.stack([np.asarray(px[c].pixels, dtype=np.float64) for c in "RGB"], axis=-1)


def render_timed(cmd, out):
    """Runs `spt render` (`cmd`, which writes `out`): its sampling time (the seconds `spt
    render` prints, after loading and BVH build) and the image; exits with spt's message
    if it fails."""
    p = subprocess.run(cmd, capture_output=True, text=True)
    m = re.search(r"wrote .*?: ([0-9.]+) s,", p.stderr) if p.returncode == 0 else None
    if m is None:
        sys.exit(f"{' '.join(cmd)}: {p.stderr}")
    return float(m.group(1)), read_exr(out)


def rel_mse(img, ref):
    """Mean over pixel-channels of (img - ref)^2 / (ref^2 + 1e-2)."""
    return float(np.mean((img - ref) ** 2 / (ref**2 + 1e-2)))


def main():
    ref = read_exr(sys.argv[1])
    for path in sys.argv[2:]:
        img = read_exr(path)
        if img.shape != ref.shape:
            sys.exit(f"{path}: shape {img.shape} differs from the reference's {ref.shape}")
        print(f"{path}: relMSE {rel_mse(img, ref):.5f}, mean {img.reshape(-1, 3).mean(0).round(5).tolist()}")


if __name__ == "__main__":
    main()
