#!/usr/bin/env bash
# Every kind of GLB lightvol writes (static, adaptive, Draco-compressed and omni volumes; spot,
# directional and omni lights; light space; with a medium; the demo's volumes and scene) passes Khronos' glTF
# validator with 0 errors and 0 warnings. Usage: validate_glbs.sh PATH/TO/lightvol
# Needs node and web/node_modules (tools/install-deps.sh runs `npm ci` in web/).
set -euo pipefail
exe=$(realpath "${1:?usage: validate_glbs.sh PATH/TO/lightvol}")
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
data="$root/data"
[ -d "$root/web/node_modules/gltf-validator" ] ||
  { echo "web/node_modules/gltf-validator is missing: run tools/install-deps.sh" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
run() { "$exe" "$@" --quiet; }

spot="$data/spot_light.json" directional="$data/directional_light.json"
depth="$data/synthetic_256.exr"
run build "$depth" --light "$spot" --out static.glb
run build "$depth" --light "$spot" --out adaptive.glb --adaptive --max-error 0.01
run build "$depth" --light "$spot" --out draco.glb --draco
run build "$depth" --light "$spot" --out adaptive_draco.glb --draco --adaptive --max-error 0.01
run build "$depth" --light "$spot" --out medium.glb --medium "$data/sponza_medium.json"
run build "$depth" --light "$spot" --out light_space.glb --space light
run build "$depth" --light "$directional" --out directional.glb
run build "$depth" --light "$directional" --out directional_draco.glb --draco
printf '{ "type": "omni", "position": [0.5, 3.0, -1.0], "near": 0.1, "far": 40.0 }\n' > omni.json
run shadowmap "$data/sponza_crop.ply" --light omni.json --size 32 --out 'omni_{face}.exr' --cpu
run build 'omni_{face}.exr' --light omni.json --out omni.glb
run build 'omni_{face}.exr' --light omni.json --out omni_adaptive.glb --adaptive --max-error 0.05
run build 'omni_{face}.exr' --light omni.json --out omni_draco.glb --draco
# The demo's GLBs for the web viewer: its volumes with light and medium, and the scene.
run demo --out demo --size 32 > /dev/null
files=(*.glb demo/volume_static.glb demo/volume_adaptive.glb demo/scene.glb)
node "$root/web/tests/validate_glb.mjs" "${files[@]}"
