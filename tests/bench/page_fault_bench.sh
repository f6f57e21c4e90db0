#!/usr/bin/env bash
# Page faults and CPU of the default adaptive build (E = 0.001) of the 4097² Sponza and Sibenik spot
# maps (adaptive_scale_bench.sh's maps and light box), for each of the two processes apart: lightvol
# itself and the lightvol-image helper that decodes the map (run through a wrapper under
# /usr/bin/time, named by LIGHTVOL_IMAGE_HELPER). With a second build folder, both versions run
# alternately; each row is the median of RUNS runs, and the output's md5 (first 12 digits) says
# whether both wrote the same bytes.
# Usage: tests/bench/page_fault_bench.sh BUILD_DIR [OTHER_BUILD_DIR] [RUNS] SCENES_DIR
#   (BUILD_DIR configured with -DLIGHTVOL_BUILD_BENCH=ON: heightfield_tool), e.g.
#   tests/bench/page_fault_bench.sh build /tmp/main-build 3 ../shared/scenes
set -euo pipefail
usage="usage: page_fault_bench.sh BUILD_DIR [OTHER_BUILD_DIR] [RUNS] SCENES_DIR"
build=$(realpath "${1:?$usage}")
other=${2:-}
[ -n "$other" ] && other=$(realpath "$other")
runs=${3:-3}
scenes=${4:?$usage}
source "$(dirname "$0")/bench_common.sh"
versions=("$build")
[ -n "$other" ] && versions+=("$other")

real_spot_maps "$build" "$scenes" 4097

# measure OUT SCENE BUILD: appends "lv_minor lv_major lv_cpu helper_minor helper_major helper_cpu md5".
# lightvol ends an idle helper that has not ended 0.1 s after its channel closed (killing its process
# group): under load that can take the wrapping /usr/bin/time before it writes, and the run is then
# made again (at most 5 times).
measure() {
  local out=$1 scene=$2 b=$3
  printf '#!/bin/sh\nexec /usr/bin/time -f "%%R %%F %%U %%S" -o "%s" "%s" "$@"\n' "$work/th" \
    "$b/lightvol-image" > "$work/helper.sh"
  chmod +x "$work/helper.sh"
  for _ in 1 2 3 4 5; do
    rm -f "$work/out.ply" "$work/th"
    LIGHTVOL_IMAGE_HELPER="$work/helper.sh" /usr/bin/time -f '%R %F %U %S' -o "$work/tl" \
      "$b/lightvol" build "$work/$scene.exr" --light "$work/box.json" --adaptive --max-error 0.001 \
      --out "$work/out.ply" --quiet
    sleep 0.5
    [ -s "$work/th" ] && break
  done
  [ -s "$work/th" ] || { echo "lightvol-image of $b wrote no times in 5 runs" >&2; exit 1; }
  read -r hmin hmaj hu hs < "$work/th"
  read -r tmin tmaj tu ts < "$work/tl"
  # lightvol's rusage includes its waited-for child's: the helper's counts are taken off.
  echo "$((tmin - hmin)) $((tmaj - hmaj)) $(echo "$tu + $ts - $hu - $hs" | bc -l) $hmin $hmaj" \
    "$(echo "$hu + $hs" | bc -l) $(md5sum < "$work/out.ply" | cut -c1-12)" >> "$out"
}

col() { cut -d' ' -f"$2" "$1" | median; }
echo "E = 0.001; $(nproc) cores; load average $(cut -d' ' -f1-3 /proc/loadavg); $(date -u '+%Y-%m-%d %H:%M')"
printf '| map | version | lightvol minor faults | lightvol CPU | helper minor faults | helper CPU | output md5 |\n'
printf '|---|---|---:|---:|---:|---:|---|\n'
for scene in "${real_maps[@]}"; do
  for j in "${!versions[@]}"; do : > "$work/v$j"; done
  for ((i = 0; i < runs; i++)); do
    for j in "${!versions[@]}"; do measure "$work/v$j" "$scene" "${versions[$j]}"; done
  done
  for j in "${!versions[@]}"; do
    printf '| %s | %s | %s | %.2f s | %s | %.2f s | %s |\n' "$scene" "${versions[$j]}" \
      "$(col "$work/v$j" 1)" "$(col "$work/v$j" 3)" "$(col "$work/v$j" 4)" "$(col "$work/v$j" 6)" \
      "$(cut -d' ' -f7 "$work/v$j" | sort -u | tr '\n' ' ')"
  done
done
echo "(load average at the end: $(cut -d' ' -f1-3 /proc/loadavg))"
