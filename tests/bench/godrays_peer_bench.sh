#!/usr/bin/env bash
# lightvol's live volume (web/live.html, LightVolume) against three-good-godrays 0.11.2 in one
# headless chromium on SwiftShader, one run, one table (docs/performance.md). The peer, three 0.182.0
# and postprocessing 6.39.6 are installed with npm into a scratch folder outside the source tree
# (PEER_DIR, default /tmp/lightvol-peer); the web viewer's own modules must be in web/node_modules.
# Usage: tests/bench/godrays_peer_bench.sh BUILD_DIR [--frames N] [--demo-size N] [--map N] [--omni-map N]
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
build=$(realpath "${1:?usage: godrays_peer_bench.sh BUILD_DIR [OPTIONS]}")
shift
exec node "$here/godrays_peer_bench.mjs" "$build/lightvol" "$@"
