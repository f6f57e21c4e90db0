#!/usr/bin/env bash
# Omni builds through the CLI: six W×W EXR faces ({face} path) of the synthetic room → binary PLY,
# at W = 512 and 1024, static and --adaptive --max-error 0.01: median wall time and peak memory
# (RSS) over RUNS runs, with the read / build / check / write stages from --report.
# Usage: tests/bench/omni_build_bench.sh BUILD_DIR [RUNS]   (BUILD_DIR configured with -DLIGHTVOL_BUILD_BENCH=ON)
set -euo pipefail
build=$(realpath "${1:?usage: omni_build_bench.sh BUILD_DIR [RUNS]}")
runs=${2:-3}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
median() { sort -g | awk '{a[NR]=$1} END {print (NR%2 ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2)}'; }
printf '| faces | mode | vertices | triangles | wall (median of %d) | read | build | check | write | peak memory |\n' "$runs"
printf '|---|---|---|---|---|---|---|---|---|---|\n'
for n in 512 1024; do
  "$build/tests/bench/make_omni_depth" "$n" "$work/room$n"'_{face}.exr' > "$work/omni.json"
  for mode in static adaptive; do
  extra=""; [ "$mode" = adaptive ] && extra="--adaptive --max-error 0.01"
  : > "$work/wall"; : > "$work/rss"; : > "$work/stages"
  for ((i = 0; i < runs; i++)); do
    rm -f "$work/v.ply"
    /usr/bin/time -f '%e %M' -o "$work/t" "$build/lightvol" build "$work/room$n"'_{face}.exr' \
      --light "$work/omni.json" --out "$work/v.ply" --quiet --report "$work/r.json" $extra
    read -r wall rss < "$work/t"
    echo "$wall" >> "$work/wall"; echo "$rss" >> "$work/rss"
    python3 - "$work" >> "$work/stages" <<'PY'
import json, sys
r = json.load(open(sys.argv[1] + "/r.json"))
stage = {s["name"]: s["seconds"] for s in r["stages"]}
get = lambda p: sum(v for k, v in stage.items() if k.startswith(p))
print(get("reading omni"), get("building"), get("checking"), get("writing"), r["vertices"], r["triangles"])
PY
  done
  col() { awk -v c="$1" '{print $c}' "$work/stages" | median; }
  printf '| 6×%d² | %s | %s | %s | %.2f s | %.2f s | %.2f s | %.2f s | %.2f s | %.0f MiB |\n' "$n" \
    "$mode" "$(col 5)" "$(col 6)" "$(median < "$work/wall")" "$(col 1)" "$(col 2)" "$(col 3)" "$(col 4)" \
    "$(echo "$(median < "$work/rss") / 1024" | bc -l)"
  done
done
