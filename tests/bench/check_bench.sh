#!/usr/bin/env bash
# lightvol check end to end on the static spot volume of the 1024² synthetic map (2,097,150
# triangles: the 2,093,058 of the grid plus the 4,092 of the fan), written as binary PLY: median
# wall time and peak memory over RUNS runs, with --light (the linear-time proof) and without it
# (CGAL: self-intersections + bounds a volume). check_bench (Google Benchmark) times the library
# calls alone.
# Usage: tests/bench/check_bench.sh BUILD_DIR [RUNS]   (BUILD_DIR configured with -DLIGHTVOL_BUILD_BENCH=ON)
set -euo pipefail
build=$(realpath "${1:?usage: check_bench.sh BUILD_DIR [RUNS]}")
runs=${2:-5}
source "$(dirname "$0")/bench_common.sh"
"$build/tests/bench/make_depth" 1024 1024 "$work/d.exr"
"$build/lightvol" build "$work/d.exr" --light "$work/spot.json" --out "$work/v.ply" --quiet
printf '| command | wall (median of %d) | peak memory |\n|---|---|---|\n' "$runs"
run() {
  local label=$1; shift
  : > "$work/wall"; : > "$work/rss"
  for ((i = 0; i < runs; i++)); do
    /usr/bin/time -f '%e %M' -o "$work/t" "$build/lightvol" check "$work/v.ply" "$@" --quiet
    read -r wall rss < "$work/t"
    echo "$wall" >> "$work/wall"; echo "$rss" >> "$work/rss"
  done
  printf '| `%s` | %.2f s | %.0f MiB |\n' "$label" "$(median < "$work/wall")" "$(echo "$(median < "$work/rss") / 1024" | bc -l)"
}
run "lightvol check v.ply --light spot.json" --light "$work/spot.json"
run "lightvol check v.ply" 
