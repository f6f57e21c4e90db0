#!/usr/bin/env bash
# Installs what lightvol needs to build and test on Debian bookworm (as root, or through sudo).
set -euo pipefail
packages=(
  build-essential cmake ninja-build pkg-config git time bc python3
  libopenmesh-dev libdraco-dev libtinygltf-dev libopenimageio-dev openimageio-tools
  libcgal-dev libeigen3-dev libgmp-dev libmpfr-dev libtbb-dev libxxhash-dev
  libopenvdb-dev  # OpenVDB density grids (lightvol-image reads them)
  libopenexr-dev  # OpenEXR's C core: lightvol-exr, the fast reader of plain EXR depth maps
  libdeflate-dev  # lightvol-exr inflates ZIP-compressed EXR chunks with it (optional: else zlib)
  python3-openvdb  # the density tests write their OpenVDB files with it (/usr/bin/python3)
  parallel  # lightvol batch --shard across hosts, in its test
  nlohmann-json3-dev libcli11-dev
  libegl-dev libgl-dev libegl-mesa0 libgl1-mesa-dri
  libgtest-dev libgmock-dev libbenchmark-dev
  clang libclang-rt-14-dev clang-format
  chromium  # the web viewer's browser test (headless, SwiftShader's WebGL2)
  blender python3-numpy  # a real client of the GLB (its glTF importer needs numpy)
)
# Node.js for the web viewer's tests (Khronos' glTF validator, puppeteer-core): Debian's, unless a
# node is installed already (e.g. from NodeSource, whose nodejs package brings its own npm).
command -v node >/dev/null || packages+=(nodejs npm)
sudo=""
[ "$(id -u)" -eq 0 ] || sudo="sudo"
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "installing: ${missing[*]}"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# The npm packages of web/ (package-lock.json): three.js, Khronos' glTF validator, puppeteer-core.
# Installed as the invoking user, again only when the lock file is newer than what is installed.
web="$(cd "$(dirname "$0")/.." && pwd)/web"
if [ ! -f "$web/node_modules/.package-lock.json" ] ||
   [ "$web/package-lock.json" -nt "$web/node_modules/.package-lock.json" ]; then
  echo "installing web/'s npm packages (npm ci)"
  (cd "$web" && npm ci --no-audit --no-fund --loglevel=error >/dev/null)
fi
