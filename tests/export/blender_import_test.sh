#!/usr/bin/env bash
# A real client of lightvol's GLB: Blender's own glTF importer (Debian's blender 3.4), headless.
# Builds a spot, a directional and an omni volume (and the spot's adaptive volume) from shadow maps of the bundled Sponza crop
# (`lightvol shadowmap --cpu`, small maps: Blender's import stays around a second per volume),
# writes each as a GLB with its build report, and imports all three in one Blender run
# (tests/export/blender_import.py, whose header lists what it asserts: the light's type, pose,
# spot_size and spot_blend from the light files' closed forms; the mesh's vertex, face and edge
# counts, bounds and signed volume from the build reports).
# Usage: tests/export/blender_import_test.sh LIGHTVOL_EXE
# Exit 77 (ctest SKIP) when blender is not installed, unless LIGHTVOL_REQUIRE_BLENDER=1 (CI), where
# a missing blender fails. BLENDER names another executable (default: blender on PATH).
set -euo pipefail
exe=$(realpath "${1:?usage: blender_import_test.sh LIGHTVOL_EXE}")
here=$(cd "$(dirname "$0")" && pwd)
data=$(cd "$here/../../data" && pwd)
blender=${BLENDER:-blender}
if ! command -v "$blender" > /dev/null; then
  if [ "${LIGHTVOL_REQUIRE_BLENDER:-0}" = 1 ]; then
    echo "blender is not installed and LIGHTVOL_REQUIRE_BLENDER=1: run tools/install-deps.sh" >&2
    exit 1
  fi
  echo "SKIP: blender is not installed (apt package blender; tools/install-deps.sh installs it)"
  exit 77
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
run() { "$exe" "$@" --quiet; }

# Lights whose poses are neither axis-aligned nor at the origin, so that a wrong axis conversion,
# sign or handedness shows; the spot's aspect is not 1, so its inner and outer cones differ from
# the symmetric case's.
cat > spot.json << 'EOF'
{ "type": "spot", "position": [1.5, 8.0, -0.5], "direction": [-0.3, -1.0, 0.2], "up": [0, 0, -1],
  "fov_y_deg": 50, "aspect": 1.5, "near": 0.5, "far": 30, "depth": "window" }
EOF
cat > directional.json << 'EOF'
{ "type": "directional", "position": [0.5, 12.0, 0.25], "direction": [0.2, -1.0, -0.1],
  "up": [0, 0, -1], "ortho": [-5, 5, -4, 4], "near": 0, "far": 20, "depth": "linear" }
EOF
cat > omni.json << 'EOF'
{ "type": "omni", "position": [0.5, 3.0, -1.0], "near": 0.1, "far": 40.0 }
EOF
scene="$data/sponza_crop.ply"
run shadowmap "$scene" --light spot.json --size 48 --out spot.exr --cpu
run shadowmap "$scene" --light directional.json --size 40 --out directional.exr --cpu
run shadowmap "$scene" --light omni.json --size 16 --out 'omni_{face}.exr' --cpu
run build spot.exr --light spot.json --out spot.glb --report spot.report.json
run build directional.exr --light directional.json --out directional.glb \
  --report directional.report.json
run build 'omni_{face}.exr' --light omni.json --out omni.glb --report omni.report.json
# An adaptive volume too: fewer, irregular triangles, the same closed mesh for the importer.
run build spot.exr --light spot.json --out adaptive.glb --adaptive --max-error 0.01 \
  --report adaptive.report.json

# --python-exit-code: an exception in the script fails the run (Blender exits 0 otherwise).
# --factory-startup: no user preferences or add-ons of this machine's user.
"$blender" -b --factory-startup --python-exit-code 1 --python "$here/blender_import.py" -- \
  spot.glb spot.json spot.report.json \
  directional.glb directional.json directional.report.json \
  omni.glb omni.json omni.report.json \
  adaptive.glb spot.json adaptive.report.json > blender.log 2>&1 || {
  cat blender.log
  echo "blender_import.py failed (Blender's log above)" >&2
  exit 1
}
grep '^blender_import' blender.log
grep -q '^blender_import: 4 volumes passed$' blender.log ||
  { cat blender.log; echo "blender_import.py did not report 4 volumes passed" >&2; exit 1; }
