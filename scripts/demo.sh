#!/usr/bin/env bash
# Sets up, builds, and runs the main job on the bundled example: measures a lab
# record, fits a fabric preset to it and drapes the preset over the drapemeter.
set -euo pipefail
cd "$(dirname "$0")/.."
bash cmake/setup-deps.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_UNITY_BUILD=ON >/dev/null
cmake --build build -j"$(env -u OMP_NUM_THREADS -u OMP_THREAD_LIMIT nproc)" # nproc honours OMP_NUM_THREADS
out=${1:-out/example}
mkdir -p "$out"
record=examples/DL-A04
echo "== drape simulate: the seed paper's Table 1 over a 300/150 mm drapemeter"
build/bin/drape simulate --fabric seed-table1 --sample-diameter 300mm --disc-diameter 150mm --out "$out/seed-table1"
if build/bin/drape help measure >/dev/null 2>&1 && [ -d "$record" ]; then
  echo "== drape measure $record"
  build/bin/drape measure "$record" --overlay "$out/measure-overlay.png"
fi
if build/bin/drape help fit >/dev/null 2>&1 && [ -d "$record" ]; then
  echo "== drape fit $record (grid 41, Levenberg-Marquardt on the exact sensitivities of the rest states; about 40 s)"
  build/bin/drape fit "$record" --out "$out/fabric.json" --report "$out/report"
  echo "== drape predict at 360/180 mm"
  build/bin/drape predict --fabric "$out/fabric.json" --sample-diameter 360mm --disc-diameter 180mm
fi
echo "outputs in $out"
