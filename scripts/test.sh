#!/usr/bin/env bash
# Sets up (installs what is missing from Debian), builds, and runs the test
# suite: the `unit` label by default; `scripts/test.sh all` runs the slow tests too.
set -euo pipefail
cd "$(dirname "$0")/.."
bash cmake/setup-deps.sh
# Build jobs: the processors this process may use. GNU nproc also honours
# OMP_NUM_THREADS, which the tests below set to 1 (the sanitizer build ran on one
# core in CI for that reason), so it is asked without it, once.
jobs=$(env -u OMP_NUM_THREADS -u OMP_THREAD_LIMIT nproc)
WERROR=OFF; [ "${CI:-}" = "true" ] && WERROR=ON
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_UNITY_BUILD=ON -DDRAPE_WERROR=$WERROR >/dev/null
# The slow tests and the benchmarks are outside `all` (CI runs the unit label
# only); `all` builds them too, so they never rot unbuilt for long.
if [ "${1:-}" = "all" ]; then
  cmake --build build -j"$jobs" --target all slow_tests benchmarks
else
  cmake --build build -j"$jobs"
fi
# Each test is one process; CHOLMOD's OpenMP threads only pay on large solves.
export OMP_NUM_THREADS=${OMP_NUM_THREADS:-1}
status=0
if [ "${1:-}" = "all" ]; then
  ctest --test-dir build --output-on-failure -j2 || status=$?
else
  ctest --test-dir build --output-on-failure -j2 -L unit || status=$?
fi
# The unit tests again under the address and undefined-behaviour sanitizers: by
# default those of what reads outside input (records, photos, presets, meshes, the
# library, the CLI's bad inputs); `all` adds the solver's numerics (SOLVER tests).
if [ "${DRAPE_SKIP_SANITIZE:-}" != "1" ]; then
  SOLVER=OFF; [ "${1:-}" = "all" ] && SOLVER=ON
  cmake --preset sanitize -DDRAPE_SANITIZE_SOLVER=$SOLVER >/dev/null
  cmake --build --preset sanitize -j"$jobs"
  ASAN_OPTIONS=detect_leaks=0 ctest --preset sanitize -j2 || status=$?
fi
exit $status
