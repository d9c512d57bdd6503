#!/usr/bin/env bash
# Sets up (installs what is missing from Debian), builds, and runs the test
# suite: the `unit` label by default; `scripts/test.sh all` runs the slow tests too.
set -euo pipefail
cd "$(dirname "$0")/.."
bash cmake/setup-deps.sh
WERROR=OFF; [ "${CI:-}" = "true" ] && WERROR=ON
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DDRAPE_WERROR=$WERROR >/dev/null
cmake --build build -j"$(nproc)"
# Each test is one process; CHOLMOD's OpenMP threads only pay on large solves.
export OMP_NUM_THREADS=${OMP_NUM_THREADS:-1}
if [ "${1:-}" = "all" ]; then
  ctest --test-dir build --output-on-failure -j2
else
  ctest --test-dir build --output-on-failure -j2 -L unit
fi
