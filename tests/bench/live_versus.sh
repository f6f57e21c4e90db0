#!/usr/bin/env bash
# The live rows of the paper's Table 1 protocol (live_table1.sh: the same Sponza lights, camera and
# medium) for two builds of lightvol in one run, so that a change to the live volume's generation
# is measured against what it replaces under the same load: per map, one after the other and in
# this order, live static (BUILD_AFTER), live adaptive of BUILD_BEFORE, live adaptive of
# BUILD_AFTER, and ray marching at the steps live_table1.sh found within 1 % of the reference
# (BUILD_AFTER); ROUNDS times, the order reversed every other round, each row the median of its
# rounds. Both builds make the same volume (the adaptive one is build's quadtree triangle for
# triangle), so the images are the same and only the times differ; live_table1.sh gives the
# errors. Ratios are of this run's frame times.
#
# Usage: tests/bench/live_versus.sh BUILD_BEFORE BUILD_AFTER [SCENE] [SIZES] [OMNI_SIZES]
#   SIZES (default "1024 2048 4096"), OMNI_SIZES (default "512"; "" for none).
# Environment: CAMERA ("640 360"), FRAMES (3), ROUNDS (2), MAX_ERROR (0.01), STEPS (256: ray
# marching's steps for the spot light), OMNI_STEPS (1024: for the omni light).
# Each BUILD holds `lightvol` and `lightvol-image`. SCENE defaults to
# ../shared/scenes/sponza/sponza.obj next to the repository; without it the script says so and
# stops.
set -euo pipefail
source "$(dirname "$0")/sponza_setup.sh"
before=$(realpath "${1:?usage: live_versus.sh BUILD_BEFORE BUILD_AFTER [SCENE] [SIZES] [OMNI_SIZES]}")
after=$(realpath "${2:?usage: live_versus.sh BUILD_BEFORE BUILD_AFTER [SCENE] [SIZES] [OMNI_SIZES]}")
repo=$(cd "$(dirname "$0")/../.." && pwd)
scene=${3:-$repo/../shared/scenes/sponza/sponza.obj}
sizes=${4-1024 2048 4096}
omni_sizes=${5-512}
read -r cam_w cam_h <<< "${CAMERA:-640 360}"
frames=${FRAMES:-3}
rounds=${ROUNDS:-2}
max_error=${MAX_ERROR:-0.01}
steps=${STEPS:-256}
omni_steps=${OMNI_STEPS:-1024}
if [[ ! -f $scene ]]; then
  echo "live_versus: no scene at $scene (the Dabrovic Sponza OBJ; data/README.md says where it comes from)" >&2
  exit 0
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# live_table1.sh's lights, camera and medium.
sponza_setup "$work" "$cam_w" "$cam_h"

run() { "$@" > "$work/out" 2> "$work/err" || { echo "live_versus: failed: $*" >&2; cat "$work/err" >&2; return 1; }; }
after_text() { sed -n "s/.*$1\([0-9.e+-]*\).*/\1/p" "$work/out" | head -1; }
common=(--camera "$work/camera.json" --depth "$work/camera.exr" --medium "$work/medium.json" --quiet)

run "$after/lightvol" shadowmap "$scene" --camera "$work/camera.json" --out "$work/camera.exr"
echo "Sponza ($(basename "$scene")), camera ${cam_w}x${cam_h}, $(nproc) cores, medians of $frames frames and of $rounds rounds, adaptive --max-error $max_error; load average at the start: $(cut -d' ' -f1-3 /proc/loadavg)"
echo "before: $before; after: $after"
echo
printf '| light / map | method | generation | airlight | frame | FPS | frame / live static | ray marching / frame |\n'
printf '|---|---|---:|---:|---:|---:|---:|---:|\n'

# One measurement: NAME LIGHTVOL ARGS... → "GEN FRAME" (ms) appended to $work/NAME
measure() {
  local name=$1 lv=$2
  shift 2
  run "$lv" render "$@" "${common[@]}" --out "$work/a.exr" --frames "$frames"
  echo "$(after_text 'volume generation alone: ') $(after_text 'time per frame: ')" >> "$work/$name"
}

table_rows() {  # LABEL LIGHT MAP_SIZE STEPS
  local label=$1 light=$2 n=$3 n_steps=$4 map=$work/map.exr
  run "$after/lightvol" shadowmap "$scene" --light "$light" --size "$n" --out "$map"
  local sm=(--light "$light" --shadow-map "$map")
  rm -f "$work"/m_*
  local names=(m_static m_before m_after m_march) r k
  for (( r = 0; r < rounds; ++r )); do
    local order=(0 1 2 3)
    (( r % 2 == 1 )) && order=(3 2 1 0)
    for k in "${order[@]}"; do
      case $k in
        0) measure m_static "$after/lightvol" --method live "${sm[@]}" ;;
        1) measure m_before "$before/lightvol" --method live --adaptive --max-error "$max_error" "${sm[@]}" ;;
        2) measure m_after "$after/lightvol" --method live --adaptive --max-error "$max_error" "${sm[@]}" ;;
        3) measure m_march "$after/lightvol" --method raymarch --samples "$n_steps" "${sm[@]}" ;;
      esac
    done
  done
  python3 - "$label" "$n_steps" "$work" <<'PY'
import statistics, sys
label, steps, work = sys.argv[1:]
def read(name):
    rows = [l.split() for l in open(f"{work}/{name}")]
    gen = statistics.median(float(r[0]) if len(r) > 1 else 0.0 for r in rows)
    frame = statistics.median(float(r[-1]) for r in rows)
    return gen, frame
static, march = read("m_static"), read("m_march")
for name, method in (("m_static", "live static"), ("m_before", "live adaptive, before"),
                     ("m_after", "live adaptive, after"), ("m_march", f"ray marching, N = {steps}")):
    gen, frame = read(name)
    ms = lambda v: f"{v:,.1f} ms"
    print(f"| {label} | {method} | {ms(gen) if gen else '–'} | {ms(frame - gen)} | {ms(frame)} | "
          f"{1e3 / frame:.3g} | {frame / static[1]:.2f} | {march[1] / frame:.2f} |")
PY
  rm -f "$map"
}

for n in $sizes; do table_rows "spot ${n}²" "$work/spot.json" "$n" "$steps"; done
for n in $omni_sizes; do table_rows "omni 6×${n}²" "$work/omni.json" "$n" "$omni_steps"; done
echo
echo "load average at the end: $(cut -d' ' -f1-3 /proc/loadavg)"
echo "generation: the volume made on the GPU from the map (render --method live --frames K's \"volume"
echo "generation alone\"); airlight: the frame minus the generation; frame: render --frames K's time"
echo "per frame (shadow map pass not included: the same for every row)."
