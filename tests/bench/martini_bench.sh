#!/usr/bin/env bash
# lightvol's adaptive tessellation against Mapbox Martini (RTIN, @mapbox/martini 0.2.0) on the
# synthetic 1025² and 4097² shadow maps (floor, boxes, one-texel bars, a sphere; values in [0, 1]).
# Both get max error 0.001; lightvol uses a directional light with near 0, far 1 and linear depth, so
# world units along a texel ray are depth units, as Martini's heights are. The reached error of both
# meshes is measured by the same code (heightfield_tool error); Martini is also rerun at tighter
# bounds until it meets 0.001. Times: Martini's createTile + getMesh inside node; lightvol's whole
# `build` process (read EXR, tessellate, check, write PLY) and its tessellation stage alone.
# Usage: tests/bench/martini_bench.sh BUILD_DIR [SIZES]   (BUILD_DIR with -DLIGHTVOL_BUILD_BENCH=ON)
# Martini is installed with npm into a scratch folder under /tmp (never into the source tree).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
build=$(realpath "${1:?usage: martini_bench.sh BUILD_DIR [SIZES]}")
sizes=${2:-"1025 4097"}
bound=0.001
scratch=${MARTINI_DIR:-/tmp/lightvol-martini}
mkdir -p "$scratch"
if [ ! -d "$scratch/node_modules/@mapbox/martini" ]; then
  (cd "$scratch" && npm install --silent --no-audit --no-fund @mapbox/martini@0.2.0 >/dev/null)
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
tool="$build/tests/bench/heightfield_tool"

printf '| map | mesher | bound | triangles | reached max error | time |\n|---|---|---|---|---|---|\n'
for n in $sizes; do
  "$tool" map "$n" "$work/map.exr" "$work/map.f32"
  # Martini at the bound, then at tighter bounds until its measured error meets the bound.
  node "$here/martini_bench.js" "$scratch" "$work/map.f32" "$n" "$work/m" \
    $bound 0.0005 0.00025 0.000125 0.0000625 0.00003125 0.000015625 > "$work/martini.txt"
  i=0
  while read -r _ b _ tris _ tile _ mesh; do
    read -r _ _ _ reached _ uncovered < <("$tool" error "$work/map.f32" "$n" "$work/m$i.mrt")
    ms=$(awk -v a="$tile" -v b="$mesh" 'BEGIN { printf "%.0f ms (tile %.0f + mesh %.0f)", a + b, a, b }')
    if [ "$i" = 0 ] || awk -v r="$reached" -v e=$bound 'BEGIN { exit !(r <= e) }'; then
      printf '| %s² | Martini | %s | %s | %s | %s |\n' "$((n - 1))" "$b" "$tris" "$reached" "$ms"
    fi
    if [ "$i" != 0 ] && awk -v r="$reached" -v e=$bound 'BEGIN { exit !(r <= e) }'; then break; fi
    i=$((i + 1))
  done < "$work/martini.txt"
  # Texel (col, row) lies at world (col, −row): ortho left −0.5, right n − 0.5, bottom 0.5 − n, top 0.5.
  cat > "$work/light.json" <<JSON
{"type": "directional", "position": [0, 0, 0], "direction": [0, 0, -1], "up": [0, 1, 0],
 "ortho": [-0.5, $((n - 1)).5, -$((n - 1)).5, 0.5], "near": 0, "far": 1, "depth": "linear"}
JSON
  best=""
  for run in 1 2 3; do
    /usr/bin/time -f '%e' -o "$work/t" "$build/lightvol" build "$work/map.exr" --light "$work/light.json" \
      --adaptive --max-error $bound --out "$work/v.ply" --quiet --report "$work/r.json"
    wall=$(cat "$work/t")
    stage=$(python3 -c "import json,sys; r=json.load(open(sys.argv[1])); print([s['seconds'] for s in r['stages'] if s['name'].startswith('building')][0])" "$work/r.json")
    if [ -z "$best" ] || awk -v a="$wall" -v b="${best%% *}" 'BEGIN { exit !(a < b) }'; then best="$wall $stage"; fi
  done
  read -r _ tris _ reached _ uncovered < <("$tool" error "$work/map.f32" "$n" "$work/v.ply")
  read -r wall stage <<< "$best"
  printf '| %s² | lightvol --adaptive | %s | %s | %s | %.0f ms build process (tessellation %.0f ms) |\n' \
    "$((n - 1))" "$bound" "$tris" "$reached" "$(awk -v w="$wall" 'BEGIN { print w * 1000 }')" \
    "$(awk -v s="$stage" 'BEGIN { print s * 1000 }')"
done
