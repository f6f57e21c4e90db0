#!/usr/bin/env bash
# The default (checked) static build against other builds of lightvol, in alternating rounds on
# the same synthetic spot maps (make_depth), with the I/O floor of each size measured in every
# round: medians of wall time, user+sys CPU and peak resident size, and the load average before
# each size. For changes whose effect is smaller than what other jobs on the machine do to one run:
# alternating runs see the same load. Two floors: `dd` in 1 MiB blocks (what writing the bytes
# costs at least) and the command the scale targets were first measured against (`head -c` from
# /dev/zero, 8 KiB writes); and BUILD_DIR's unchecked (streamed) build, the build's own least. The output file is removed before every run (a rename over
# last run's 637 MB would add its freeing to the run), and the outputs of all builds are compared.
# Usage: tests/bench/checked_build_pairs.sh BUILD_DIR OTHER_BUILD_DIR[:OTHER...] [ROUNDS] [SIZES...]
#        (BUILD_DIR configured with -DLIGHTVOL_BUILD_BENCH=ON; an OTHER needs only lightvol and
#        lightvol-image; default 5 rounds, sizes 1024 2048 4096)
set -euo pipefail
build=$(realpath "${1:?usage: checked_build_pairs.sh BUILD_DIR OTHER_BUILD_DIR[:OTHER...] [ROUNDS] [SIZES...]}")
IFS=: read -r -a others <<< "${2:?usage: checked_build_pairs.sh BUILD_DIR OTHER_BUILD_DIR[:OTHER...] [ROUNDS] [SIZES...]}"
builds=()
for o in "${others[@]}"; do builds+=("$(realpath "$o")"); done
builds+=("$build")
rounds=${3:-5}
shift $(($# < 3 ? $# : 3))
sizes=("$@")
[ ${#sizes[@]} -gt 0 ] || sizes=(1024 2048 4096)
source "$(dirname "$0")/bench_common.sh"
# The light of docs/performance.md's scale targets (the eye at the origin, looking down −Z).
echo '{"type": "spot", "position": [0,0,0], "direction": [0,0,-1], "up": [0,1,0], "fov_y_deg": 60, "near": 0.5, "far": 20, "depth": "window"}' > "$work/spot.json"

# timed TAG COMMAND...: one run under /usr/bin/time, its "wall cpu peak_kib" appended to $work/TAG.
timed() {
  /usr/bin/time -f '%e %U %S %M' -o "$work/t" "${@:2}"
  read -r wall user sys rss < "$work/t"
  echo "$wall $(echo "$user + $sys" | bc -l) $rss" >> "$work/$1"
}
# one LIGHTVOL TAG [FLAGS...]: the build of the map into $work/v.ply, timed.
one() {
  rm -f "$work/v.ply"
  timed "$2" "$1" build "$work/d.exr" --light "$work/spot.json" --out "$work/v.ply" -q "${@:3}"
}
walls() { awk '{ printf "%s%s", (NR > 1 ? " " : ""), $1 }' "$work/$1"; }
col() { awk -v c="$2" '{ print $c }' "$work/$1" | median; }
# row LOAD LABEL TAG: the medians of TAG's runs at map size $n, with their peak.
row() {
  printf '| %d² | %s | %s | %.2f s | %.2f s | %.1f MiB | %s |\n' "$n" "$1" "$2" "$(col "$3" 1)" \
    "$(col "$3" 2)" "$(echo "$(col "$3" 3) / 1024" | bc -l)" "$(walls "$3")"
}

printf '| map | load (1 min) | build | wall | user+sys | peak RSS | walls of the runs |\n|---|---|---|---:|---:|---:|---|\n'
for n in "${sizes[@]}"; do
  "$build/tests/bench/make_depth" "$n" "$n" "$work/d.exr"
  load=$(cut -d' ' -f1 /proc/loadavg)
  rm -f "$work"/t_* "$work/floor_t" "$work/head_t" "$work/nocheck_t"
  for ((i = 0; i < rounds; i++)); do
    for k in "${!builds[@]}"; do
      one "${builds[$k]}/lightvol" "t_$k"
      # Compared by hash and removed at once: no run writes beside another's 637 MB.
      sum=$(md5sum < "$work/v.ply")
      [ "$k" -eq 0 ] && first=$sum
      [ "$sum" = "$first" ] || { echo "$n²: the outputs differ" >&2; exit 1; }
      bytes=$(stat -c %s "$work/v.ply")
      rm -f "$work/v.ply"
    done
    one "$build/lightvol" nocheck_t --no-check
    rm -f "$work/v.ply"
    timed floor_t sh -c "cat '$work/d.exr' > /dev/null; dd if=/dev/zero of='$work/floor' bs=1M count=$(( (bytes + 1048575) / 1048576 )) status=none"
    rm -f "$work/floor"
    timed head_t sh -c "cat '$work/d.exr' > /dev/null; head -c $bytes /dev/zero > '$work/floor'"
    rm -f "$work/floor"
  done
  for k in "${!builds[@]}"; do row "$load" "${builds[$k]}" "t_$k"; done
  row "" "$build --no-check (streamed)" nocheck_t
  printf '| %d² | | I/O floor: cat EXR + dd %s MB (1 MiB writes) | %.2f s | %.2f s | | %s |\n' "$n" \
    "$(( bytes / 1000000 ))" "$(col floor_t 1)" "$(col floor_t 2)" "$(walls floor_t)"
  printf '| %d² | | I/O floor: cat EXR + head -c %s MB (8 KiB writes) | %.2f s | %.2f s | | %s |\n' \
    "$n" "$(( bytes / 1000000 ))" "$(col head_t 1)" "$(col head_t 2)" "$(walls head_t)"
  rm -f "$work/d.exr"
done
echo "load average at the end: $(cut -d' ' -f1-3 /proc/loadavg)"
