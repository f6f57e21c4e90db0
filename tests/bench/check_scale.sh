#!/usr/bin/env bash
# What the check costs at scale: for synthetic 2048² and 4096² spot maps, a default `build`
# (which checks the volume before writing it), `build --no-check`, and `check --light` of the
# binary PLY that build wrote; whole process under /usr/bin/time: user+sys CPU, wall, peak memory
# (max RSS). With a second build folder, both versions run alternately and the table has a row
# for each. One run each by default (the machine is shared: compare CPU and peak memory first).
# Usage: tests/bench/check_scale.sh BUILD_DIR [OTHER_BUILD_DIR] [RUNS] [SIZES]
#   (BUILD_DIR configured with -DLIGHTVOL_BUILD_BENCH=ON for make_depth), e.g.
#   tests/bench/check_scale.sh build                       # this version
#   tests/bench/check_scale.sh build /tmp/main-build 3     # against another, medians of 3
set -euo pipefail
build=$(realpath "${1:?usage: check_scale.sh BUILD_DIR [OTHER_BUILD_DIR] [RUNS] [SIZES]}")
other=${2:-}
[ -n "$other" ] && other=$(realpath "$other")
runs=${3:-1}
sizes=${4:-"2048 4096"}
source "$(dirname "$0")/bench_common.sh"
# measure LABEL FILE-PREFIX COMMAND...: appends "cpu wall rss" of one run to PREFIX.
measure() {
  local out=$1; shift
  /usr/bin/time -f '%U %S %e %M' -o "$work/t" "$@" > /dev/null
  read -r user sys wall rss < "$work/t"
  echo "$(echo "$user + $sys" | bc -l) $wall $rss" >> "$out"
}
versions=("$build")
[ -n "$other" ] && versions+=("$other")
printf '| map | triangles | version | command | CPU user+sys | wall | peak memory |\n'
printf '|---|---|---|---|---|---|---|\n'
for n in $sizes; do
  "$build/tests/bench/make_depth" "$n" "$n" "$work/d$n.exr"
  "$build/lightvol" build "$work/d$n.exr" --light "$work/spot.json" --out "$work/v$n.ply" --quiet
  tris=$(head -c 400 "$work/v$n.ply" | grep -a '^element face' | awk '{print $3}')
  for j in "${!versions[@]}"; do for c in build nocheck check; do : > "$work/v$j.$c"; done; done
  for ((i = 0; i < runs; i++)); do
    for j in "${!versions[@]}"; do
      v=${versions[$j]} tag=$work/v$j
      rm -f "$work/out.ply"
      measure "$tag.build" "$v/lightvol" build "$work/d$n.exr" --light "$work/spot.json" --out "$work/out.ply" --quiet
      rm -f "$work/out.ply"
      measure "$tag.nocheck" "$v/lightvol" build "$work/d$n.exr" --light "$work/spot.json" --out "$work/out.ply" --quiet --no-check
      measure "$tag.check" "$v/lightvol" check "$work/v$n.ply" --light "$work/spot.json" --quiet
    done
  done
  for j in "${!versions[@]}"; do
    v=${versions[$j]} tag=$work/v$j
    for c in build nocheck check; do
      case $c in
        build) label='`build`' ;;
        nocheck) label='`build --no-check`' ;;
        check) label='`check v.ply --light`' ;;
      esac
      printf '| %d² | %s | %s | %s | %.2f s | %.2f s | %.0f MiB |\n' "$n" "$tris" "$v" "$label" \
        "$(cut -d' ' -f1 "$tag.$c" | median)" "$(cut -d' ' -f2 "$tag.$c" | median)" \
        "$(echo "$(cut -d' ' -f3 "$tag.$c" | median) / 1024" | bc -l)"
    done
  done
done
