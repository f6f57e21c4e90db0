#!/usr/bin/env bash
# The web viewer in headless chromium (SwiftShader's WebGL2) against `lightvol render --method
# volume`: static, adaptive, Draco and omni volumes of the bundled scene, relative L2 <= 1 %
# (web/tests/browser_test.mjs says how). Usage: browser_test.sh PATH/TO/lightvol [options...]
# Needs node, chromium, oiiotool and web/node_modules (tools/install-deps.sh installs them).
set -euo pipefail
exe=$(realpath "${1:?usage: browser_test.sh PATH/TO/lightvol}")
shift
root=$(cd "$(dirname "$0")/../.." && pwd)
command -v node >/dev/null || { echo "node is missing: run tools/install-deps.sh" >&2; exit 1; }
[ -x "${CHROMIUM:-/usr/bin/chromium}" ] || { echo "chromium is missing: run tools/install-deps.sh" >&2; exit 1; }
[ -d "$root/web/node_modules/puppeteer-core" ] ||
  { echo "web/node_modules is missing: run tools/install-deps.sh" >&2; exit 1; }
exec node "$root/web/tests/browser_test.mjs" "$exe" "$@"
