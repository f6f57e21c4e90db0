#!/usr/bin/env bash
# GNU parallel spreads `lightvol batch JOBS --shard {}/3` over two "hosts" with --sshlogin, as
# docs/batch.md shows. The hosts are this machine: parallel's --ssh names a stand-in for ssh that
# runs the command it is given here, so parallel's remote path (its quoting of the command for the
# remote shell, one slot per host) is still what runs; the paths hold a space (hence --quote).
# Asserts: every shard exits 0; the shards' result lines together name every job exactly once,
# each in its shard (job i in shard i mod 3); every output exists and passes `lightvol check`;
# both hosts ran shards; a second run skips every job.
# Usage: tests/cli/batch_parallel_test.sh LIGHTVOL_EXE (exit 77: GNU parallel is not installed)
set -euo pipefail
exe=$(realpath "${1:?usage: batch_parallel_test.sh LIGHTVOL_EXE}")
data=$(cd "$(dirname "$0")/../../data" && pwd)
command -v parallel > /dev/null || { echo "GNU parallel is not installed (apt package parallel)"; exit 77; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
work="$tmp/batch work"
mkdir -p "$work/out"
cp "$data/synthetic_256.exr" "$data/spot_light.json" "$data/directional_light.json" "$work/"

# The ssh stand-in: ssh [OPTIONS] HOST [--] COMMAND...; sshd would join COMMAND's words with spaces
# and give them to the login shell, so this does the same here, and logs the host. sshd also sets
# SHELL to the login shell, which parallel's remote worker runs the command with (under an
# environment without SHELL, as CI's may be, the worker would silently run nothing).
cat > "$tmp/ssh-here" <<EOF
#!/usr/bin/env bash
SHELL=\$(getent passwd "\$(id -u)" | cut -d: -f7)
export SHELL=\${SHELL:-/bin/sh}
while [ \$# -gt 0 ]; do
  case "\$1" in
    --) shift; break ;;
    -[bcDEeFIiJLlmOoPpQRSWw]) shift 2 ;;  # options that take a value
    -*) shift ;;
    *) break ;;
  esac
done
host=\$1; shift
[ "\${1:-}" = "--" ] && shift
echo "\$host" >> "$tmp/hosts.log"
exec bash -c "\$*"
EOF
chmod +x "$tmp/ssh-here"

# Nine jobs: static and adaptive, spot and directional, several formats.
formats=(ply glb obj off stl drc ply glb obj)
for i in $(seq 0 8); do
  light=spot_light.json; [ $((i % 4)) -eq 3 ] && light=directional_light.json
  args='[]'; [ $((i % 2)) -eq 1 ] && args='["--adaptive", "--max-error", "0.01"]'
  printf '{"id": "job %d", "inputs": ["synthetic_256.exr"], "light": "%s", "out": "out/v%d.%s", "args": %s}\n' \
    "$i" "$light" "$i" "${formats[$i]}" "$args" >> "$work/jobs.jsonl"
done

run_shards() {
  parallel --will-cite --quote --ssh "$tmp/ssh-here" --sshlogin 1/hostA,1/hostB \
    "$exe" batch "$work/jobs.jsonl" --shard {}/3 --quiet --results "$work/results{}.jsonl" ::: 0 1 2
}
run_shards

python3 - "$work" <<'PY'
import json, sys
work = sys.argv[1]
seen = {}
for k in range(3):
    for text in open(f"{work}/results{k}.jsonl"):
        r = json.loads(text)
        job = r["line"] - 1
        assert job % 3 == k, f"job {job} ran in shard {k}"
        assert r["status"] == "ok", r
        seen[job] = seen.get(job, 0) + 1
assert sorted(seen) == list(range(9)), f"jobs run: {sorted(seen)}"
assert all(n == 1 for n in seen.values()), f"runs per job: {seen}"
PY

for i in $(seq 0 8); do
  light=spot_light.json; [ $((i % 4)) -eq 3 ] && light=directional_light.json
  out=$(ls "$work/out/v$i".* | grep -v report)
  "$exe" check "$out" --light "$work/$light" --quiet || { echo "FAIL: $out does not pass check"; exit 1; }
done
[ "$(ls "$work/out" | grep -vc report)" -eq 9 ] || { echo "FAIL: not exactly 9 outputs"; ls "$work/out"; exit 1; }
grep -qx hostA "$tmp/hosts.log" && grep -qx hostB "$tmp/hosts.log" ||
  { echo "FAIL: the shards did not run on both hosts:"; cat "$tmp/hosts.log"; exit 1; }

# Again: every job is skipped.
run_shards
skipped=$(cat "$work"/results?.jsonl | python3 -c 'import json, sys; print(sum(json.loads(l)["status"] == "skipped" for l in sys.stdin))')
[ "$skipped" -eq 9 ] || { echo "FAIL: $skipped of 9 jobs skipped on the second run"; exit 1; }
echo "batch_parallel_test: 9 jobs in 3 shards on 2 hosts, each once, all checked; rerun skipped all"
