#!/usr/bin/env bash
# Drape tests made by an independent simulator, Blender's cloth (Debian's
# `blender`, run headless), written as drape-lab records: the same fabric at
# several set-ups, for checking what the engine says about the change of D with
# the set-up (docs/model-discrepancy.md, "An independent simulator").
#
#   bash scripts/blender-drapes.sh OUT [--bending "50 200 800"] [--setups "300-150 240-180 360-180"] [-- ARGS]
#
# Each record is OUT/B<bending>-<D1>-<D2>/ (rest.obj, contours.csv, meta.json,
# blender.json); ARGS go to scripts/blender/drape_record.py (e.g. --vertex-mass 1
# --shear 10, --offset-mm 6,0). OUT/summary.csv has one row per record. About
# 20-40 s per record on one core; blender is installed from Debian if missing.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
[ $# -ge 1 ] || { sed -n 2,13p "$0"; exit 2; }
out=$1; shift
bendings="50 200 800"
setups="300-150 240-180 360-180"
extra=()
while [ $# -gt 0 ]; do
  case $1 in
    --bending) bendings=$2; shift 2 ;;
    --setups) setups=$2; shift 2 ;;
    --) shift; extra=("$@"); break ;;
    *) echo "blender-drapes.sh: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
if ! command -v blender >/dev/null; then
  echo "blender-drapes.sh: installing Debian's blender"
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends blender >/dev/null
fi
mkdir -p "$out"
echo "record,bending,sample_mm,disc_mm,drape_coefficient_percent,node_count,frames,at_rest,wall_s" > "$out/summary.csv"
for b in $bendings; do
  for su in $setups; do
    s=${su%-*}; d=${su#*-}
    rec="$out/B$b-$su"
    blender -b --factory-startup --python "$here/scripts/blender/drape_record.py" -- \
      --out "$rec" --sample-mm "$s" --disc-mm "$d" --bending "$b" "${extra[@]}" 2>&1 | grep -E "^drape_record: B|Error|error" || true
    [ -f "$rec/blender.json" ] || { echo "blender-drapes.sh: no record written for $rec" >&2; exit 1; }
    python3 - "$rec" "$b" "$s" "$d" >> "$out/summary.csv" <<'EOF'
import json, os, sys
rec, b, s, d = sys.argv[1:5]
j = json.load(open(os.path.join(rec, "blender.json")))
print("%s,%s,%s,%s,%.2f,%d,%d,%s,%.1f" % (os.path.basename(rec), b, s, d, j["drape_coefficient_percent"], j["node_count"],
                                         j["frames"], str(j["at_rest"]).lower(), j["wall_s"]))
EOF
  done
done
column -s, -t < "$out/summary.csv"
