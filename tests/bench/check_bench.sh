#!/usr/bin/env bash
# lightvol check end to end on the static spot volume of the synthetic map (1024²: 2,097,150
# triangles, the 2,093,058 of the grid plus the 4,092 of the fan; 4096²: 33,546,238), written as
# binary PLY: median wall time and peak memory over RUNS runs, with --light (the linear-time proof)
# and without it (self-intersections + bounds a volume: lightvol's engine, the default, and CGAL's,
# `--engine cgal`, at sizes up to CGAL_MAX), and the ratio CGAL / lightvol in the same run.
# check_bench (Google Benchmark) times the library calls alone, among them CGAL's own parallel
# test (PMP::does_self_intersect<Parallel_if_available_tag>).
# Usage: tests/bench/check_bench.sh BUILD_DIR [RUNS] [SIZES] [CGAL_MAX]
#   (BUILD_DIR configured with -DLIGHTVOL_BUILD_BENCH=ON), e.g.
#   tests/bench/check_bench.sh build 3 "1024 4096" 1024
set -euo pipefail
build=$(realpath "${1:?usage: check_bench.sh BUILD_DIR [RUNS] [SIZES] [CGAL_MAX]}")
runs=${2:-5}
sizes=${3:-1024}
cgal_max=${4:-1024}
source "$(dirname "$0")/bench_common.sh"
printf 'load: %s\n\n' "$(uptime)"
printf '| map | triangles | command | wall (median of %d) | peak memory |\n|---|---|---|---|---|\n' "$runs"
# run LABEL ARGS...: prints a row, leaves the median wall time in $work/last.
run() {
  local label=$1; shift
  : > "$work/wall"; : > "$work/rss"
  for ((i = 0; i < runs; i++)); do
    /usr/bin/time -f '%e %M' -o "$work/t" "$build/lightvol" check "$work/v.ply" "$@" --quiet || true
    read -r wall rss < "$work/t"
    echo "$wall" >> "$work/wall"; echo "$rss" >> "$work/rss"
  done
  median < "$work/wall" > "$work/last"
  printf '| %d² | %s | `%s` | %.2f s | %.0f MiB |\n' "$n" "$tris" "$label" "$(cat "$work/last")" \
    "$(echo "$(median < "$work/rss") / 1024" | bc -l)"
}
for n in $sizes; do
  "$build/tests/bench/make_depth" "$n" "$n" "$work/d.exr"
  "$build/lightvol" build "$work/d.exr" --light "$work/spot.json" --out "$work/v.ply" --quiet
  tris=$(head -c 400 "$work/v.ply" | grep -a '^element face' | awk '{print $3}')
  run "lightvol check v.ply --light spot.json" --light "$work/spot.json"
  run "lightvol check v.ply"
  ours=$(cat "$work/last")
  if [ "$n" -le "$cgal_max" ]; then
    run "lightvol check v.ply --engine cgal" --engine cgal
    printf '| %d² | %s | CGAL / lightvol (without light) | %.1fx | |\n' "$n" "$tris" \
      "$(echo "$(cat "$work/last") / $ours" | bc -l)"
  fi
done
