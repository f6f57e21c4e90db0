# Sourced by the Sponza benchmarks (sponza_bench.sh, live_table1.sh, live_versus.sh): their one
# setup, so that their tables measure the same view.
#   sponza_setup DIR WIDTH HEIGHT  writes DIR/spot.json (the 60° spot above the atrium),
#   DIR/omni.json (the omni light in it), DIR/camera.json (the camera along the nave, at
#   WIDTH×HEIGHT) and DIR/medium.json (the fog).
sponza_setup() {
  local dir=$1 width=$2 height=$3
  cat > "$dir/spot.json" <<'JSON'
{ "type": "spot", "position": [0, 14, -1], "direction": [0, -14, 4], "up": [1, 0, 0],
  "fov_y_deg": 60, "near": 0.5, "far": 40, "depth": "window" }
JSON
  cat > "$dir/omni.json" <<'JSON'
{ "type": "omni", "position": [0, 6, 0], "near": 0.1, "far": 40, "depth": "window" }
JSON
  cat > "$dir/camera.json" <<JSON
{ "type": "spot", "position": [-12, 2.5, 0.3], "direction": [1, 0.2, 0], "up": [0, 1, 0],
  "fov_y_deg": 60, "aspect": $(python3 -c "print($width / $height)"), "near": 0.1, "far": 60,
  "depth": "window", "width": $width, "height": $height }
JSON
  cat > "$dir/medium.json" <<'JSON'
{ "scattering": 0.04, "absorption": 0.01, "intensity": 200, "phase": { "type": "hg", "g": 0.3 } }
JSON
}
