#!/usr/bin/env bash
# lightvol's adaptive tessellations (collapse, the default, and quadtree) against Mapbox Martini
# (RTIN, @mapbox/martini 0.2.0) and Delatin (greedy Delaunay insertion, delatin 0.2.0, the JS port of
# hmm) on height fields: the synthetic shadow maps (floor, boxes, one-texel bars, a sphere) and real
# spot shadow maps of Sponza and Sibenik rendered with `lightvol shadowmap` (linear depth divided by
# far, so values lie in [0, 1]; sizes 2^k + 1 because Martini needs them). lightvol builds with a
# directional light, near 0, far 1, linear depth: world units along a texel ray are height units, as
# the other meshers' are. One shared checker (heightfield_tool error) measures every mesh at every
# texel: triangles (the volume's closing dropped), max error reached, smallest angle (texel space).
# Time and peak memory: the whole process (/usr/bin/time: wall, user+sys CPU, max RSS) — lightvol
# build (read EXR, tessellate, check, write PLY) and node (read map, mesh, write the dump). Martini
# is rerun at halved thresholds until its measured error meets E; only that row is printed.
# Omni (OMNI_SIZE, default 512; 0 skips): lightvol's two tessellations of real omni volumes, six
# faces of each scene from `lightvol shadowmap` (linear depth), bound E × far in world units;
# reached error, triangles and smallest angle from `build --report`. Martini and Delatin are not
# run per face: their union is no closed volume (each face meshes its borders on its own, so the
# seams do not share vertices), and an omni face's error is a distance along perspective rays,
# not a height.
# Upsampled maps (UPSAMPLED, default "2048 4096"; "" skips; add 16384 for the largest): plateaus
# with steps, lightvol only (Martini needs 2^k + 1 texels). The 1024² Sponza spot map (depth/far)
# with each texel repeated (N/1024)² times, and heightfield_tool's `steps` map, whose fix-up rounds
# cascade across the map (N/8 − 1 rounds). Their own table: triangles, largest error (lightvol's
# report), fix-up rounds, the balance step's seconds (threshold, balance and fix-up), whole-process
# wall, CPU and peak memory; then per map and tessellation the ratio of each size's wall time to
# the first size's. LIGHTVOL (default BUILD_DIR/lightvol) picks the lightvol to time, e.g. an older
# build for a before/after in one run.
# Usage: tests/bench/tessellation_bench.sh BUILD_DIR [SIZES] [E] [REAL_SIZES] [SCENES_DIR]
#   BUILD_DIR configured with -DLIGHTVOL_BUILD_BENCH=ON (heightfield_tool); SIZES "1025 4097";
#   E 0.001; REAL_SIZES "1025 4097"; SCENES_DIR with sponza/sponza.obj and sibenik/sibenik.obj.
# Environment: MESHERS (default "collapse quadtree martini delatin") picks the rows; DELATIN_MAX
# (default 0: no limit) skips Delatin above that size (about 280 s of CPU at 4097²).
# The npm packages go into a scratch folder under /tmp (TIN_DIR), never into the source tree.
# One run per cell (no repetition): on a shared machine, compare CPU time rather than wall time.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
build=$(realpath "${1:?usage: tessellation_bench.sh BUILD_DIR [SIZES] [E] [REAL_SIZES] [SCENES_DIR]}")
sizes=${2-"1025 4097"}
bound=${3:-0.001}
real_sizes=${4-"1025 4097"}
meshers=${MESHERS:-"collapse quadtree martini delatin"}
delatin_max=${DELATIN_MAX:-0}
omni_size=${OMNI_SIZE:-512}
upsampled=${UPSAMPLED-"2048 4096"}
runs() { [[ " $meshers " == *" $1 "* ]]; }
scenes=${5:-$here/../../../shared/scenes}
scratch=${TIN_DIR:-/tmp/lightvol-martini}
mkdir -p "$scratch"
if { runs martini || runs delatin; } &&
  { [ ! -d "$scratch/node_modules/@mapbox/martini" ] || [ ! -d "$scratch/node_modules/delatin" ]; }; then
  (cd "$scratch" && npm install --silent --no-audit --no-fund @mapbox/martini@0.2.0 delatin@0.2.0 >/dev/null)
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
tool="$build/tests/bench/heightfield_tool"
lv=${LIGHTVOL:-$build/lightvol}

# timed CMD...: runs it under /usr/bin/time; sets wall, cpu (user+sys), mem (MB); returns its status.
timed() {
  local status=0
  /usr/bin/time -f '%e %U %S %M' -o "$work/time" "$@" || status=$?
  read -r wall user sys kb < <(tail -n 1 "$work/time")
  cpu=$(awk -v u="$user" -v s="$sys" 'BEGIN { printf "%.2f", u + s }')
  mem=$(awk -v k="$kb" 'BEGIN { printf "%.0f", k / 1024 }')
  return $status
}

row() {  # map mesher threshold mesh
  read -r _ tris _ reached _ uncovered _ angle < <("$tool" error "$work/map.f32" "$n" "$4" $((n - 1)))
  printf '| %s | %s | %s | %s | %s | %s | %s s | %s s | %s MB | %s° |\n' "$1" "$2" "$3" "$tris" \
    "$reached" "$uncovered" "$wall" "$cpu" "$mem" "$angle"
}

bench_map() {  # label: $work/map.exr and $work/map.f32 of size $n
  local label=$1
  # A light box one unit across (texel (col, row) at (col, −row) / (N − 1)), as the tables in
  # docs/performance.md were measured (a box N units wide builds too). The checker scales back.
  local ortho
  ortho=$(awk -v n="$n" 'BEGIN { s = n - 1; printf "%.17g, %.17g, %.17g, %.17g", -0.5 / s, (s + 0.5) / s, -(s + 0.5) / s, 0.5 / s }')
  cat > "$work/light.json" <<JSON
{"type": "directional", "position": [0, 0, 0], "direction": [0, 0, -1], "up": [0, 1, 0],
 "ortho": [$ortho], "near": 0, "far": 1, "depth": "linear"}
JSON
  for t in collapse quadtree; do
    runs $t || continue
    if ! timed "$lv" build "$work/map.exr" --light "$work/light.json" --adaptive --max-error "$bound" \
      --tessellation $t --out "$work/v.ply" --quiet 2> "$work/err"; then
      printf '| %s | lightvol %s | %s | (build failed: %s) |||||||\n' "$label" "$t" "$bound" \
        "$(head -c 160 "$work/err")"
      continue
    fi
    row "$label" "lightvol $t" "$bound" "$work/v.ply"
  done
  if runs martini; then
  local th=$bound
  for _ in 1 2 3 4 5 6 7; do
    timed node "$here/tin_bench.mjs" "$scratch" martini "$work/map.f32" "$n" "$work/m" "$th" > /dev/null
    read -r _ _ _ reached _ < <("$tool" error "$work/map.f32" "$n" "$work/m0.mrt")
    if awk -v r="$reached" -v e="$bound" 'BEGIN { exit !(r <= e) }'; then break; fi
    th=$(awk -v t="$th" 'BEGIN { printf "%.9g", t / 2 }')
  done
  row "$label" "Martini" "$th" "$work/m0.mrt"
  fi
  runs delatin || return 0
  if [ "$delatin_max" -gt 0 ] && [ "$n" -gt "$delatin_max" ]; then
    printf '| %s | Delatin | %s | (not run: size above DELATIN_MAX=%s) |||||||\n' "$label" "$bound" "$delatin_max"
    return 0
  fi
  timed node "$here/tin_bench.mjs" "$scratch" delatin "$work/map.f32" "$n" "$work/d" "$bound" > /dev/null
  row "$label" "Delatin" "$bound" "$work/d0.mrt"
}

echo "E = $bound; $(nproc) cores; $(date -u +%Y-%m-%d)"
printf '| map | mesher | threshold | triangles | max error reached | uncovered texels | wall | CPU | peak memory | smallest angle |\n'
printf '|---|---|---|---:|---:|---:|---:|---:|---:|---:|\n'
for n in $sizes; do
  "$tool" map "$n" "$work/map.exr" "$work/map.f32"
  bench_map "synthetic $n²"
done
for scene in sponza sibenik; do
  obj="$scenes/$scene/$scene.obj"
  [ -f "$obj" ] || { echo "(no $obj: $scene skipped)" >&2; continue; }
  # Sponza: above the atrium looking down through it (sponza_bench.sh's light, 90°); Sibenik (its
  # units are about 1/30 m): inside the nave looking down. Heights: linear depth / far.
  case $scene in
    sponza) light='"position": [0, 14, -1], "direction": [0, -14, 4], "near": 0.5, "far": 40'
            far=40 ;;
    sibenik) light='"position": [150, 400, 0], "direction": [0.3, -1, 0.0001], "near": 1, "far": 800'
             far=800 ;;
  esac
  cat > "$work/spot.json" <<JSON
{ "type": "spot", $light, "up": [1, 0, 0], "fov_y_deg": 90, "depth": "linear" }
JSON
  for n in $real_sizes; do
    "$lv" shadowmap "$obj" --light "$work/spot.json" --size "$n" --out "$work/shadow.exr" --quiet
    "$tool" from "$work/shadow.exr" "$n" "$(awk -v f=$far 'BEGIN { print 1 / f }')" "$work/map.exr" "$work/map.f32"
    bench_map "$scene spot $n² (depth/far)"
  done
  [ "$omni_size" -gt 0 ] || continue
  # Omni at the spot light's position, linear depth; bound E × far (world units).
  pos=$(sed 's/.*"position": \(\[[^]]*\]\).*/\1/' <<< "$light")
  cat > "$work/omni.json" <<JSON
{ "type": "omni", "position": $pos, "near": $(sed 's/.*"near": \([0-9.]*\).*/\1/' <<< "$light"), "far": $far, "depth": "linear" }
JSON
  "$lv" shadowmap "$obj" --light "$work/omni.json" --size "$omni_size" --out "$work/omni_{face}.exr" --quiet
  oe=$(awk -v e="$bound" -v f="$far" 'BEGIN { printf "%.9g", e * f }')
  for t in collapse quadtree; do
    runs $t || continue
    if ! timed "$lv" build "$work/omni_{face}.exr" --light "$work/omni.json" --adaptive \
      --max-error "$oe" --tessellation $t --out "$work/v.ply" --report "$work/r.json" --quiet \
      2> "$work/err"; then
      printf '| %s omni | lightvol %s | %s | (build failed: %s) |||||||\n' "$scene" "$t" "$oe" \
        "$(head -c 160 "$work/err")"
      continue
    fi
    read -r tris reached angle < <(python3 -c '
import json, sys
a = json.load(open(sys.argv[1]))["adaptive"]
print(a["grid_triangles"], "%.6g" % a["max_error_reached"], a["min_angle_degrees"])' "$work/r.json")
    printf '| %s omni 6×%s² (world) | lightvol %s | %s | %s | %s | – | %s s | %s s | %s MB | %.4g° |\n' "$scene" \
      "$omni_size" "$t" "$oe" "$tris" "$reached" "$wall" "$cpu" "$mem" "$angle"
  done
done

[ -n "$upsampled" ] || exit 0
# Upsampled maps: one table, then the wall-time ratios to the first size.
upsampled_row() {  # label n
  local label=$1 n=$2
  awk -v n="$n" 'BEGIN { s = n - 1; printf "{\"type\": \"directional\", \"position\": [0, 0, 0], \"direction\": [0, 0, -1], \"up\": [0, 1, 0], \"ortho\": [%.17g, %.17g, %.17g, %.17g], \"near\": 0, \"far\": 1, \"depth\": \"linear\"}\n", -0.5 / s, (s + 0.5) / s, -(s + 0.5) / s, 0.5 / s }' > "$work/light.json"
  for t in collapse quadtree; do
    runs $t || continue
    if ! timed "$lv" build "$work/map.exr" --light "$work/light.json" --adaptive --max-error "$bound" \
      --tessellation $t --out "$work/v.ply" --report "$work/r.json" --quiet 2> "$work/err"; then
      printf '| %s | lightvol %s | (build failed: %s) ||||||\n' "$label $n²" "$t" "$(head -c 160 "$work/err")"
      continue
    fi
    read -r tris reached rounds balance < <(python3 -c '
import json, sys
a = json.load(open(sys.argv[1]))["adaptive"]
print(a["grid_triangles"], "%.6g" % a["max_error_reached"], a["fixup_rounds"], "%.3f" % a["seconds"]["balance"])' "$work/r.json")
    printf '| %s | lightvol %s | %s | %s | %s | %s s | %s s | %s s | %s MB |\n' "$label $n²" "$t" "$tris" \
      "$reached" "$rounds" "$balance" "$wall" "$cpu" "$mem"
    echo "$label|$t|$n|$wall" >> "$work/walls"
  done
}
echo
echo "Upsampled maps, E = $bound; $(nproc) cores; load $(cut -d' ' -f1-3 /proc/loadavg)"
printf '| map | mesher | triangles | max error reached | fix-up rounds | balance | wall | CPU | peak memory |\n'
printf '|---|---|---:|---:|---:|---:|---:|---:|---:|\n'
: > "$work/walls"
obj="$scenes/sponza/sponza.obj"
if [ -f "$obj" ]; then
  cat > "$work/spot.json" <<JSON
{ "type": "spot", "position": [0, 14, -1], "direction": [0, -14, 4], "near": 0.5, "far": 40, "up": [1, 0, 0], "fov_y_deg": 90, "depth": "linear" }
JSON
  "$lv" shadowmap "$obj" --light "$work/spot.json" --size 1024 --out "$work/shadow.exr" --quiet
  "$tool" from "$work/shadow.exr" 1024 0.025 "$work/sponza1024.exr" "$work/map.f32"
  for n in $upsampled; do
    "$tool" upsample "$work/sponza1024.exr" $((n / 1024)) "$work/map.exr" "$work/map.f32"
    upsampled_row "Sponza spot 1024² (depth/far) upsampled to" "$n"
  done
else
  echo "(no $obj: the upsampled Sponza map skipped)" >&2
fi
for n in $upsampled; do
  "$tool" steps "$n" "$work/map.exr" "$work/map.f32"
  upsampled_row "steps" "$n"
done
rm -f "$work/map.exr" "$work/map.f32" "$work/v.ply"
echo
awk -F'|' '{ key = $1 " (" $2 ")"; if (!(key in first)) { first[key] = $4; size[key] = $3 }
             else printf "%s: wall %s² / %s² = %.2f\n", key, $3, size[key], $4 / first[key] }' "$work/walls"
