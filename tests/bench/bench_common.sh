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
