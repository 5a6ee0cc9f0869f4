#!/usr/bin/env python3
"""Writes data/parts/demo_block.stl: the placeholder demo part (a 160 x 120 x 80 mm block,
base on z = 0, centred on the z axis). Run from anywhere: python3 data/parts/make_demo_part.py"""
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))


def box_triangles(sx, sy, sz):
    x, y = sx / 2, sy / 2
    v = [(-x, -y, 0), (x, -y, 0), (x, y, 0), (-x, y, 0),
         (-x, -y, sz), (x, -y, sz), (x, y, sz), (-x, y, sz)]
    quads = [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)]
    for a, b, c, d in quads:
        yield v[a], v[b], v[c]
        yield v[a], v[c], v[d]


def write_binary_stl(path, triangles):
    triangles = list(triangles)
    with open(path, "wb") as f:
        f.write(b"scanplan demo part".ljust(80, b" "))
        f.write(struct.pack("<I", len(triangles)))
        for tri in triangles:
            f.write(struct.pack("<3f", 0.0, 0.0, 0.0))
            for p in tri:
                f.write(struct.pack("<3f", *p))
            f.write(struct.pack("<H", 0))


if __name__ == "__main__":
    write_binary_stl(os.path.join(HERE, "demo_block.stl"), box_triangles(160.0, 120.0, 80.0))
