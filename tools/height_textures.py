#!/usr/bin/env python3
"""Writes the example height maps (tileable, 8-bit grey PNGs) into examples/textures/.

bricks_height.png: staggered bricks, 4 rows x 2 bricks a tile, raised 1.0 with
smooth bevels into mortar at 0.15 (slopes stay moderate: the sphere tracer's step
bound grows with the steepest texel step).
dimples_height.png: a hexagonal lattice of round dimples, 0.6 deep, on 1.0.
"""
import math
import os
from PIL import Image

N = 256
here = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "examples", "textures")


def smooth(t):
    t = min(max(t, 0.0), 1.0)
    return t * t * (3 - 2 * t)


def bricks():
    img = Image.new("L", (N, N))
    rows, cols, bevel = 4, 2, 0.06  # bevel in tile units
    for y in range(N):
        for x in range(N):
            u, v = (x + 0.5) / N, (y + 0.5) / N
            r = int(v * rows)
            uu = u * cols + (0.5 if r % 2 else 0.0)
            fu = uu - math.floor(uu)
            fv = v * rows - r
            # distance to the brick's edge, in tile units
            du = min(fu, 1 - fu) / cols
            dv = min(fv, 1 - fv) / rows
            e = min(du, dv)
            h = 0.15 + 0.85 * smooth((e - 0.006) / bevel)
            img.putpixel((x, y), int(round(255 * h)))
    img.save(os.path.join(here, "bricks_height.png"))


def dimples():
    img = Image.new("L", (N, N))
    # a lattice that tiles the unit square: 4 columns, rows offset by half
    k = 4
    for y in range(N):
        for x in range(N):
            u, v = (x + 0.5) / N * k, (y + 0.5) / N * k
            best = 9.0
            for j in range(-1, k + 2):
                for i in range(-1, k + 2):
                    cx = i + (0.5 if j % 2 else 0.0)
                    cy = j
                    best = min(best, math.hypot(u - cx, v - cy))
            h = 1.0 - 0.6 * smooth(1 - best / 0.45)
            img.putpixel((x, y), int(round(255 * h)))
    img.save(os.path.join(here, "dimples_height.png"))


if __name__ == "__main__":
    bricks()
    dimples()
