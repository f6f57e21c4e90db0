#!/usr/bin/env bash
# lightvol's self-intersection test against CGAL's own parallel one
# (PMP::does_self_intersect<Parallel_if_available_tag>) on the same in-memory volume: the static
# volume of the synthetic 1024² spot map, 2,097,150 triangles (check_bench's volume_1024). One run
# of the script: lightvol's test (5 iterations), CGAL's (one iteration, stopped after LIMIT
# seconds), lightvol's again, each in its own check_bench process under /usr/bin/time. Prints the
# wall time of one test (Google Benchmark's real time; for a stopped CGAL run, the LIMIT it did not
# finish in), the process's CPU (user + sys, which includes building the volume once, about the
# same for both), and CGAL / lightvol. A stopped run gives a lower bound, marked ">".
# Usage: tests/bench/cgal_parallel_ratio.sh BUILD_DIR [LIMIT_SECONDS=300]
#   (BUILD_DIR configured with -DLIGHTVOL_BUILD_BENCH=ON)
set -euo pipefail
build=$(realpath "${1:?usage: cgal_parallel_ratio.sh BUILD_DIR [LIMIT_SECONDS]}")
limit=${2:-300}
bench="$build/tests/bench/check_bench"
[ -x "$bench" ] || { echo "no $bench: configure with -DLIGHTVOL_BUILD_BENCH=ON" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# real_time JSON: Google Benchmark's real time of the file's first benchmark, in seconds.
real_time() {
  python3 -c 'import json, sys
b = json.load(open(sys.argv[1]))["benchmarks"][0]
if b.get("error_occurred"): sys.exit("check_bench: " + b.get("error_message", "error"))
print(b["real_time"] / 1000)' "$1"
}
# ours NAME: lightvol's test; sets wall (seconds per test) and cpu (the process's user + sys).
ours() {
  /usr/bin/time -f '%U %S' -o "$work/$1.time" "$bench" --benchmark_filter='^BM_LightvolSelfIntersection/' \
    --benchmark_out="$work/$1.json" --benchmark_out_format=json > /dev/null 2> "$work/$1.err" ||
    { cat "$work/$1.err" >&2; exit 1; }
  wall=$(real_time "$work/$1.json")
  cpu=$(awk '{print $1 + $2}' "$work/$1.time")
}

printf 'load at start: %s\n\n' "$(uptime)"
ours ours1
ours1=$wall; ours1_cpu=$cpu
# CGAL's run: its CPU is sampled from /proc every second, so a run stopped at LIMIT still reports
# what it used.
(
  rc=0
  timeout -s KILL "$limit" "$bench" --benchmark_filter='^BM_CgalPmpParallelSelfIntersection/' \
    --benchmark_out="$work/cgal.json" --benchmark_out_format=json > /dev/null 2>&1 || rc=$?
  echo "$rc" > "$work/cgal.rc"
) 2> /dev/null &
sleep 0.2
pid=$(pgrep -n -f 'check_bench --benchmark_filter=\^BM_CgalPmp' || true)
ticks=$(getconf CLK_TCK)
cgal_cpu=0
start=$(date +%s.%N)
while [ ! -f "$work/cgal.rc" ]; do
  if [ -n "$pid" ] && [ -r "/proc/$pid/stat" ]; then
    cgal_cpu=$(awk -v t="$ticks" '{print ($14 + $15) / t}' "/proc/$pid/stat" 2> /dev/null || echo "$cgal_cpu")
  fi
  sleep 1
done
elapsed=$(echo "$(date +%s.%N) - $start" | bc -l)
if [ "$(cat "$work/cgal.rc")" -eq 0 ]; then
  cgal=$(real_time "$work/cgal.json")
  mark=""
else
  cgal=$limit; mark=">"
fi
ours ours2
ours2=$wall; ours2_cpu=$cpu
ours=$(printf '%s\n%s\n' "$ours1" "$ours2" | sort -g | tail -1)  # the slower of the two
printf '| test | wall per test | process CPU (user+sys) |\n|---|---:|---:|\n'
printf '| lightvol (before CGAL) | %.3f s | %.2f s (5 tests) |\n' "$ours1" "$ours1_cpu"
printf '| CGAL parallel | %s%.1f s | %s%.1f s (1 test%s) |\n' "$mark" "$cgal" "$mark" "$cgal_cpu" \
  "$([ -n "$mark" ] && echo ", stopped after $(printf '%.0f' "$elapsed") s")"
printf '| lightvol (after CGAL) | %.3f s | %.2f s (5 tests) |\n' "$ours2" "$ours2_cpu"
printf '| CGAL / lightvol (slower lightvol run) | %s%.0fx | |\n' "$mark" "$(echo "$cgal / $ours" | bc -l)"
printf '\nload at end: %s\n' "$(uptime)"
