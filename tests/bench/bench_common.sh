# Sourced by the shell benchmarks: a scratch folder $work (removed on exit), the synthetic maps'
# spot light in $work/spot.json (make_depth's maps are seen through it), and `median`, which reads
# numbers one per line and prints their median.
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cat > "$work/spot.json" <<'JSON'
{"type": "spot", "position": [0, 10, 0], "direction": [0, -1, 0], "up": [0, 0, -1],
 "fov_y_deg": 60, "near": 1, "far": 20}
JSON
median() { sort -g | awk '{a[NR]=$1} END {print (NR%2 ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2)}'; }

# real_spot_maps BUILD SCENES_DIR N: the Sponza and Sibenik N² spot maps of tessellation_bench.sh's
# lights (linear depth / far), rendered with BUILD's lightvol shadowmap and written as
# $work/SCENE.exr, read in the unit light box $work/box.json. Sets real_maps to the scenes made; a
# scene whose mesh is missing is skipped, saying so.
real_spot_maps() {
  local build=$1 scenes=$2 n=$3 scene obj light far
  real_maps=()
  awk -v n="$n" 'BEGIN { s = n - 1; printf "{\"type\": \"directional\", \"position\": [0, 0, 0], \"direction\": [0, 0, -1], \"up\": [0, 1, 0], \"ortho\": [%.17g, %.17g, %.17g, %.17g], \"near\": 0, \"far\": 1, \"depth\": \"linear\"}\n", -0.5 / s, (s + 0.5) / s, -(s + 0.5) / s, 0.5 / s }' > "$work/box.json"
  for scene in sponza sibenik; do
    obj="$scenes/$scene/$scene.obj"
    [ -f "$obj" ] || { echo "(no $obj: $scene skipped)" >&2; continue; }
    case $scene in  # tessellation_bench.sh's lights
      sponza) light='"position": [0, 14, -1], "direction": [0, -14, 4], "near": 0.5, "far": 40'; far=40 ;;
      sibenik) light='"position": [150, 400, 0], "direction": [0.3, -1, 0.0001], "near": 1, "far": 800'; far=800 ;;
    esac
    echo "{ \"type\": \"spot\", $light, \"up\": [1, 0, 0], \"fov_y_deg\": 90, \"depth\": \"linear\" }" > "$work/spot_$scene.json"
    "$build/lightvol" shadowmap "$obj" --light "$work/spot_$scene.json" --size "$n" --out "$work/shadow.exr" --quiet
    "$build/tests/bench/heightfield_tool" from "$work/shadow.exr" "$n" "$(awk -v f=$far 'BEGIN { print 1 / f }')" \
      "$work/$scene.exr" "$work/$scene.f32"
    rm -f "$work/$scene.f32"
    real_maps+=("$scene")
  done
}
