#!/usr/bin/env bash
# Build time and peak memory from 1024² to 16384² synthetic spot maps (make_depth), one run per
# case: static default (checked), static --no-check (binary PLY: streamed row by row to the file)
# and adaptive --max-error 0.001, each with wall time, user+sys CPU, peak resident size and the
# memory estimate lightvol checks its budget against (read from the refusal under --max-memory 1K).
# The I/O floor of each size is measured in the same run: reading the EXR (cat) and writing a file
# of the static PLY's size (dd). A case the default budget refuses is shown as refused, with the
# estimate. Maps are made in TMPDIR (16384²: 1 GiB) and deleted at the end.
# Usage: tests/bench/scale_bench.sh BUILD_DIR [SIZES...]   (BUILD_DIR configured with
#        -DLIGHTVOL_BUILD_BENCH=ON; default sizes 1024 4096 8192 16384)
set -euo pipefail
build=$(realpath "${1:?usage: scale_bench.sh BUILD_DIR [SIZES...]}")
shift
sizes=("$@")
[ ${#sizes[@]} -gt 0 ] || sizes=(1024 4096 8192 16384)
source "$(dirname "$0")/bench_common.sh"
lv="$build/lightvol"
# KiB → "156.5 MiB" or "5.4 GiB", as lightvol prints sizes.
human() { awk -v k="$1" 'BEGIN { if (k < 1048576) printf "%.1f MiB", k / 1024; else printf "%.1f GiB", k / 1048576 }'; }

# The estimate: the "needs about X" of the refusal under a 1 KiB budget.
estimate() {
  { "$lv" --max-memory 1K "$@" --quiet 2>&1 >/dev/null || true; } | sed -n 's/.*needs about \([0-9.]* [KMGT]iB\).*/\1/p'
}

# case LABEL ARGS...: one run under /usr/bin/time; prints a table row.
run_case() {
  local n=$1 label=$2; shift 2
  local est; est=$(estimate "$@" || true)
  rm -f "$work/v.ply"
  if /usr/bin/time -f '%e %U %S %M' -o "$work/t" "$lv" "$@" --quiet 2> "$work/err"; then
    read -r wall user sys rss < "$work/t"
    printf '| %d² | %s | %.2f s | %.2f s | %s | %s |\n' "$n" "$label" "$wall" \
      "$(echo "$user + $sys" | bc -l)" "$(human "$rss")" "$est"
  else
    printf '| %d² | %s | refused: %s | | | %s |\n' "$n" "$label" \
      "$(sed -n 's/.*\(needs about [^;]*\);.*/\1/p' "$work/err" | head -1)" "$est"
  fi
}

printf '| map | case | wall | user+sys | peak RSS | estimate |\n|---|---|---|---|---|---|\n'
for n in "${sizes[@]}"; do
  "$build/tests/bench/make_depth" "$n" "$n" "$work/d.exr"
  common=(build "$work/d.exr" --light "$work/spot.json" --out "$work/v.ply")
  run_case "$n" "static --no-check (streamed PLY)" "${common[@]}" --no-check
  bytes=$(stat -c %s "$work/v.ply")
  sync
  /usr/bin/time -f '%e %U %S' -o "$work/t" sh -c \
    "cat '$work/d.exr' > /dev/null; dd if=/dev/zero of='$work/floor' bs=1M count=$(( (bytes + 1048575) / 1048576 )) status=none"
  read -r wall user sys < "$work/t"
  rm -f "$work/floor"
  printf '| %d² | I/O floor: cat EXR + dd %s MB | %.2f s | %.2f s | | |\n' "$n" \
    "$(( bytes / 1000000 ))" "$wall" "$(echo "$user + $sys" | bc -l)"
  run_case "$n" "static default (checked)" "${common[@]}"
  run_case "$n" "adaptive --max-error 0.001" "${common[@]}" --adaptive --max-error 0.001
  rm -f "$work/v.ply" "$work/d.exr"
done
