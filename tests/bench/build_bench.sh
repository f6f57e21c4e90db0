#!/usr/bin/env bash
# Static spot builds from 1024², 2048² and 4096² EXR maps to binary PLY: median wall time and peak
# memory over RUNS runs, with the time of each stage (from --report) and, as a floor for "just
# reading the EXR and writing the file", the time of `cat` reading the EXR and writing a copy of
# the PLY through the page cache.
# Usage: tests/bench/build_bench.sh BUILD_DIR [RUNS] [EXTRA BUILD FLAGS...]
#   (BUILD_DIR configured with -DLIGHTVOL_BUILD_BENCH=ON), e.g. ... build 5 --no-check
set -euo pipefail
build=$(realpath "${1:?usage: build_bench.sh BUILD_DIR [RUNS]}")
runs=${2:-5}
shift $(( $# < 2 ? $# : 2 ))
extra=("$@")
source "$(dirname "$0")/bench_common.sh"
printf '| map | triangles | wall (median of %d) | read | build | check | write | peak memory | cat EXR + PLY |\n' "$runs"
printf '|---|---|---|---|---|---|---|---|---|\n'
for n in 1024 2048 4096; do
  "$build/tests/bench/make_depth" "$n" "$n" "$work/d$n.exr"
  : > "$work/wall"; : > "$work/rss"; : > "$work/read"; : > "$work/build"; : > "$work/write"; : > "$work/check"; : > "$work/cp"
  for ((i = 0; i < runs; i++)); do
    rm -f "$work/v.ply"
    /usr/bin/time -f '%e %M' -o "$work/t" "$build/lightvol" build "$work/d$n.exr" --light "$work/spot.json" \
      --out "$work/v.ply" --quiet --report "$work/r.json" "${extra[@]}"
    read -r wall rss < "$work/t"
    echo "$wall" >> "$work/wall"; echo "$rss" >> "$work/rss"
    python3 - "$work" <<'PY'
import json, sys
w = sys.argv[1]; r = json.load(open(w + "/r.json"))
stage = {s["name"]: s["seconds"] for s in r["stages"]}
def get(prefix): return sum(v for k, v in stage.items() if k.startswith(prefix))
for name, prefix in (("read", "reading " + w + "/d"), ("build", "building"), ("check", "checking"), ("write", "writing")):
    open(w + "/" + name, "a").write("%f\n" % get(prefix))
open(w + "/tris", "w").write(str(r["triangles"]))
PY
    sync
    /usr/bin/time -f '%e' -o "$work/t2" sh -c "cat '$work/d$n.exr' > /dev/null; cat '$work/v.ply' > '$work/copy.ply'"
    cat "$work/t2" >> "$work/cp"; rm -f "$work/copy.ply"
  done
  printf '| %d² | %s | %.2f s | %.2f s | %.2f s | %.2f s | %.2f s | %.0f MiB | %.2f s |\n' "$n" "$(cat "$work/tris")" \
    "$(median < "$work/wall")" "$(median < "$work/read")" "$(median < "$work/build")" "$(median < "$work/check")" \
    "$(median < "$work/write")" "$(echo "$(median < "$work/rss") / 1024" | bc -l)" "$(median < "$work/cp")"
done
