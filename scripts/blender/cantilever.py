"""Blender's cloth bending against the heavy elastica: a strip clamped at one end.

    blender -b --factory-startup --python scripts/blender/cantilever.py -- \
        --bend-Nm 4e-6 --density-gm2 125 [--length-mm 100] [--spacing-mm 7.5] [--json OUT]

A strip of length L (width 4 spacings) meshed in squares of side h (two
triangles each), its first two columns pinned (a clamp: position and slope),
Blender's settings from docs/library.md's mapping of the physical fabric (as
drape_record.py sets them), hangs under gravity to rest. The elastica of the
same strip (bending rigidity B per width, weight w = rho g per area):
theta'' = -(w / B) (L - s) cos(theta), theta(0) = 0, theta'(L) = 0, solved by
shooting; the bending rigidity Blender behaves as is the B whose elastica
droops as far as Blender's strip. Prints B_blender / B for the spacing.
"""
import argparse
import json
import math
import os
import sys
import time

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from drape_record import physical_cloth  # noqa: E402 (the same mapping as the drapes)


def args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    ap = argparse.ArgumentParser(prog="cantilever.py")
    ap.add_argument("--bend-Nm", type=float, default=4e-6)
    ap.add_argument("--density-gm2", type=float, default=125.0)
    ap.add_argument("--stretch-N-m", type=float, default=2000.0)
    ap.add_argument("--shear-N-m", type=float, default=20.0)
    ap.add_argument("--length-mm", type=float, default=100.0)
    ap.add_argument("--spacing-mm", type=float, default=7.5)
    ap.add_argument("--vertex-mass", type=float, default=0.1)
    ap.add_argument("--quality", type=int, default=8)
    ap.add_argument("--frames", type=int, default=400)
    ap.add_argument("--json", default="")
    return ap.parse_args(argv)


def droop(lam, n=2000):
    """Tip drop / L of the heavy elastica with lambda = w L^3 / B (s in units of L)."""
    def shoot(k0):  # theta'(0) = k0 (curvature at the clamp, downward positive)
        th, k, ds = 0.0, k0, 1.0 / n
        y = 0.0
        for i in range(n):
            s = i * ds
            # theta (downward from the horizontal) and k = theta'; theta'' = -lam (1 - s) cos(theta)
            def f(s_, th_, k_):
                return k_, -lam * (1 - s_) * math.cos(th_)
            a1, b1 = f(s, th, k)
            a2, b2 = f(s + ds / 2, th + ds / 2 * a1, k + ds / 2 * b1)
            a3, b3 = f(s + ds / 2, th + ds / 2 * a2, k + ds / 2 * b2)
            a4, b4 = f(s + ds, th + ds * a3, k + ds * b3)
            y += ds * math.sin(th + ds / 2 * a1)
            th += ds / 6 * (a1 + 2 * a2 + 2 * a3 + a4)
            k += ds / 6 * (b1 + 2 * b2 + 2 * b3 + b4)
        return k, y
    lo, hi = 0.0, lam  # theta'(0) between 0 and lambda / 2 (the linear beam's)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        k_end, _ = shoot(mid)
        if k_end > 0:
            hi = mid
        else:
            lo = mid
    return shoot(0.5 * (lo + hi))[1]


def main():
    a = args()
    t0 = time.time()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.gravity = (0.0, 0.0, -9.81)
    h = a.spacing_mm / 1000.0
    nx = round(a.length_mm / a.spacing_mm) + 1  # columns 0..nx-1 from the clamp (x = 0) to the tip
    ny = 5
    verts = [((i - 1) * h, (j - 2) * h, 0.0) for i in range(nx + 1) for j in range(ny)]  # column 0 at x = -h: the clamp's second row
    faces = []
    for i in range(nx):
        for j in range(ny - 1):
            v = i * ny + j
            faces.append((v, v + ny, v + ny + 1))
            faces.append((v, v + ny + 1, v + 1))
    me = bpy.data.meshes.new("strip")
    me.from_pydata(verts, [], faces)
    me.update()
    ob = bpy.data.objects.new("strip", me)
    scene.collection.objects.link(ob)
    vg = ob.vertex_groups.new(name="pin")
    vg.add([i * ny + j for i in range(2) for j in range(ny)], 1.0, "REPLACE")
    mod = ob.modifiers.new("Cloth", "CLOTH")
    s = mod.settings
    s.quality = a.quality
    s.vertex_group_mass = "pin"
    s.bending_model = "ANGULAR"
    s.air_damping = 2.0
    s.tension_damping = s.compression_damping = s.shear_damping = 25.0
    s.bending_damping = 5.0
    # Each interior vertex of the square grid carries a square h x h.
    physical_cloth(s, a.density_gm2 * 1e-3 * h * h, h, a.bend_Nm, a.stretch_N_m, a.shear_N_m, a.vertex_mass)
    mod.collision_settings.use_collision = False
    mod.point_cache.frame_end = a.frames
    scene.frame_end = a.frames
    tip = [(nx) * ny + j for j in range(ny)]
    last = None
    for fr in range(1, a.frames + 1):
        scene.frame_set(fr)
        if fr % 50 == 0:
            ev = ob.evaluated_get(bpy.context.evaluated_depsgraph_get())
            z = sum(ev.data.vertices[v].co.z for v in tip) / len(tip)
            if last is not None and abs(z - last) < 1e-5 and fr >= 200:
                break
            last = z
    ev = ob.evaluated_get(bpy.context.evaluated_depsgraph_get())
    z = -sum(ev.data.vertices[v].co.z for v in tip) / len(tip)
    L = nx * h  # from the clamp (x = 0) to the tip column
    w = a.density_gm2 * 1e-3 * 9.81
    lam = w * L ** 3 / a.bend_Nm
    d_model = droop(lam) * L
    # The B whose elastica droops as far (bisection on log B).
    lo, hi = math.log(a.bend_Nm) - 3, math.log(a.bend_Nm) + 3  # a factor 20 either way (the shooting is unreliable far beyond)
    for _ in range(50):
        mid = 0.5 * (lo + hi)
        if droop(w * L ** 3 / math.exp(mid)) * L > z:
            lo = mid
        else:
            hi = mid
    b_eff = math.exp(0.5 * (lo + hi))
    out = {"spacing_mm": a.spacing_mm, "length_mm": 1000 * L, "bend_Nm": a.bend_Nm, "lambda": lam, "droop_blender_mm": 1000 * z,
           "droop_elastica_mm": 1000 * d_model, "bend_blender_Nm": b_eff, "ratio": b_eff / a.bend_Nm, "frames": fr,
           "wall_s": round(time.time() - t0, 1)}
    print("cantilever: " + json.dumps(out))
    if a.json:
        with open(a.json, "w") as fh:
            json.dump(out, fh, indent=2)


main()
