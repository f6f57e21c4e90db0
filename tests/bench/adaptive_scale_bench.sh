#!/usr/bin/env bash
# Adaptive builds at scale (E = 0.001, default flags: the collapse): synthetic spot maps of
# make_depth (window depth, the light of bench_common.sh) at SIZES, and the 4097² Sponza and
# Sibenik spot maps of tessellation_bench.sh (linear depth / far, in its unit light box) when
# SCENES_DIR has them. Whole process under /usr/bin/time (user+sys CPU, wall, peak memory) and the
# build report's stages (reading the image; "pyramid": texel depths and the error pyramid;
# collapse). With a second build folder, both versions run alternately, and each row of the
# second table is this version over the other (CPU, wall, memory, read, pyramid, collapse): ratios
# from one run of both. The output's md5
# (first 12 digits) says whether both wrote the same bytes.
# ANY_MAP_SIZES (environment, default none), e.g. "16384": at each such N, also the maps that
# are hardest on the adaptive build, in the unit light box (linear depth / far): the Sponza and
# Sibenik spot maps rendered at N² (with SCENES_DIR), Sponza's 1024² map upsampled to N² (each
# texel repeated: plateaus with steps) and heightfield_tool's steps map (its fix-up rounds
# cascade: N/8 - 1 of them).
# Usage: tests/bench/adaptive_scale_bench.sh BUILD_DIR [OTHER_BUILD_DIR] [RUNS] [SIZES] [SCENES_DIR]
#   (BUILD_DIR configured with -DLIGHTVOL_BUILD_BENCH=ON: make_depth, heightfield_tool), e.g.
#   tests/bench/adaptive_scale_bench.sh build /tmp/main-build 1 "4096 16384" ../shared/scenes
set -euo pipefail
build=$(realpath "${1:?usage: adaptive_scale_bench.sh BUILD_DIR [OTHER_BUILD_DIR] [RUNS] [SIZES] [SCENES_DIR]}")
other=${2:-}
[ -n "$other" ] && other=$(realpath "$other")
runs=${3:-1}
sizes=${4:-"4096 16384"}
scenes=${5:-}
source "$(dirname "$0")/bench_common.sh"
versions=("$build")
[ -n "$other" ] && versions+=("$other")

# measure OUT MAP LIGHT BINARY: appends "cpu wall peak_MiB read pyramid collapse triangles md5"
# of one build.
measure() {
  local out=$1 map=$2 light=$3 lv=$4
  rm -f "$work/out.ply"
  /usr/bin/time -f '%U %S %e %M' -o "$work/t" "$lv" build "$map" --light "$light" --adaptive \
    --max-error 0.001 --out "$work/out.ply" --report "$work/r.json" --quiet
  read -r user sys wall rss < "$work/t"
  python3 - "$work/r.json" "$user" "$sys" "$wall" "$rss" "$(md5sum < "$work/out.ply" | cut -c1-12)" >> "$out" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
read = sum(s["seconds"] for s in r["stages"] if s["name"].startswith("reading") and not s["name"].endswith(".json"))
a = r["adaptive"]["seconds"]
print(float(sys.argv[2]) + float(sys.argv[3]), sys.argv[4], int(sys.argv[5]) / 1024, read,
      a["error_pyramid"], a["collapse"], r["triangles"], sys.argv[6])
PY
}

col() { cut -d' ' -f"$2" "$1" | median; }
maps=()   # "label|map|light"
for n in $sizes; do
  "$build/tests/bench/make_depth" "$n" "$n" "$work/d$n.exr"
  maps+=("synthetic spot $n² (window)|$work/d$n.exr|$work/spot.json")
done
# real_maps_at N: the scenes' spot maps at N² as $work/SCENE_N.exr in $work/box_N.json.
real_maps_at() {
  local n=$1 scene
  real_spot_maps "$build" "$scenes" "$n"
  mv "$work/box.json" "$work/box_$n.json"
  for scene in "${real_maps[@]}"; do
    mv "$work/$scene.exr" "$work/${scene}_$n.exr"
    maps+=("$scene spot $n² (depth/far)|$work/${scene}_$n.exr|$work/box_$n.json")
  done
}
[ -n "$scenes" ] && real_maps_at 4097
tool="$build/tests/bench/heightfield_tool"
for n in ${ANY_MAP_SIZES:-}; do
  if [ -n "$scenes" ]; then
    real_maps_at "$n"
    if [ -f "$work/sponza_$n.exr" ]; then
      real_spot_maps "$build" "$scenes" 1024
      "$tool" upsample "$work/sponza.exr" $((n / 1024)) "$work/upsampled_$n.exr" "$work/upsampled.f32"
      rm -f "$work/upsampled.f32"
      maps+=("Sponza spot 1024² upsampled to $n²|$work/upsampled_$n.exr|$work/box_$n.json")
    fi
  fi
  "$tool" steps "$n" "$work/steps_$n.exr" "$work/steps.f32"
  rm -f "$work/steps.f32"
  [ -f "$work/box_$n.json" ] || awk -v n="$n" 'BEGIN { s = n - 1; printf "{\"type\": \"directional\", \"position\": [0, 0, 0], \"direction\": [0, 0, -1], \"up\": [0, 1, 0], \"ortho\": [%.17g, %.17g, %.17g, %.17g], \"near\": 0, \"far\": 1, \"depth\": \"linear\"}\n", -0.5 / s, (s + 0.5) / s, -(s + 0.5) / s, 0.5 / s }' > "$work/box_$n.json"
  maps+=("steps $n²|$work/steps_$n.exr|$work/box_$n.json")
done

echo "E = 0.001; $(nproc) cores; load average $(cut -d' ' -f1-3 /proc/loadavg); $(date -u '+%Y-%m-%d %H:%M')"
printf '| map | version | triangles | output md5 | CPU user+sys | wall | peak memory | read | pyramid | collapse |\n'
printf '|---|---|---:|---|---:|---:|---:|---:|---:|---:|\n'
ratios=()
for m in "${maps[@]}"; do
  IFS='|' read -r label map light <<< "$m"
  for j in "${!versions[@]}"; do : > "$work/v$j"; done
  for ((i = 0; i < runs; i++)); do
    for j in "${!versions[@]}"; do measure "$work/v$j" "$map" "$light" "${versions[$j]}/lightvol"; done
  done
  for j in "${!versions[@]}"; do
    printf '| %s | %s | %s | %s | %.2f s | %.2f s | %.0f MiB | %.2f s | %.2f s | %.2f s |\n' "$label" \
      "${versions[$j]}" "$(col "$work/v$j" 7)" "$(cut -d' ' -f8 "$work/v$j" | sort -u | tr '\n' ' ')" \
      "$(col "$work/v$j" 1)" "$(col "$work/v$j" 2)" \
      "$(col "$work/v$j" 3)" "$(col "$work/v$j" 4)" "$(col "$work/v$j" 5)" "$(col "$work/v$j" 6)"
  done
  if [ -n "$other" ]; then
    ratios+=("$(printf '| %s | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f |' "$label" \
      "$(echo "$(col "$work/v0" 1) / $(col "$work/v1" 1)" | bc -l)" \
      "$(echo "$(col "$work/v0" 2) / $(col "$work/v1" 2)" | bc -l)" \
      "$(echo "$(col "$work/v0" 3) / $(col "$work/v1" 3)" | bc -l)" \
      "$(echo "$(col "$work/v0" 4) / $(col "$work/v1" 4)" | bc -l)" \
      "$(echo "$(col "$work/v0" 5) / $(col "$work/v1" 5)" | bc -l)" \
      "$(echo "$(col "$work/v0" 6) / $(col "$work/v1" 6)" | bc -l)")")
  fi
done
if [ -n "$other" ]; then
  printf '\nThis version over the other (medians of %d):\n\n' "$runs"
  printf '| map | CPU | wall | peak memory | read | pyramid | collapse |\n|---|---:|---:|---:|---:|---:|---:|\n'
  printf '%s\n' "${ratios[@]}"
fi
