#!/usr/bin/env bash
# Golden outputs: runs a fixed set of lightvol commands on the bundled data and prints one line per
# output, "<sha256>  <name>". A refactoring must not change any line:
#
#   tests/golden/golden_outputs.sh build/lightvol > now.txt && diff tests/golden/expected.txt now.txt
#
# (or `tests/golden/golden_outputs.sh build/lightvol --check`, which does that diff). The outputs
# cover static, adaptive and omni volumes in every format, `stats --json`, `check --json`, a CPU
# shadow map and `render` EXRs. Timings and peak memory are removed from the JSON reports before
# hashing; everything else is hashed byte for byte. When a change is meant to alter an output,
# regenerate expected.txt and say which lines changed and why in the commit message.
set -euo pipefail
exe=$(realpath "${1:?usage: golden_outputs.sh PATH/TO/lightvol [--check]}")
mode=${2:-}
here=$(cd "$(dirname "$0")" && pwd)
data=$(cd "$here/../../data" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
# Inputs by a relative path: reports name their inputs, and the checkout's folder must not matter.
ln -s "$data" data

# JSON without the fields that measure time or memory, keys sorted.
strip_json() {
  python3 -c '
import json, sys
VOLATILE = {"seconds", "total_seconds", "peak_memory_bytes", "stages", "ms", "milliseconds"}
def strip(v):
    if isinstance(v, dict):
        return {k: strip(x) for k, x in v.items() if k not in VOLATILE and not k.endswith("_seconds")}
    if isinstance(v, list):
        return [strip(x) for x in v]
    return v
print(json.dumps(strip(json.load(sys.stdin)), sort_keys=True, indent=1))'
}

run() { "$exe" "$@" --quiet > /dev/null; }

{
  # Static and adaptive spot volumes in every format; a directional volume; light space.
  for ext in ply obj off stl drc glb; do
    run build "data/synthetic_256.exr" --light "data/spot_light.json" --out "static.$ext"
    run build "data/synthetic_256.exr" --light "data/spot_light.json" --out "adaptive.$ext" \
      --adaptive --max-error 0.01
  done
  run build "data/synthetic_256.exr" --light "data/spot_light.json" --out static_ascii.ply --ascii
  run build "data/synthetic_256.exr" --light "data/spot_light.json" --out static_draco.glb --draco
  run build "data/synthetic_256.exr" --light "data/spot_light.json" --out laplacian.ply \
    --refine laplacian --threshold 0.001
  run build "data/synthetic_256.exr" --light "data/directional_light.json" --out directional.ply
  run build "data/synthetic_256.exr" --light "data/directional_light.json" --out directional_adaptive.ply \
    --adaptive --max-error 0.001
  run build "data/synthetic_256.exr" --light "data/spot_light.json" --out light_space.ply --space light

  # Omni: six faces rendered on the CPU from the bundled scene, then static and adaptive volumes.
  printf '{ "type": "omni", "position": [0.5, 3.0, -1.0], "near": 0.1, "far": 40.0 }\n' > omni.json
  run shadowmap "data/sponza_crop.ply" --light omni.json --size 48 --out 'omni_{face}.exr' --cpu
  for ext in ply glb; do
    run build 'omni_{face}.exr' --light omni.json --out "omni_static.$ext"
    run build 'omni_{face}.exr' --light omni.json --out "omni_adaptive.$ext" --adaptive --max-error 0.05
  done

  # A CPU shadow map of the bundled scene.
  run shadowmap "data/sponza_crop.ply" --light "data/sponza_spot.json" --size 96 --out spot_shadow.exr --cpu

  # Reports.
  "$exe" stats "data/synthetic_256.exr" --light "data/spot_light.json" --max-error 0.001,0.01 --json --quiet \
    | strip_json > stats.json
  "$exe" stats 'omni_{face}.exr' --light omni.json --max-error 0.05 --json --quiet | strip_json > stats_omni.json
  "$exe" check static.ply --light "data/spot_light.json" --json --quiet | strip_json > check.json
  "$exe" check adaptive.off --json --quiet | strip_json > check_nolight.json

  # Renders of the bundled scene from a small camera: the CPU reference and the volume method.
  run build spot_shadow.exr --light "data/sponza_spot.json" --out sponza_static.ply
  python3 -c '
import json, sys
cam = json.load(open(sys.argv[1])); cam["width"], cam["height"] = 64, 48
json.dump(cam, open("cam.json", "w"))' "data/sponza_camera.json"
  run shadowmap "data/sponza_crop.ply" --camera cam.json --out camdepth.exr --cpu
  for method in reference volume; do
    run render sponza_static.ply --light "data/sponza_spot.json" --camera cam.json \
      --depth camdepth.exr --medium "data/sponza_medium.json" --shadow-map spot_shadow.exr \
      --method $method --out "render_$method.exr"
  done
} 2> errors.txt || { cat errors.txt >&2; exit 1; }

for f in $(ls | sort); do
  case "$f" in errors.txt|hashes.txt|cam.json|omni.json|data) continue ;; esac
  case "$f" in
    # OpenEXR files carry the time they were written (DateTime): hash the rest of the header
    # and the pixels (OpenImageIO's SHA-1 of the pixel data).
    *.exr) echo "$(oiiotool --info -v --hash "$f" | grep -v 'DateTime\|^Reading' | sha256sum | cut -d' ' -f1)  $f" ;;
    *) sha256sum "$f" ;;
  esac
done > "$work/hashes.txt"

if [ "$mode" = "--check" ]; then
  diff -u "$here/expected.txt" "$work/hashes.txt" && echo "golden outputs: all $(wc -l < "$work/hashes.txt") identical"
else
  cat "$work/hashes.txt"
fi
