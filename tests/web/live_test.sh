#!/usr/bin/env bash
# The live page (web/live.html, web/light_volume.js) in headless chromium (SwiftShader's WebGL2):
# for a spot, a directional and an omni light, frames 0 and 30 of the animation against `lightvol
# render --method volume` of the volume `lightvol build` makes from the page's own shadow map and
# light, relative L2 <= 1 %; the bad-input messages (web/tests/live_test.mjs says how).
# Usage: live_test.sh PATH/TO/lightvol [options...]
# Needs node, chromium and web/node_modules (tools/install-deps.sh installs them).
set -euo pipefail
exe=$(realpath "${1:?usage: live_test.sh PATH/TO/lightvol}")
shift
root=$(cd "$(dirname "$0")/../.." && pwd)
command -v node >/dev/null || { echo "node is missing: run tools/install-deps.sh" >&2; exit 1; }
[ -x "${CHROMIUM:-/usr/bin/chromium}" ] || { echo "chromium is missing: run tools/install-deps.sh" >&2; exit 1; }
[ -d "$root/web/node_modules/puppeteer-core" ] ||
  { echo "web/node_modules is missing: run tools/install-deps.sh" >&2; exit 1; }
exec node "$root/web/tests/live_test.mjs" "$exe" "$@"
