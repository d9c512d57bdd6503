#!/usr/bin/env bash
# Reproduces the edge-contact before/after of docs/decisions/0001-edge-contact.md
# (issue 7; the fits of 2026-11-22 at grid 25).
#
#   bash scripts/model-discrepancy.sh [OUT_DIR] [PART ...]
#
# PART: fits (baseline before/after on all of set-a, ~40 min on 2 cores),
#       heldout (fit on D + nodes, predict side view and contours; 3 records, ~15 min),
#       signatures (hypotheses at the fitted presets, ~3 min), stiffening (~10 min),
#       summary (tables and plots of the fits: drape fit-summary).
# Default: all parts. Needs build/bin/drape (bash scripts/test.sh builds it).
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
drape="${DRAPE_BIN:-$here/build/bin/drape}"
data="${DRAPE_DATA:-$here/../shared/data/drape-lab/set-a}"
out="${1:-$here/build/model-discrepancy}"
shift || true
parts=("$@")
[ ${#parts[@]} -eq 0 ] && parts=(fits heldout signatures stiffening summary)
mkdir -p "$out"
export OMP_NUM_THREADS=1
ids=(DL-A01 DL-A02 DL-A03 DL-A04 DL-A05 DL-A06 DL-A07 DL-A08 DL-A09 DL-A10)
want() { local p; for p in "${parts[@]}"; do [ "$p" = "$1" ] && return 0; done; return 1; }

# The fits of this script were made with the plain bending stencils (the
# default before 2026-11-30, docs/decisions/0011-bending-correction.md): --plain-bending.
if want fits; then
  # Before: the seed's vertex-only contact. After: contact on mesh edges too.
  for id in "${ids[@]}"; do
    "$drape" fit "$data/$id" --grid 25 --plain-bending --vertex-contact-only --out "$out/before-$id.json" --report "$out/before-$id" --json > "$out/before-$id.summary.json"
    "$drape" fit "$data/$id" --grid 25 --plain-bending --out "$out/after-$id.json" --report "$out/after-$id" --json > "$out/after-$id.summary.json"
  done
fi

if want heldout; then
  # Fit on the top photo and the drapemeter (D, nodes); the side view (hem) and
  # the laser contours are held out and predicted.
  for id in DL-A04 DL-A07 DL-A08; do
    "$drape" fit "$data/$id" --grid 25 --plain-bending --channels dc,nodes --vertex-contact-only --out "$out/heldout-before-$id.json" --json > "$out/heldout-before-$id.summary.json"
    "$drape" fit "$data/$id" --grid 25 --plain-bending --channels dc,nodes --out "$out/heldout-after-$id.json" --json > "$out/heldout-after-$id.summary.json"
    # Errors in physical units (the fits' sigmas differ), 4 seeds each, as each was fitted.
    "$drape" compare "$data/$id" --fabric "$out/heldout-before-$id.json" --vertex-contact-only --seeds 4 --quiet > "$out/heldout-before-$id.compare.txt"
    "$drape" compare "$data/$id" --fabric "$out/heldout-after-$id.json" --seeds 4 --quiet > "$out/heldout-after-$id.compare.txt"
  done
fi

if want signatures; then
  # Each hypothesis switched on at the preset fitted to the record, one at a time.
  for id in DL-A04 DL-A08; do
    f="$out/after-$id.json"
    [ -f "$f" ] || { echo "run the 'fits' part first ($f missing)" >&2; exit 1; }
    "$drape" compare "$data/$id" --fabric "$f" --quiet > "$out/sig-$id-fitted.txt"
    "$drape" compare "$data/$id" --fabric "$f" --vertex-contact-only --quiet > "$out/sig-$id-vertex-contact.txt"
    "$drape" compare "$data/$id" --fabric "$f" --disc-grip --quiet > "$out/sig-$id-disc-grip.txt"
    python3 - "$f" "$out/stiff-$id.json" <<'EOF'
import json, sys
d = json.load(open(sys.argv[1])); d["parameters"]["bend_stiffening_radius_m"] = 0.01
json.dump(d, open(sys.argv[2], "w"))
EOF
    "$drape" compare "$data/$id" --fabric "$out/stiff-$id.json" --quiet > "$out/sig-$id-stiffening-10mm.txt"
    "$drape" compare "$data/$id" --fabric "$f" --grid 41 --quiet > "$out/sig-$id-grid41.txt"
  done
fi

if want signatures; then
  # How deep the baseline's mesh edges cut the pedestal rim, with and without edge contact.
  for g in 25 49; do
    for m in --vertex-contact-only ""; do
      rm -rf "$out/rim-$g$m"
      "$drape" simulate --fabric "$out/before-DL-A04.json" --grid $g $m --out "$out/rim-$g$m" --quiet > /dev/null
      python3 "$here/scripts/rim_cut.py" "$out/rim-$g$m/rest.obj"
    done
  done
fi

if want stiffening; then
  # The stiffening-bending model on the records where the baseline misses most.
  for id in DL-A05 DL-A10; do
    for m in stiffening softening; do
      "$drape" fit "$data/$id" --grid 25 --plain-bending --model $m --out "$out/$m-$id.json" --report "$out/$m-$id" --json > "$out/$m-$id.summary.json"
    done
  done
  "$drape" fit "$data/DL-A04" --grid 25 --plain-bending --model softening --out "$out/softening-DL-A04.json" --json > "$out/softening-DL-A04.summary.json"
  for m in stiffening softening; do # started from the baseline's optimum (the nested case radius = 0)
    "$drape" fit "$data/DL-A05" --grid 25 --plain-bending --model $m --start "$out/after-DL-A05.json" --out "$out/nested-$m-DL-A05.json" --json > "$out/nested-$m-DL-A05.summary.json"
  done
fi
if want summary; then
  args=()
  for id in "${ids[@]}"; do args+=("before=$out/before-$id" "after=$out/after-$id"); done
  "$drape" fit-summary --out "$out/summary" "${args[@]}"
fi
echo "results in $out"
