#!/usr/bin/env bash
# Runs one libFuzzer target for a given time (not part of the default test run):
#
#   scripts/fuzz.sh TARGET SECONDS [extra libFuzzer flags]
#   scripts/fuzz.sh list
#
# TARGET: names, meta, contours, preset, library, mesh, image (fuzz/fuzz_TARGET.cpp).
# Configures build-fuzz/ with clang (DRAPE_FUZZ=ON: every library instrumented,
# address + undefined sanitizers), builds the target, seeds its corpus from the
# project's own files the first time (examples/, data/library, docs/fit-report, the legacy preset in tests/library/data,
# ../shared/data/drape-lab, assimp's small test models), and runs it at low
# priority in one process. The corpus grows in build-fuzz/corpus/TARGET;
# findings (crash-*, leak-*, timeout-*, oom-*) land in build-fuzz/findings/TARGET/
# and the run's log, with libFuzzer's final statistics, in build-fuzz/logs/.
# A finding becomes a regression test: copy it to fuzz/regressions/TARGET/
# (tests/fuzz replays every file there through the same code).
set -euo pipefail
cd "$(dirname "$0")/.."
root="$PWD"
targets="names meta contours preset library mesh image"
if [ "${1:-}" = "list" ] || [ $# -lt 2 ]; then
  echo "usage: scripts/fuzz.sh TARGET SECONDS [libFuzzer flags]   (TARGET: $targets)"
  [ "${1:-}" = "list" ] && exit 0 || exit 2
fi
target="$1"; seconds="$2"; shift 2
case " $targets " in *" $target "*) ;; *) echo "unknown target '$target' (one of: $targets)" >&2; exit 2 ;; esac
build="${DRAPE_FUZZ_BUILD:-$root/build-fuzz}"
jobs="${JOBS:-1}"

if [ ! -f "$build/CMakeCache.txt" ]; then
  CC=clang CXX=clang++ nice -n 10 cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DDRAPE_FUZZ=ON \
    -DDRAPE_BUILD_GUI=OFF -DDRAPE_BUILD_TESTS=OFF -DDRAPE_BUILD_BENCH=OFF >/dev/null
fi
nice -n 10 cmake --build "$build" --target "fuzz_$target" -j"$jobs"

corpus="$build/corpus/$target"
seeds="$build/seeds/$target"
findings="$build/findings/$target"
mkdir -p "$corpus" "$seeds" "$findings" "$build/logs"
shared="$root/../shared/data/drape-lab"
models=/usr/share/assimp/models

# One seed file: the bytes of FILE, after an optional prefix given as printf escapes.
seed() {
  local prefix="$1" file="$2" name
  name="$(echo "$file" | md5sum | cut -c1-12)-$(basename "$file")"
  { printf "$prefix"; cat "$file"; } >"$seeds/$name"
}

if [ -z "$(ls -A "$seeds")" ]; then
  case "$target" in
  names)
    for f in "$root"/data/library/*.json; do jq -r '.name, .composition, .notes' "$f" >"$seeds/$(basename "$f").txt"; done
    printf 'Cafe\xcc\x81 silk\xc2\xa0' >"$seeds/nfd-nbsp.txt"
    printf '\xea\xb0\x80\xe1\x84\x80\xe1\x85\xa1\xe1\x86\xa8' >"$seeds/hangul.txt"
    ;;
  meta)
    seed "" "$root/examples/DL-A04/meta.json"
    for f in "$shared"/set-a/*/meta.json; do [ -f "$f" ] && seed "" "$f"; done
    ;;
  contours)
    # The first byte picks the declared ray step (fuzz_contours.cpp): \001 = 1 degree.
    seed '\001' "$root/examples/DL-A04/contours.csv"
    for f in "$shared"/set-a/*/contours.csv; do [ -f "$f" ] && seed '\000' "$f"; done
    head -40 "$root/examples/DL-A04/contours.csv" >"$build/contours-head.csv" && seed '\000' "$build/contours-head.csv"
    ;;
  preset)
    for f in "$root"/data/library/*.json "$root"/docs/fit-report/*.fabric.json "$root"/tests/library/data/*.fabric.json; do seed "" "$f"; done
    "$root/build/bin/drape" export-seed --fabric "$root/data/library/silk.json" --out "$seeds/silk-seed19.json" >/dev/null 2>&1 ||
      printf '{"format":"seed-19","w":30,"h":30,"u":30,"v":30,"x0":-15,"y0":15,"z0":0,"ClothOverMass":0.5,"SstKu":150,"SstDu":7,"SstKv":150,"SstDv":7,"SshK":40,"SshD":6,"SflKu":24,"SflDu":8,"SflKv":24,"SflDv":8}' >"$seeds/seed-table1.json"
    ;;
  library)
    for f in "$root"/data/library/*.json; do seed "" "$f"; done
    lib="$build/seed-library.sqlite"
    rm -f "$lib"
    if [ -x "$root/build/bin/drape" ]; then
      "$root/build/bin/drape" library import "$root/data/library" --library "$lib" >/dev/null
      "$root/build/bin/drape" library export --all --library "$lib" --out "$seeds/starter-library.json" >/dev/null
      rm -f "$lib" "$lib"-*
    fi
    jq -s '.' "$root"/data/library/*.json >"$seeds/array.json"
    ;;
  mesh)
    # The first byte picks the extension (fuzz_mesh.cpp): obj ply stl off dae gltf glb fbx 3ds x ase ac.
    i=0
    for ext in obj ply stl off dae gltf glb fbx 3ds x ase ac; do
      find "$models" -iname "*.$ext" -size -24k 2>/dev/null | head -6 | while read -r f; do seed "\\$(printf '%03o' $i)" "$f"; done
      i=$((i + 1))
    done
    ;;
  image)
    # The first four bytes are the declared width and height (16-bit little-endian each).
    for f in "$root"/examples/DL-A04/*.jpg; do seed '\x80\x04\x68\x03' "$f"; done # 1152 x 872
    # Small images decode 100 times faster: the project's photos with their frame
    # header patched to 64 x 48 (libjpeg then decodes the first blocks only), and
    # a 64 x 48 PNG and BMP written here.
    python3 - "$root/examples/DL-A04" "$seeds" <<'PY'
import os, struct, sys, zlib
src, out = sys.argv[1:3]
size = struct.pack("<HH", 64, 48)
for name in ("top.jpg", "side.jpg", "iso.jpg"):
    b = bytearray(open(os.path.join(src, name), "rb").read())
    i = 2
    while i + 9 < len(b) and b[i] == 0xFF:
        m = b[i + 1]
        if 0xC0 <= m <= 0xCF and m not in (0xC4, 0xC8, 0xCC):
            b[i + 5:i + 9] = struct.pack(">HH", 48, 64)
            break
        i += 2 + (b[i + 2] << 8 | b[i + 3])
    open(os.path.join(out, "small-" + name), "wb").write(size + bytes(b))
w, h = 64, 48
raw = b"".join(b"\0" + bytes(v for x in range(w) for v in ((x * 4) & 255, (y * 5) & 255, ((x ^ y) * 8) & 255)) for y in range(h))
def chunk(t, d): return struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d) & 0xFFFFFFFF)
png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)) + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b"")
open(os.path.join(out, "small.png"), "wb").write(size + png)
pix = b"".join(bytes(v for x in range(w) for v in (((x ^ y) * 8) & 255, (y * 5) & 255, (x * 4) & 255)) for y in range(h))
bmp = b"BM" + struct.pack("<IHHI", 54 + len(pix), 0, 0, 54) + struct.pack("<IiiHHIIiiII", 40, w, h, 1, 24, 0, len(pix), 2835, 2835, 0, 0) + pix
open(os.path.join(out, "small.bmp"), "wb").write(size + bmp)
PY
    ;;
  esac
fi

log="$build/logs/$target-$(date +%Y%m%d-%H%M%S).log"
case "$target" in
  image) max_len=300000 ;;
  contours) max_len=70000 ;;
  mesh | library) max_len=65536 ;;
  *) max_len=16384 ;;
esac
# assimp and OpenCV are not instrumented and leak on some bad files (assimp's
# glTF 1 reader does on its own test models): leaks are not findings there.
leaks=1
case "$target" in mesh | image) leaks=0 ;; esac
echo "fuzz_$target for $seconds s; log $log"
set +e
ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=$leaks:allocator_may_return_null=1}" UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1" \
  nice -n 10 "$build/bin/fuzz_$target" "$corpus" "$seeds" -max_total_time="$seconds" -max_len="$max_len" -timeout=20 \
  -rss_limit_mb=2560 -malloc_limit_mb=2048 -print_final_stats=1 -artifact_prefix="$findings/" "$@" >"$log" 2>&1
status=$?
grep -aE "^#[0-9]+ *(INITED|DONE)|ERROR|SUMMARY|stat::|Test unit written|invariant" "$log" || true
set -e
echo "exit $status; findings: $(ls "$findings" | wc -l) file(s) in $findings"
exit "$status"
