#!/usr/bin/env bash
# `lightvol batch` of JOBS small builds (default 1,000) against as many separate `lightvol build`
# processes run two at a time (xargs -P 2): wall time, user+sys CPU seconds and the largest
# resident set, A and B alternately RUNS times (default 3), medians, and the ratio.
# Each job is a default static spot build (with its check) to binary PLY, from one of four
# distinct maps of 256×256, 256×255, 255×256 and 255×255 texels (tests/bench/make_depth; one map
# per size, so the sizes differ by a texel), each with a light of its aspect.
# Usage: tests/bench/batch_bench.sh BUILD_DIR [RUNS] [JOBS]
#   (BUILD_DIR configured with -DLIGHTVOL_BUILD_BENCH=ON)
set -euo pipefail
build=$(realpath "${1:?usage: batch_bench.sh BUILD_DIR [RUNS] [JOBS]}")
runs=${2:-3}
jobs=${3:-1000}
work=$(mktemp -d)
trap '[ -n "${KEEP:-}" ] || rm -rf "$work"' EXIT

sizes=("256 256" "256 255" "255 256" "255 255")
for m in 0 1 2 3; do
  read -r w h <<< "${sizes[$m]}"
  "$build/tests/bench/make_depth" "$w" "$h" "$work/map$m.exr"
  aspect=$(awk -v w="$w" -v h="$h" 'BEGIN { printf "%.17g", w / h }')
  cat > "$work/light$m.json" <<JSON
{"type": "spot", "position": [0, 10, 0], "direction": [0, -1, 0], "up": [0, 0, -1],
 "fov_y_deg": 60, "aspect": $aspect, "near": 1, "far": 20}
JSON
done
mkdir "$work/out"
for ((i = 0; i < jobs; i++)); do
  m=$((i % 4))
  printf '{"id": "%d", "inputs": ["map%d.exr"], "light": "light%d.json", "out": "out/v%d.ply"}\n' \
    "$i" "$m" "$m" "$i" >> "$work/jobs.jsonl"
  printf '%s\0%s\0%s\0' "$work/map$m.exr" "$work/light$m.json" "$work/out/v$i.ply" >> "$work/args"
done

# One measured run: "wall user+sys maxrss_kib", from /usr/bin/time -v.
measure() {
  rm -rf "$work/out" && mkdir "$work/out"
  /usr/bin/time -v -o "$work/time" "$@" > /dev/null
  local made
  made=$(find "$work/out" -name 'v*.ply' | wc -l)
  [ "$made" -eq "$jobs" ] || { echo "batch_bench: $made of $jobs volumes written" >&2; exit 1; }
  python3 - "$work/time" <<'PY'
import sys
t = {}
for line in open(sys.argv[1]):
    k, _, v = line.strip().rpartition(": ")
    t[k] = v
wall = t["Elapsed (wall clock) time (h:mm:ss or m:ss)"].split(":")
secs = sum(float(x) * 60 ** i for i, x in enumerate(reversed(wall)))
cpu = float(t["User time (seconds)"]) + float(t["System time (seconds)"])
print(f"{secs:.2f} {cpu:.2f} {int(t['Maximum resident set size (kbytes)'])}")
PY
}
median() { sort -g | awk '{a[NR]=$1} END {print (NR%2 ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2)}'; }

: > "$work/a"; : > "$work/b"
for ((r = 0; r < runs; r++)); do
  measure "$build/lightvol" batch "$work/jobs.jsonl" --quiet >> "$work/a"
  measure xargs -0 -n 3 -P 2 sh -c '"$0" build "$1" --light "$2" --out "$3" --quiet' \
    "$build/lightvol" < "$work/args" >> "$work/b"
done

col() { awk -v c="$2" '{print $c}' "$1" | median; }
printf '| %d jobs of 256² (median of %d) | wall | user+sys | max RSS |\n|---|---|---|---|\n' "$jobs" "$runs"
printf '| `lightvol batch` (one process, --jobs = %d cores) | %.2f s | %.2f s | %.0f MiB |\n' \
  "$(nproc)" "$(col "$work/a" 1)" "$(col "$work/a" 2)" "$(echo "$(col "$work/a" 3) / 1024" | bc -l)"
printf '| %d `lightvol build` processes (xargs -P 2) | %.2f s | %.2f s | %.0f MiB |\n' \
  "$jobs" "$(col "$work/b" 1)" "$(col "$work/b" 2)" "$(echo "$(col "$work/b" 3) / 1024" | bc -l)"
printf '| processes / batch | %.2f× | %.2f× | |\n' \
  "$(echo "$(col "$work/b" 1) / $(col "$work/a" 1)" | bc -l)" \
  "$(echo "$(col "$work/b" 2) / $(col "$work/a" 2)" | bc -l)"
