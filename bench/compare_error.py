#!/usr/bin/env python3
"""Error of a render against a converged reference: relMSE and mean |z|.

    python3 bench/compare_error.py REF.exr IMAGE.exr [IMAGE.exr ...]

relMSE = mean over pixel-channels of (img - ref)^2 / (ref^2 + 1e-2), the metric the
Mitsuba references' README quotes (and Rousselle et al. use). Prints one line per image.
"""
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
