"""A drape test made by Blender's cloth simulator, written as a drape-lab record.

Run directly, or by scripts/blender-drapes.sh for a scan:

    blender -b --factory-startup --python scripts/blender/drape_record.py -- \
        --out DIR --sample-mm 300 --disc-mm 150 \
        (--bend-Nm B [--density-gm2 RHO] [--stretch-N-m Y] [--shear-N-m G] [--compression-ratio C] [--bending-factor F]
         | --bending K [--tension T] [--compression C] [--shear S] [--vertex-mass M] | --preset Cotton|Denim|...)
        [--spacing-mm 7.5] [--offset-mm=DX,DY] [--pin-centre-mm R] [--friction F] [--seed S] [--max-frames N]

An independent check of the engine: Blender's cloth (a mass-spring model with
angular bending springs, implicit integration, its own collision handling) has
nothing in common with Drapekit's solver. The specimen is a disc meshed in
concentric rings at a fixed spacing (so a fabric keeps one discretisation at every
set-up), laid flat on a cylindrical pedestal (top at z = 0, 120 mm high) with a
0.2 mm random waviness, and dropped until its D moves by less than --rest-dc
points over 100 frames. Written into DIR:

  rest.obj       the rest state (mm, pedestal top at z = 0, axis at x = y = 0)
  contours.csv   the outer envelope of horizontal cuts every 5 mm below the
                 pedestal top, on rays every 1 degree (the lab's format), where
                 the cut closes around the pedestal
  meta.json      the record (no cameras): the set-up, the fabric's declared
                 density and thickness, and lab_drape_coefficient_percent from
                 the vertical projection of the rest state
  blender.json   what Blender was given, D, the folds of the outline, the
                 specimen's centre at rest, and how the run ended

With --bend-Nm the fabric is physical: docs/library.md's mapping sets Blender's
vertex mass, tension, compression, shear and bending, all scaled by one factor so
the vertex mass is --vertex-mass (statics depend on the ratios only). Otherwise
Blender's own numbers (--bending, --tension, ...) or one of its presets are used.
docs/model-discrepancy.md ("An independent simulator") has the measured settings.
"""
import argparse
import json
import math
import os
import random
import sys
import time

import bpy


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    ap = argparse.ArgumentParser(prog="drape_record.py")
    ap.add_argument("--out", required=True)
    ap.add_argument("--sample-mm", type=float, default=300.0)
    ap.add_argument("--disc-mm", type=float, default=150.0)
    ap.add_argument("--spacing-mm", type=float, default=7.5)
    ap.add_argument("--bending", type=float, default=0.5, help="Blender's bending stiffness")
    ap.add_argument("--tension", type=float, default=100.0)
    ap.add_argument("--shear", type=float, default=10.0)
    ap.add_argument("--density-gm2", type=float, default=200.0, help="declared in meta.json")
    ap.add_argument("--thickness-mm", type=float, default=0.5, help="declared in meta.json")
    ap.add_argument("--offset-mm", default="0,0", help="specimen laid off the pedestal's axis (x,y)")
    ap.add_argument("--pin-centre-mm", type=float, default=0.0,
                    help="pin the specimen's vertices within this radius of its centre (as the engine anchors its centre: "
                         "no sliding off the pedestal)")
    ap.add_argument("--collision-mm", type=float, default=1.0,
                    help="Blender's cloth collision distance and the pedestal's outer thickness [mm]")
    ap.add_argument("--bending-model", default="ANGULAR", choices=["ANGULAR", "LINEAR"], help="Blender's bending springs")
    ap.add_argument("--friction", type=float, default=5.0, help="Blender's cloth friction on the pedestal")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--bend-Nm", type=float, default=0.0,
                    help="a physical fabric: bending rigidity B [N*m]; with it, --stretch-N-m, --shear-N-m and --density-gm2 set "
                         "Blender's vertex mass, tension, compression, shear and bending by docs/library.md's mapping (all "
                         "scaled by one factor so the vertex mass is --vertex-mass: statics depend on the ratios only)")
    ap.add_argument("--stretch-N-m", type=float, default=2000.0)
    ap.add_argument("--shear-N-m", type=float, default=20.0)
    ap.add_argument("--compression-ratio", type=float, default=1.0,
                    help="physical mode: Blender's compression stiffness as a fraction of its tension (woven fabric buckles)")
    ap.add_argument("--bending-factor", type=float, default=1.0,
                    help="physical mode: Blender's bending times this (scripts/blender/cantilever.py measures what Blender's "
                         "bending is against the elastica)")
    ap.add_argument("--preset", default="", help="one of Blender's own cloth presets (Cotton, Denim, Leather, Rubber, Silk): "
                    "its stiffnesses, mass, damping and quality replace the flags'")
    ap.add_argument("--compression", type=float, default=1.0, help="Blender's compression stiffness (woven fabric buckles: soft)")
    ap.add_argument("--vertex-mass", type=float, default=0.01, help="kg (statics depend on stiffness over weight only)")
    ap.add_argument("--bending-damping", type=float, default=5.0)
    ap.add_argument("--air-damping", type=float, default=2.0, help="Blender's air damping (settling speed only)")
    ap.add_argument("--quality", type=int, default=8, help="Blender's cloth steps per frame")
    ap.add_argument("--max-frames", type=int, default=1500)
    ap.add_argument("--rest-dc", type=float, default=0.3, help="at rest: D moves less than this [points] over 100 frames")
    ap.add_argument("--id", default="")
    a = ap.parse_args(argv)
    for name in ("sample_mm", "disc_mm", "spacing_mm", "bending", "tension", "shear", "density_gm2", "thickness_mm"):
        v = getattr(a, name)
        if not (v > 0 and math.isfinite(v)):
            ap.error("--%s must be a positive number, got %r" % (name.replace("_", "-"), v))
    if a.disc_mm >= a.sample_mm:
        ap.error("--disc-mm %g must be smaller than --sample-mm %g" % (a.disc_mm, a.sample_mm))
    try:
        a.offset = [float(t) for t in a.offset_mm.split(",")]
        assert len(a.offset) == 2 and all(math.isfinite(t) for t in a.offset)
    except (ValueError, AssertionError):
        ap.error("--offset-mm must be DX,DY in mm, got %r" % a.offset_mm)
    return a


def rings_mesh(radius, spacing):
    """A disc in concentric rings: ring i at radius i*h with round(2 pi i) nodes."""
    m = max(2, round(radius / spacing))
    h = radius / m
    verts = [(0.0, 0.0)]
    rings = [[0]]
    for i in range(1, m + 1):
        n = max(6, round(2 * math.pi * i))
        phase = 0.5 * (i % 2) * 2 * math.pi / n
        ring = []
        for k in range(n):
            t = phase + 2 * math.pi * k / n
            ring.append(len(verts))
            verts.append((i * h * math.cos(t), i * h * math.sin(t)))
        rings.append(ring)
    faces = []
    for a, b in zip(rings[:-1], rings[1:]):
        if len(a) == 1:
            for k in range(len(b)):
                faces.append((a[0], b[k], b[(k + 1) % len(b)]))
            continue
        # Merge walk around both rings by angle.
        def ang(v):
            x, y = verts[v]
            return math.atan2(y, x) % (2 * math.pi)
        ia = sorted(range(len(a)), key=lambda k: ang(a[k]))
        ib = sorted(range(len(b)), key=lambda k: ang(b[k]))
        A = [a[k] for k in ia]
        B = [b[k] for k in ib]
        i = j = 0
        while i < len(A) or j < len(B):
            ta = ang(A[(i + 1) % len(A)]) + (2 * math.pi if i + 1 >= len(A) else 0)
            tb = ang(B[(j + 1) % len(B)]) + (2 * math.pi if j + 1 >= len(B) else 0)
            if j >= len(B) or (i < len(A) and ta < tb):
                faces.append((A[i % len(A)], A[(i + 1) % len(A)], B[j % len(B)]))
                i += 1
            else:
                faces.append((A[i % len(A)], B[(j + 1) % len(B)], B[j % len(B)]))
                j += 1
    return verts, faces, h


def apply_preset(settings, name):
    """Blender's own preset file (presets/cloth/NAME.py), line by line: each is
    `bpy.context.cloth.settings.FIELD = VALUE`."""
    for folder in bpy.utils.preset_paths("cloth"):
        for f in os.listdir(folder):
            if os.path.splitext(f)[0].lower() == name.lower():
                path = os.path.join(folder, f)
                with open(path) as fh:
                    for line in fh:
                        line = line.strip()
                        prefix = "bpy.context.cloth.settings."
                        if line.startswith(prefix) and "=" in line:
                            field, value = (t.strip() for t in line[len(prefix):].split("=", 1))
                            setattr(settings, field, float(value) if "." in value or "e" in value else int(value))
                return path
    raise SystemExit("drape_record.py: --preset %r: no such Blender cloth preset (folders: %s)" % (name, bpy.utils.preset_paths("cloth")))


def physical_cloth(s, mass_per_vertex, h, bend_Nm, stretch_N_m, shear_N_m, vertex_mass, compression_ratio=1.0, bending_factor=1.0):
    """docs/library.md's mapping of a physical fabric onto Blender's cloth settings
    `s` (its cloth forces scale gravity by 0.001, springs are per edge length), for
    a mesh of spacing h [m] whose vertices carry `mass_per_vertex` [kg]; every
    value times one factor so the vertex mass is `vertex_mass` (statics depend on
    the ratios only). Returns what was set. Shared with cantilever.py."""
    f = vertex_mass / mass_per_vertex
    s.mass = vertex_mass
    s.tension_stiffness = f * 0.001 * stretch_N_m * h
    s.compression_stiffness = compression_ratio * s.tension_stiffness
    s.shear_stiffness = f * 0.001 * shear_N_m * h
    s.bending_stiffness = bending_factor * f * 0.01 * bend_Nm / (h * h)
    return {"vertex_mass_kg": s.mass, "tension": s.tension_stiffness, "compression": s.compression_stiffness,
            "shear": s.shear_stiffness, "bending": s.bending_stiffness, "factor": f}


def physical_settings(s, a, h, nverts):
    """physical_cloth for the specimen: its mass spread evenly over its vertices."""
    area = math.pi * (a.sample_mm / 2000.0) ** 2
    a.blender_settings = physical_cloth(s, a.density_gm2 * 1e-3 * area / nverts, h, a.bend_Nm, a.stretch_N_m, a.shear_N_m, a.vertex_mass,
                                        a.compression_ratio, a.bending_factor)


def build_scene(a):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.unit_settings.system = "METRIC"
    scene.gravity = (0.0, 0.0, -9.81)
    # The pedestal: a cylinder, top at z = 0.
    r2 = a.disc_mm / 2000.0
    bpy.ops.mesh.primitive_cylinder_add(vertices=256, radius=r2, depth=0.12, location=(0, 0, -0.06))
    ped = bpy.context.active_object
    ped.name = "pedestal"
    ped.modifiers.new("Collision", "COLLISION")
    ped.collision.thickness_outer = a.collision_mm / 1000.0
    ped.collision.cloth_friction = a.friction
    ped.collision.damping = 0.5
    # The specimen.
    verts, faces, h = rings_mesh(a.sample_mm / 2000.0, a.spacing_mm / 1000.0)
    rnd = random.Random(a.seed)
    z0 = 0.003
    co = [(x + a.offset[0] / 1000.0, y + a.offset[1] / 1000.0, z0 + rnd.gauss(0.0, 0.0002)) for x, y in verts]
    me = bpy.data.meshes.new("specimen")
    me.from_pydata(co, [], faces)
    me.update()
    cloth = bpy.data.objects.new("specimen", me)
    scene.collection.objects.link(cloth)
    mod = cloth.modifiers.new("Cloth", "CLOTH")
    s = mod.settings
    if a.pin_centre_mm > 0:
        vg = cloth.vertex_groups.new(name="pin")
        vg.add([i for i, (x, y) in enumerate(verts) if math.hypot(x, y) <= a.pin_centre_mm / 1000.0], 1.0, "REPLACE")
        s.vertex_group_mass = "pin"
    s.quality = a.quality
    s.mass = a.vertex_mass
    s.air_damping = a.air_damping
    s.bending_model = a.bending_model
    s.tension_stiffness = a.tension
    s.compression_stiffness = a.compression
    s.shear_stiffness = a.shear
    s.bending_stiffness = a.bending
    s.tension_damping = 25.0
    s.compression_damping = 25.0
    s.shear_damping = 25.0
    s.bending_damping = a.bending_damping
    if a.preset:
        apply_preset(s, a.preset)
    if a.bend_Nm > 0:
        physical_settings(s, a, h, len(verts))
    c = mod.collision_settings
    c.use_collision = True
    c.distance_min = a.collision_mm / 1000.0
    c.collision_quality = 2
    c.use_self_collision = False
    mod.point_cache.frame_start = 1
    mod.point_cache.frame_end = a.max_frames
    scene.frame_start = 1
    scene.frame_end = a.max_frames
    return scene, cloth, faces, h


def evaluated_positions(scene, cloth):
    dg = bpy.context.evaluated_depsgraph_get()
    ev = cloth.evaluated_get(dg)
    return [tuple(v.co) for v in ev.data.vertices]


def run(scene, cloth, edges, a):
    """Steps frames until the vertical projection's D changes by less than
    --rest-dc points over 100 frames (Blender's collision response keeps a few
    vertices at the rim chattering by a fraction of a millimetre per frame, so
    the vertices' motion never falls to zero)."""
    history = []
    p = None
    for f in range(1, a.max_frames + 1):
        scene.frame_set(f)
        if f % 25 and f != a.max_frames:
            continue
        p = evaluated_positions(scene, cloth)
        dc = drape_coefficient([(1000 * x, 1000 * y, 1000 * z) for x, y, z in p], edges, a, 1.0)
        history.append((f, dc))
        print("drape_record: frame %d, D %.2f %%" % (f, dc), flush=True)
        old = [d for g, d in history if g <= f - 100]
        if f >= 200 and old and abs(dc - old[-1]) < a.rest_dc:
            return p, f, history, True
    return p, a.max_frames, history, False


def outline(pos, edges, step_deg):
    return ray_envelope([((pos[u][0], pos[u][1]), (pos[v][0], pos[v][1])) for u, v in edges], step_deg)


def node_count(env, prominence_mm=3.0):
    """Folds of the projection's outline r(theta): maxima of r smoothed over
    +-5 degrees that rise at least `prominence_mm` above the minima either side."""
    n = len(env)
    w = max(1, round(n * 5 / 360))
    r = [x if x == x else 0.0 for x in env]
    sm = [sum(r[(i + k) % n] for k in range(-w, w + 1)) / (2 * w + 1) for i in range(n)]
    i0 = min(range(n), key=lambda i: sm[i])  # start at the deepest trough
    seq = sm[i0:] + sm[:i0] + [sm[i0]]
    count, low, high, rising = 0, seq[0], seq[0], True
    for x in seq[1:]:
        if rising:
            high = max(high, x)
            if high - x >= prominence_mm and high - low >= prominence_mm:
                count += 1
                rising, low = False, x
        else:
            low = min(low, x)
            if x - low >= prominence_mm:
                rising, high = True, x
    return count


def drape_coefficient(pos, edges, a, step_deg):
    env = outline(pos, edges, step_deg)
    area = sum(0.5 * r * r * math.radians(step_deg) for r in env if r == r)
    r1, r2 = a.sample_mm / 2, a.disc_mm / 2
    return 100.0 * (area - math.pi * r2 * r2) / (math.pi * r1 * r1 - math.pi * r2 * r2)


def ray_envelope(segments, step_deg):
    """Outermost radius on each ray (every step_deg) from the z axis over 2D segments."""
    n = round(360 / step_deg)
    best = [float("nan")] * n
    for (x1, y1), (x2, y2) in segments:
        t1 = math.degrees(math.atan2(y1, x1))
        t2 = math.degrees(math.atan2(y2, x2))
        d = (t2 - t1 + 180.0) % 360.0 - 180.0
        lo, hi = (t1, t1 + d) if d >= 0 else (t1 + d, t1)
        k0 = math.ceil(lo / step_deg)
        k1 = math.floor(hi / step_deg)
        for k in range(k0, k1 + 1):
            t = math.radians(k * step_deg)
            c, s = math.cos(t), math.sin(t)
            # Ray r*(c, s) against the segment p1 + u (p2 - p1).
            ex, ey = x2 - x1, y2 - y1
            den = c * ey - s * ex
            if abs(den) < 1e-15:
                r = max(math.hypot(x1, y1), math.hypot(x2, y2))
            else:
                r = (x1 * ey - y1 * ex) / den
            if r <= 0:
                continue
            i = k % n
            if not (best[i] >= r):
                best[i] = r
    return best


def cut(pos, faces, z):
    segs = []
    for f in faces:
        pts = [pos[v] for v in f]
        out = []
        for i in range(3):
            p, q = pts[i], pts[(i + 1) % 3]
            if (p[2] - z) * (q[2] - z) < 0:
                u = (z - p[2]) / (q[2] - p[2])
                out.append((p[0] + u * (q[0] - p[0]), p[1] + u * (q[1] - p[1])))
        if len(out) == 2:
            segs.append((out[0], out[1]))
    return segs


def main():
    a = parse_args()
    t0 = time.time()
    os.makedirs(a.out, exist_ok=True)
    scene, cloth, faces, h = build_scene(a)
    edges = set()
    for t in faces:
        for i in range(3):
            u, v = t[i], t[(i + 1) % 3]
            edges.add((min(u, v), max(u, v)))
    pos, frames, history, at_rest = run(scene, cloth, edges, a)
    wall = time.time() - t0
    # Millimetres; the cloth's height over the pedestal centre is its collision
    # distance, not a drape: the pedestal top is moved to the cloth's underside there.
    pos = [(1000 * x, 1000 * y, 1000 * z) for x, y, z in pos]
    r2 = a.disc_mm / 2
    on_top = [p[2] for p in pos if math.hypot(p[0], p[1]) < 0.5 * r2]
    lift = sorted(on_top)[len(on_top) // 2] if on_top else 0.0
    pos = [(x, y, z - lift) for x, y, z in pos]
    with open(os.path.join(a.out, "rest.obj"), "w") as f:
        f.write("# Blender cloth rest state (mm), scripts/blender/drape_record.py\n")
        for p in pos:
            f.write("v %.4f %.4f %.4f\n" % p)
        for t in faces:
            f.write("f %d %d %d\n" % (t[0] + 1, t[1] + 1, t[2] + 1))
    # Contours every 5 mm where the cut closes around the pedestal.
    rows, depths = [], []
    d = 5
    zmin = min(p[2] for p in pos)
    while -d > zmin:
        env = ray_envelope(cut(pos, faces, -d), 1.0)
        if all(r == r and r > r2 for r in env):
            depths.append(d)
            for k, r in enumerate(env):
                t = math.radians(k)
                rows.append("%d,%d,%.2f,%.2f" % (d, k, r * math.cos(t), r * math.sin(t)))
        d += 5
    with open(os.path.join(a.out, "contours.csv"), "w") as f:
        f.write("depth_mm,theta_deg,x_mm,y_mm\n" + "\n".join(rows) + ("\n" if rows else ""))
    # The vertical projection's outline (every mesh edge projected), its area, D.
    dc = drape_coefficient(pos, edges, a, 0.25)
    nodes = node_count(outline(pos, edges, 1.0))
    rid = a.id or os.path.basename(os.path.normpath(a.out))
    meta = {
        "specimen_id": rid,
        "configuration": {"specimen_diameter_D1_mm": a.sample_mm, "support_disc_diameter_D2_mm": a.disc_mm,
                          "pedestal_height_mm": 120.0, "specimen_centred": a.offset == [0.0, 0.0]},
        "fabric": {"areal_density_g_m2": a.density_gm2, "thickness_mm": a.thickness_mm,
                   "warp_direction": "+x", "weft_direction": "+y", "colour": "grey"},
        "gravity_m_s2": 9.81,
        "units": {"length": "mm", "angles": "deg"},
        "contours": {"file": "contours.csv", "depths_mm": depths, "theta_step_deg": 1.0, "repeatability_sigma_mm": 0.3},
        "lab_drape_coefficient_percent": round(dc, 2),
    }
    with open(os.path.join(a.out, "meta.json"), "w") as f:
        json.dump(meta, f, indent=2)
        f.write("\n")
    info = {"blender": bpy.app.version_string, "settings": getattr(a, "blender_settings", None), "args": {k: v for k, v in vars(a).items() if k != "offset"},
            "vertices": len(pos), "triangles": len(faces), "spacing_mm": 1000 * h,
            "frames": frames, "at_rest": at_rest, "dc_history": history, "wall_s": round(wall, 1),
            "drape_coefficient_percent": dc, "node_count": nodes,
            "specimen_centre_at_rest_mm": [round(pos[0][0], 2), round(pos[0][1], 2)], "depths_mm": depths, "lift_mm": lift}
    with open(os.path.join(a.out, "blender.json"), "w") as f:
        json.dump(info, f, indent=2)
        f.write("\n")
    print("drape_record: %s D %.2f %%, %d folds, %d frames%s, %.1f s" % (rid, dc, nodes, frames, "" if at_rest else " (NOT at rest)", wall))


if __name__ == "__main__":  # (cantilever.py imports physical_cloth)
    main()
