#!/usr/bin/env bash
# The paper's Table 1 on Sponza (Billeter et al. 2010), end to end through the CLI: for a spot light
# above the atrium shining down through it (the paper's Figure 8a) at shadow maps 1024², 2048²,
# 4096², and an omni light at 6×128² and 6×512²:
#   shadow map   `lightvol shadowmap` (OpenGL depth pass; GPU = draw + glFinish, wall = whole command)
#   build        `lightvol build --no-check` static, and `--adaptive --max-error E`: the build stage
#                of --report (depth image already read; mesh writing not included)
#   check        `lightvol check MESH --light` wall time (includes reading the binary PLY)
#   render       `lightvol render --method volume --frames K`: median time per frame of the volume
#                pass at the camera's size (GPU = llvmpipe here)
# Prints markdown tables. Usage:
#   tests/bench/sponza_bench.sh BUILD_DIR [SCENE] [MAX_ERROR] [SIZES] [OMNI_SIZES]
# The environment variable MODES picks the volumes of each row (default "static collapse quadtree":
# the static volume and the adaptive one with each tessellation, `--tessellation collapse`, the
# default, and `--tessellation quadtree`, the paper's); e.g. MODES="collapse quadtree" skips the slow
# static rows. PNG_DIR, if set, keeps each render there as LABEL_MODE.png to look at.
# BUILD_DIR holds the `lightvol` binary; SCENE (the full Dabrovic Sponza OBJ, see data/README.md)
# defaults to ../shared/scenes/sponza/sponza.obj next to the repository. Needs about 2.5 GB of
# free space in $TMPDIR for the 4096² PLY files.
set -euo pipefail
source "$(dirname "$0")/sponza_setup.sh"
build=$(realpath "${1:?usage: sponza_bench.sh BUILD_DIR [SCENE] [MAX_ERROR] [SIZES] [OMNI_SIZES]}")
repo=$(cd "$(dirname "$0")/../.." && pwd)
scene=${2:-$repo/../shared/scenes/sponza/sponza.obj}
max_error=${3:-0.01}
sizes=${4:-1024 2048 4096}
omni_sizes=${5:-128 512}
modes=${MODES:-static collapse quadtree}
png_dir=${PNG_DIR:-}
[[ -n $png_dir ]] && mkdir -p "$png_dir"
if [[ ! -f $scene ]]; then
  echo "sponza_bench: no scene at $scene (the Dabrovic Sponza OBJ; data/README.md says where it comes from)" >&2
  exit 0
fi
lv=$build/lightvol
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

sponza_setup "$work" 1280 720

wall() { /usr/bin/time -f '%e' -o "$work/t" "$@" > "$work/out" 2> "$work/err" || { cat "$work/err" >&2; return 1; }; cat "$work/t"; }
stage() { python3 -c "import json,sys; r=json.load(open(sys.argv[1])); print(sum(s['seconds'] for s in r['stages'] if s['name'].startswith(sys.argv[2])))" "$1" "$2"; }
field() { python3 -c "import json,sys; print(json.load(open(sys.argv[1]))[sys.argv[2]])" "$1" "$2"; }
frames_for() { local tris=$1; if (( tris > 8000000 )); then echo 1; elif (( tris > 2000000 )); then echo 2; else echo 3; fi; }

"$lv" shadowmap "$scene" --camera "$work/camera.json" --out "$work/camera.exr" --quiet

# One row: LABEL LIGHT DEPTH... ; builds (static and adaptive), checks, renders.
row() {
  local label=$1 light=$2 depth=$3 sm_wall=$4 sm_gpu=$5
  for mode in $modes; do
    local extra=() mesh=$work/$mode.ply
    [[ $mode != static ]] && extra=(--adaptive --max-error "$max_error" --tessellation "$mode")
    rm -f "$mesh"
    if ! wall "$lv" build "$depth" --light "$light" --out "$mesh" --quiet --no-check --report "$work/r.json" "${extra[@]}" > /dev/null 2>&1; then
      printf '| %s | %s | n/a: %s | | | | |\n' "$label" "$mode" "$(head -1 "$work/err")"
      continue
    fi
    local tris build_s check_s frames render_ms
    tris=$(field "$work/r.json" triangles)
    build_s=$(stage "$work/r.json" building)
    check_s=$(wall "$lv" check "$mesh" --light "$light")
    grep -q "valid" "$work/out" || { echo "check output:" >&2; cat "$work/out" >&2; }
    frames=$(frames_for "$tris")
    wall "$lv" render "$mesh" --light "$light" --camera "$work/camera.json" --depth "$work/camera.exr" \
      --medium "$work/medium.json" --out "$work/a.exr" --frames "$frames" --quiet > /dev/null
    render_ms=$(sed -n 's/.*time per frame: \([0-9.]*\) ms.*/\1/p' "$work/out")
    [[ -z $render_ms ]] && render_ms=$(sed -n 's/.*per frame[^0-9]*\([0-9.]*\).*/\1/p' "$work/out" "$work/err" | head -1)
    if [[ -n $png_dir ]]; then
      local png
      png=$png_dir/$(echo "$label" | tr -c 'A-Za-z0-9\n' '_')_$mode.png
      wall "$lv" render "$mesh" --light "$light" --camera "$work/camera.json" --depth "$work/camera.exr" \
        --medium "$work/medium.json" --out "$png" --quiet > /dev/null
    fi
    printf '| %s | %s | %s | %s s (GPU %s ms) | %.2f s | %s s | %s ms |\n' "$label" "$mode" \
      "$(python3 -c "print(f'{$tris:,}')")" "$sm_wall" "$sm_gpu" "$build_s" "$check_s" "${render_ms:-?}"
    rm -f "$mesh"
  done
}

gpu_ms() { sed -n 's/.*GPU \([0-9.]*\) ms.*/\1/p' "$work/out"; }

echo "Sponza ($scene), camera 1280x720, adaptive --max-error $max_error, $(nproc) cores, $("$lv" shadowmap --help > /dev/null && echo llvmpipe)"
echo
printf '| light / map | volume | triangles | shadow map | build | check | render / frame |\n'
printf '|---|---|---|---|---|---|---|\n'
for n in $sizes; do
  t=$(wall "$lv" shadowmap "$scene" --light "$work/spot.json" --size "$n" --out "$work/spot$n.exr")
  row "spot ${n}²" "$work/spot.json" "$work/spot$n.exr" "$t" "$(gpu_ms)"
  rm -f "$work/spot$n.exr"
done
for n in $omni_sizes; do
  t=$(wall "$lv" shadowmap "$scene" --light "$work/omni.json" --size "$n" --out "$work/omni$n.exr")
  row "omni 6×${n}²" "$work/omni.json" "$work/omni$n.exr" "$t" "$(gpu_ms)"
  rm -f "$work/omni$n.exr"
done
