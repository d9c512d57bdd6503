#!/usr/bin/env python3
"""How deep the mesh edges of a draped rest state cut into the drapemeter pedestal.

    python3 scripts/rim_cut.py REST.obj [DISC_DIAMETER_MM]

REST.obj is written by `drape simulate --out DIR` (metres, pedestal top at z = 0,
axis at x = y = 0). Each mesh edge is sampled at 101 points; a point inside the
pedestal (radius < R2 and z < 0) cuts it by min(R2 - r, -z). Prints the number
of cutting edges and the deepest cut in mm (docs/decisions/0001-edge-contact.md).
"""
import math
import sys

if len(sys.argv) < 2:
    sys.exit(__doc__)
path = sys.argv[1]
r2 = (float(sys.argv[2]) if len(sys.argv) > 2 else 150.0) / 2000.0
V, E = [], set()
try:
    with open(path) as f:
        for line in f:
            p = line.split()
            if not p:
                continue
            if p[0] == "v":
                V.append([float(x) for x in p[1:4]])
            elif p[0] == "f":
                ids = [int(x.split("/")[0]) - 1 for x in p[1:]]
                for i in range(len(ids)):
                    a, b = ids[i], ids[(i + 1) % len(ids)]
                    E.add((min(a, b), max(a, b)))
except OSError as e:
    sys.exit(f"{path}: {e.strerror}")
if not V or not E:
    sys.exit(f"{path}: no vertices or faces (not a rest.obj from drape simulate --out?)")
cutting, deepest = 0, 0.0
for a, b in E:
    d = 0.0
    for k in range(101):
        t = k / 100.0
        x, y, z = (V[a][c] * (1 - t) + V[b][c] * t for c in range(3))
        r = math.hypot(x, y)
        if r < r2 and z < 0:
            d = max(d, min(r2 - r, -z))
    if d > 0:
        cutting += 1
        deepest = max(deepest, d)
print(f"{path}: {len(V)} vertices, {len(E)} edges; {cutting} edges cut into the pedestal, deepest {deepest * 1e3:.2f} mm")
