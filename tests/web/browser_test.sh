#!/usr/bin/env bash
# A browser test of web/ in headless chromium (SwiftShader's WebGL2), after checking that what it
# needs is installed:
#   browser_test.mjs  the viewer against `lightvol render --method volume`: static, adaptive, Draco,
#                     omni volumes and noise media (spot, omni) of the bundled scene, relative L2
#                     <= 1 %;
#   live_test.mjs     the live page (web/live.html, web/light_volume.js) for a spot, a directional
#                     and an omni light, frames 0 and 30 against `lightvol render --method volume` of
#                     the volume `lightvol build` makes from the page's own map and light, <= 1 %;
#   live_adaptive_test.mjs  the live page's adaptive volumes (live.html?adaptive=E): build's
#                     quadtree triangle count, the bound E at every texel, the airlight <= 1 %.
# Each script's header says how. Usage: browser_test.sh SCRIPT.mjs PATH/TO/lightvol [options...]
# Needs node, chromium, oiiotool and web/node_modules (tools/install-deps.sh installs them).
set -euo pipefail
script=${1:?usage: browser_test.sh SCRIPT.mjs PATH/TO/lightvol [options...]}
exe=$(realpath "${2:?usage: browser_test.sh SCRIPT.mjs PATH/TO/lightvol [options...]}")
shift 2
root=$(cd "$(dirname "$0")/../.." && pwd)
command -v node >/dev/null || { echo "node is missing: run tools/install-deps.sh" >&2; exit 1; }
[ -x "${CHROMIUM:-/usr/bin/chromium}" ] || { echo "chromium is missing: run tools/install-deps.sh" >&2; exit 1; }
[ -d "$root/web/node_modules/puppeteer-core" ] ||
  { echo "web/node_modules is missing: run tools/install-deps.sh" >&2; exit 1; }
exec node "$root/web/tests/$script" "$exe" "$@"
