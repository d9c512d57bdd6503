#!/usr/bin/env bash
# The lab's top photos measured as plain photos: each record's top.jpg copied out
# of its record (so nothing of meta.json is read), the floor chessboard at -120 mm
# its only scale, no lens given; D under every perspective model against the lab's.
# The table behind docs/capture.md "Perspective: every model, side by side".
#
#   scripts/lab-photos.sh [DRAPE_BINARY] [OUT_DIR]   (defaults: build/bin/drape, out/lab-photos)
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
drape="${1:-$here/build/bin/drape}"
out="${2:-$here/out/lab-photos}"
lab="$here/../shared/data/drape-lab"
[ -x "$drape" ] || { echo "no drape binary at $drape" >&2; exit 2; }
[ -d "$lab" ] || { echo "no lab records at $lab" >&2; exit 2; }
mkdir -p "$out"
printf '%-14s %6s  %-22s %-8s %-15s %s\n' record lab_D hem_D "z(hem)" "disc-plane_D" "disc centre: off / bound [mm] (the lab's camera)"
for rec in "$lab"/set-*/DL-*; do
  [ -f "$rec/meta.json" ] && [ -f "$rec/top.jpg" ] || continue
  n=$(basename "$rec")
  read -r d1 d2 < <(python3 -c "import json,sys; c=json.load(open(sys.argv[1]))['configuration']; print(c['specimen_diameter_D1_mm'], c['support_disc_diameter_D2_mm'])" "$rec/meta.json")
  cp "$rec/top.jpg" "$out/$n.jpg"
  OMP_NUM_THREADS=1 "$drape" measure --top "$out/$n.jpg" --disc "${d2}mm" --specimen "${d1}mm" --scale chessboard --board 6x11 \
    --square 25mm --reference-height -120mm --json --overlay "$out/$n-overlay.png" > "$out/$n.json" 2> "$out/$n.err" || true
  python3 - "$out/$n.json" "$rec/meta.json" "$n" <<'PY'
import json, sys
out, meta, name = sys.argv[1:4]
lab = json.load(open(meta))["lab_drape_coefficient_percent"]
try:
    j = json.load(open(out))
except ValueError:
    print(f"{name:14s} {lab:6.1f}  no output"); sys.exit()
if j.get("refused"):
    print(f"{name:14s} {lab:6.1f}  refused: {j['refused'].get('check')}"); sys.exit()
pm = j["perspective_models"]
h, d = pm["hem"], pm["disc-plane"]
hd, hu = h["drape_coefficient_percent"], h["uncertainty_percent"]
# The disc centre against the lab's calibrated top camera (never read by the
# measurement): the pedestal's axis projected, the offset at the disc top.
cam = json.load(open(meta))["cameras"]["top"]
t = cam["t_world_to_cam_mm"]
u0, v0 = cam["fx"] * t[0] / t[2] + cam["cx"], cam["fy"] * t[1] / t[2] + cam["cy"]
sc = j["scale"]
cu, cv = sc["disc_centre_px"]
off = ((cu - u0) ** 2 + (cv - v0) ** 2) ** 0.5 * t[2] / cam["fx"]
bound = sc.get("disc_centre_bound_m")
centre = f"rim {off:4.1f}" if not sc["disc_centre_source"].startswith("centroid") else \
    f"centroid {off:4.1f} / " + (f"{bound * 1e3:.0f}" if bound is not None else "none")
print(f"{name:14s} {lab:6.1f}  {hd:5.1f} +- {hu:4.1f} ({hd - lab:+5.1f})  {(hd - lab) / hu:+5.2f}   {d['drape_coefficient_percent']:5.1f} ({d['drape_coefficient_percent'] - lab:+5.1f})  {centre}")
PY
done
