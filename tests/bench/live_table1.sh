#!/usr/bin/env bash
# The paper's Table 1 protocol (Billeter et al. 2010) on Sponza, live against baked, through the
# CLI: for a spot light above the atrium shining down through it at shadow maps 1024², 2048²,
# 4096², and an omni light at 6×512², each frame's
#   shadow map   `lightvol shadowmap` (OpenGL depth pass: draw + glFinish, its "GPU … ms")
#   generation   the volume made from that map: live, on the GPU (`render --method live --frames K`
#                prints "volume generation alone"); baked, `lightvol build` on the CPU (the build
#                stage of --report: what a moving light or object costs a baked volume per frame);
#                ray marching has none
#   airlight     the volume pass and the resolve: live, the frame minus the generation; baked,
#                `render --method volume --frames K`; ray marching, `render --method raymarch`
# for live static, live adaptive (`render --method live --adaptive --max-error E`: build's quadtree),
# baked static, baked adaptive (`build --adaptive --max-error E`) and ray marching at equal error:
# the fewest steps N (doubling from 16 to MAX_STEPS; for M > 1 given up when doubling no longer
# cuts the error by a tenth) whose image is within TARGET relative L2 of the CPU reference
# (`render --method reference` of the static volume, double precision), for each interleave M.
# Every image's error against that reference is in the table; ratios are of the frame times of
# this one run. Times are medians of FRAMES frames (after one warm-up frame).
#
# Usage: tests/bench/live_table1.sh BUILD_DIR [SCENE] [SIZES] [OMNI_SIZES]
#   SIZES (default "1024 2048 4096"), OMNI_SIZES (default "512"; "" for none).
# Environment: CAMERA ("1280 720"), FRAMES (3), MAX_ERROR (0.01, the Sponza table's adaptive
# rows), TARGET (0.01), INTERLEAVE ("1"; e.g. "1 4"), MAX_STEPS (4096), PNG_DIR (keep each image as a PNG).
# BUILD_DIR holds `lightvol`; SCENE (the full Dabrovic Sponza OBJ, data/README.md) defaults to
# ../shared/scenes/sponza/sponza.obj next to the repository; without it the script says so and
# stops. It runs unchanged where a GPU is present (EGL's device platform; the first line names the
# renderer): the same command gives the absolute table there.
set -euo pipefail
source "$(dirname "$0")/sponza_setup.sh"
build=$(realpath "${1:?usage: live_table1.sh BUILD_DIR [SCENE] [SIZES] [OMNI_SIZES]}")
repo=$(cd "$(dirname "$0")/../.." && pwd)
scene=${2:-$repo/../shared/scenes/sponza/sponza.obj}
sizes=${3-1024 2048 4096}
omni_sizes=${4-512}
read -r cam_w cam_h <<< "${CAMERA:-1280 720}"
frames=${FRAMES:-3}
max_error=${MAX_ERROR:-0.01}
target=${TARGET:-0.01}
interleaves=${INTERLEAVE:-1}
max_steps=${MAX_STEPS:-4096}
png_dir=${PNG_DIR:-}
[[ -n $png_dir ]] && mkdir -p "$png_dir"
if [[ ! -f $scene ]]; then
  echo "live_table1: no scene at $scene (the Dabrovic Sponza OBJ; data/README.md says where it comes from)" >&2
  exit 0
fi
lv=$build/lightvol
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# The lights and medium of sponza_bench.sh; its camera at CAMERA's size.
sponza_setup "$work" "$cam_w" "$cam_h"

# Runs a command with its output in $work/out and $work/err; on failure prints its error.
run() { "$@" > "$work/out" 2> "$work/err" || { echo "live_table1: failed: $*" >&2; cat "$work/err" >&2; return 1; }; }
# The first number after TEXT in $work/out, or "".
after() { sed -n "s/.*$1\([0-9.e+-]*\).*/\1/p" "$work/out" | head -1; }
thousands() { python3 -c "print(f'{int($1):,}')"; }
report_field() { python3 -c "import json,sys; print(json.load(open(sys.argv[1]))[sys.argv[2]])" "$1" "$2"; }
build_seconds() { python3 -c "import json,sys; r=json.load(open(sys.argv[1])); print(sum(s['seconds'] for s in r['stages'] if s['name'].startswith('building')))" "$1"; }
common=(--camera "$work/camera.json" --depth "$work/camera.exr" --medium "$work/medium.json")
keep_png() {  # LABEL METHOD ARGS...: the same render again as a PNG in PNG_DIR
  [[ -z $png_dir ]] && return 0
  local name=$png_dir/$(echo "$1_$2" | tr -c 'A-Za-z0-9\n' '_').png
  shift 2
  "$lv" render "$@" "${common[@]}" --out "$name" --exposure 40 --quiet > /dev/null
}

live_adaptive=no
"$lv" render --help 2> /dev/null | grep -q -- '--adaptive' && live_adaptive=yes

run "$lv" shadowmap "$scene" --camera "$work/camera.json" --out "$work/camera.exr"
run "$lv" render --method radial "${common[@]}" --light "$work/spot.json" --out "$work/r.exr" --frames 1
renderer=$(sed -n 's/.*median of 1 frames, \(.*\))$/\1/p' "$work/out")
echo "Sponza ($(basename "$scene")), camera ${cam_w}x${cam_h}, $(nproc) cores${renderer:+, $renderer}, medians of $frames frames, adaptive --max-error $max_error, ray marching at <= $target relative L2"
echo
printf '| light / map | method | triangles / steps | shadow map | generation | airlight | frame | FPS | rel. L2 vs reference | frame / live static |\n'
printf '|---|---|---:|---:|---:|---:|---:|---:|---:|---:|\n'

# One row: LABEL METHOD SIZE SM_MS GEN_MS AIR_MS ERROR
rows=()
emit() {
  local frame
  frame=$(python3 -c "print($5 + $6 and $4 + $5 + $6)")
  rows+=("$1|$2|$3|$4|$5|$6|$frame|$7")
}
flush() {  # prints the rows of one light / map, with the ratio to its live static frame
  local base=""
  for r in "${rows[@]}"; do
    IFS='|' read -r label method size sm gen air frame err <<< "$r"
    [[ $method == "live static" ]] && base=$frame
  done
  for r in "${rows[@]}"; do
    IFS='|' read -r label method size sm gen air frame err <<< "$r"
    python3 - "$label" "$method" "$size" "$sm" "$gen" "$air" "$frame" "$err" "$base" <<'PY'
import sys
label, method, size, sm, gen, air, frame, err, base = sys.argv[1:]
if float(frame) <= 0:  # no measurement: a method this lightvol lacks, or no N within TARGET
    print(f"| {label} | {method} | {size} | {float(sm):,.1f} ms | – | – | – | – | {err} | – |")
    sys.exit()
ms = lambda v: f"{float(v):,.1f} ms"
ratio = f"{float(frame) / float(base):.2f}" if base else "–"
print(f"| {label} | {method} | {size} | {ms(sm)} | {ms(gen)} | {ms(air)} | {ms(frame)} | {1e3 / float(frame):.3g} | {float(err):.1e} | {ratio} |")
PY
  done
  rows=()
}

table_rows() {  # LABEL LIGHT MAP_SIZE
  local label=$1 light=$2 n=$3 map=$work/map.exr sm ref=$work/ref.exr
  run "$lv" shadowmap "$scene" --light "$light" --size "$n" --out "$map"
  sm=$(after 'GPU ')
  local sm_args=(--light "$light" --shadow-map "$map")

  # Baked static: the CPU build of this frame's map; its mesh also gives the reference.
  run "$lv" build "$map" --light "$light" --out "$work/static.ply" --no-check --quiet --report "$work/r.json"
  local tris gen air err
  tris=$(report_field "$work/r.json" triangles)
  gen=$(python3 -c "print(1e3 * $(build_seconds "$work/r.json"))")
  run "$lv" render "$work/static.ply" --method reference --light "$light" "${common[@]}" --out "$ref" --quiet
  run "$lv" render "$work/static.ply" --light "$light" "${common[@]}" --out "$work/a.exr" --frames "$frames" --compare "$ref" --quiet
  air=$(after 'time per frame: ')
  err=$(after 'relative L2 ')
  local baked_static=("$label" "baked static" "$(thousands "$tris")" "$sm" "$gen" "$air" "$err")
  keep_png "$label" baked_static "$work/static.ply" --light "$light"
  rm -f "$work/static.ply"

  # Live static: made from the map on the GPU each frame.
  run "$lv" render --method live "${sm_args[@]}" "${common[@]}" --out "$work/a.exr" --frames "$frames" --compare "$ref" --quiet
  local frame_ms live_gen
  frame_ms=$(after 'time per frame: ')
  live_gen=$(after 'volume generation alone: ')
  emit "$label" "live static" "$(thousands "$tris")" "$sm" "$live_gen" "$(python3 -c "print(max(0.0, $frame_ms - $live_gen))")" "$(after 'relative L2 ')"
  keep_png "$label" live_static --method live "${sm_args[@]}"

  # Live adaptive (issue 23's GPU quadtree), when this lightvol has it.
  if [[ $live_adaptive == yes ]]; then
    if run "$lv" render --method live --adaptive --max-error "$max_error" "${sm_args[@]}" "${common[@]}" \
      --out "$work/a.exr" --frames "$frames" --compare "$ref" --quiet; then
      frame_ms=$(after 'time per frame: ')
      live_gen=$(after 'volume generation alone: ')
      live_gen=${live_gen:-0}
      local atris l2
      l2=$(after 'relative L2 ')
      # Its triangles are build's quadtree volume's at the same bound, triangle for triangle
      # (tests/render/live_adaptive_test.cpp): counted by that build (render prints no count).
      run "$lv" build "$map" --light "$light" --out "$work/quadtree.ply" --no-check --quiet --report "$work/q.json" \
        --adaptive --tessellation quadtree --max-error "$max_error"
      atris=$(thousands "$(report_field "$work/q.json" triangles)")
      rm -f "$work/quadtree.ply"
      emit "$label" "live adaptive" "$atris" "$sm" "$live_gen" "$(python3 -c "print(max(0.0, $frame_ms - $live_gen))")" "$l2"
      keep_png "$label" live_adaptive --method live --adaptive --max-error "$max_error" "${sm_args[@]}"
    fi
  else
    rows+=("$label|live adaptive|not in this lightvol (render --method live --adaptive)|$sm|0|0|0|–")
  fi

  emit "${baked_static[@]}"

  # Baked adaptive at E = MAX_ERROR (the default tessellation).
  run "$lv" build "$map" --light "$light" --out "$work/adaptive.ply" --no-check --quiet --report "$work/r.json" \
    --adaptive --max-error "$max_error"
  tris=$(report_field "$work/r.json" triangles)
  gen=$(python3 -c "print(1e3 * $(build_seconds "$work/r.json"))")
  run "$lv" render "$work/adaptive.ply" --light "$light" "${common[@]}" --out "$work/a.exr" --frames "$frames" --compare "$ref" --quiet
  emit "$label" "baked adaptive" "$(thousands "$tris")" "$sm" "$gen" "$(after 'time per frame: ')" "$(after 'relative L2 ')"
  keep_png "$label" baked_adaptive "$work/adaptive.ply" --light "$light"
  rm -f "$work/adaptive.ply"

  # Ray marching: the fewest steps within TARGET of the reference, for each interleave.
  local m steps found last
  for m in $interleaves; do
    steps=16 found="" last=""
    while (( steps <= max_steps )); do
      run "$lv" render --method raymarch --samples "$steps" --interleave "$m" "${sm_args[@]}" "${common[@]}" \
        --out "$work/a.exr" --compare "$ref" --quiet
      err=$(after 'relative L2 ')
      if python3 -c "import sys; sys.exit(0 if $err <= $target else 1)"; then found=$steps; break; fi
      # Interleaved (M > 1): a plateau (the gather's blur, not the steps, sets the error) ends the
      # search. M = 1 converges to the static volume's airlight, however unevenly at first.
      (( m > 1 )) && [[ -n $last ]] && python3 -c "import sys; sys.exit(0 if $err > 0.9 * $last else 1)" && break
      last=$err
      steps=$(( steps * 2 ))
    done
    if [[ -z $found ]]; then
      emit "$label" "ray marching, M = $m" "none within $target (N = $steps: $(printf '%.1e' "$err"))" "$sm" 0 0 "–"
      continue
    fi
    run "$lv" render --method raymarch --samples "$found" --interleave "$m" "${sm_args[@]}" "${common[@]}" \
      --out "$work/a.exr" --frames "$frames" --compare "$ref" --quiet
    emit "$label" "ray marching, M = $m" "N = $found" "$sm" 0 "$(after 'time per frame: ')" "$(after 'relative L2 ')"
    keep_png "$label" "raymarch_m$m" --method raymarch --samples "$found" --interleave "$m" "${sm_args[@]}"
  done
  flush
  rm -f "$map" "$ref"
}

for n in $sizes; do table_rows "spot ${n}²" "$work/spot.json" "$n"; done
for n in $omni_sizes; do table_rows "omni 6×${n}²" "$work/omni.json" "$n"; done

echo
echo "shadow map: the light's depth pass (GPU time: draw + glFinish). generation: live, the volume made"
echo "on the GPU from the map (static: transform feedback; adaptive: the compute passes; + glFinish);"
echo "baked, lightvol build on the CPU. airlight:"
echo "the volume and resolve passes (live: frame minus generation), or the marcher. frame = the three."
