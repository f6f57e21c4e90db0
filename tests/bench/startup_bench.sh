#!/usr/bin/env bash
# Startup: what a command costs before it does its work. For each case, RUNS runs (default 20),
# median wall time, median user+sys CPU (lightvol and the lightvol-image it started) and median
# peak memory; with a second build directory, its runs alternate with the first's and the table
# has both and their ratio. Then the `read` stage (from build --report) of 4096² and 8192² EXR
# maps (BIG_RUNS runs each, default 3; builds with --no-check).
# Usage: tests/bench/startup_bench.sh BUILD_DIR [BASELINE_BUILD_DIR]
#   (BUILD_DIR configured with -DLIGHTVOL_BUILD_BENCH=ON: make_depth writes the maps);
#   RUNS=20 BIG_RUNS=3 SIZES="4096 8192" in the environment change the counts and the big maps.
set -euo pipefail
a=$(realpath "${1:?usage: startup_bench.sh BUILD_DIR [BASELINE_BUILD_DIR]}")
b=${2:+$(realpath "$2")}
runs=${RUNS:-20}
big_runs=${BIG_RUNS:-3}
sizes=${SIZES:-4096 8192}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
cat > spot.json <<'JSON'
{"type": "spot", "position": [0, 10, 0], "direction": [0, -1, 0], "up": [0, 0, -1],
 "fov_y_deg": 60, "near": 1, "far": 20}
JSON
"$a/tests/bench/make_depth" 64 64 d64.exr
"$a/lightvol" build d64.exr --light spot.json --out small.ply --quiet
median() { sort -g | awk '{a[NR]=$1} END {print (NR%2 ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2)}'; }

# One run of `lightvol ARGS` from build $1, appended to $work/$2.{wall,cpu,rss}: wall time around
# the process and its user+sys time from wait4 (which include the lightvol-image it started and
# reaped), to the microsecond; peak RSS (the largest process's) from /usr/bin/time.
run() {
  python3 - "$@" <<'PY'
import os, subprocess, sys, time
build, tag, *args = sys.argv[1:]
with open("err", "w") as err:
    start = time.perf_counter()
    # Peak RSS from /usr/bin/time, a small process: a fork of this Python would carry its own
    # high-water mark into lightvol's.
    p = subprocess.Popen(["/usr/bin/time", "-f", "%M", "-o", "rss", build + "/lightvol", *args],
                         stdout=subprocess.DEVNULL, stderr=err)
    _, status, usage = os.wait4(p.pid, 0)
    wall = time.perf_counter() - start
if status != 0:
    sys.exit(open("err").read())
rss = int(open("rss").read().split()[-1])
for ext, value in (("wall", wall), ("cpu", usage.ru_utime + usage.ru_stime), ("rss", rss)):
    open(tag + "." + ext, "a").write("%.6f\n" % value)
PY
}
ms() { echo "$(median < "$1") * 1000" | bc -l; }
mib() { echo "$(median < "$1") / 1024" | bc -l; }

if [ -n "$b" ]; then
  printf '| command (median of %d) | wall | user+sys | peak RSS | baseline wall | baseline user+sys | baseline peak RSS | wall ratio |\n' "$runs"
  printf '|---|---|---|---|---|---|---|---|\n'
else
  printf '| command (median of %d) | wall | user+sys | peak RSS |\n' "$runs"
  printf '|---|---|---|---|\n'
fi
cases=("--version" "--help" "check small.ply" "build d64.exr --light spot.json --out v.ply --quiet")
for c in "${cases[@]}"; do
  rm -f A.* B.*
  read -ra args <<< "$c"
  for ((i = 0; i < runs; i++)); do
    run "$a" A "${args[@]}"
    [ -z "$b" ] || run "$b" B "${args[@]}"
  done
  if [ -n "$b" ]; then
    printf '| `lightvol %s` | %.1f ms | %.1f ms | %.1f MiB | %.1f ms | %.1f ms | %.1f MiB | %.2f |\n' "$c" \
      "$(ms A.wall)" "$(ms A.cpu)" "$(mib A.rss)" "$(ms B.wall)" "$(ms B.cpu)" "$(mib B.rss)" \
      "$(echo "$(median < A.wall) / $(median < B.wall)" | bc -l)"
  else
    printf '| `lightvol %s` | %.1f ms | %.1f ms | %.1f MiB |\n' "$c" "$(ms A.wall)" "$(ms A.cpu)" "$(mib A.rss)"
  fi
done

# The read stage of big maps: build --no-check --report, the seconds of "reading <map>".
read_stage() {
  python3 -c 'import json,sys; r=json.load(open("r.json")); print(sum(s["seconds"] for s in r["stages"] if s["name"]==sys.argv[1]))' "reading $work/$1"
}
echo
if [ -n "$b" ]; then
  printf '| map (median of %d) | read stage | build wall | user+sys | baseline read stage | baseline build wall | baseline user+sys |\n' "$big_runs"
  printf '|---|---|---|---|---|---|---|\n'
else
  printf '| map (median of %d) | read stage | build wall | user+sys |\n' "$big_runs"
  printf '|---|---|---|---|\n'
fi
for n in $sizes; do
  "$a/tests/bench/make_depth" "$n" "$n" "d$n.exr"
  rm -f A.* B.*
  for ((i = 0; i < big_runs; i++)); do
    for tag in A B; do
      build=$a; [ "$tag" = A ] || build=$b
      [ -n "$build" ] || continue
      run "$build" "$tag" build "$work/d$n.exr" --light spot.json --out v.ply --quiet --no-check --report r.json
      read_stage "d$n.exr" >> "$tag.read"
      rm -f v.ply
    done
  done
  if [ -n "$b" ]; then
    printf '| %d² | %.2f s | %.2f s | %.2f s | %.2f s | %.2f s | %.2f s |\n' "$n" "$(median < A.read)" \
      "$(median < A.wall)" "$(median < A.cpu)" "$(median < B.read)" "$(median < B.wall)" "$(median < B.cpu)"
  else
    printf '| %d² | %.2f s | %.2f s | %.2f s |\n' "$n" "$(median < A.read)" "$(median < A.wall)" "$(median < A.cpu)"
  fi
  rm -f "d$n.exr"
done
