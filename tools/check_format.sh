#!/usr/bin/env bash
# Fails (exit 1) on any C++ source of src/, cli/ or tests/ that clang-format (.clang-format) would
# change, naming the files. To fix: tools/check_format.sh --fix
set -euo pipefail
cd "$(dirname "$0")/.."
mapfile -t files < <(find src cli tests \( -name '*.cpp' -o -name '*.h' \) -not -path '*/corpus/*' | sort)
if [ "${1:-}" = "--fix" ]; then
  clang-format -i "${files[@]}"
  exit 0
fi
bad=()
for f in "${files[@]}"; do
  clang-format --dry-run --Werror "$f" > /dev/null 2>&1 || bad+=("$f")
done
if [ ${#bad[@]} -gt 0 ]; then
  printf '%s: not formatted as .clang-format says\n' "${bad[@]}"
  echo "check_format: ${#bad[@]} file(s); run tools/check_format.sh --fix"
  exit 1
fi
echo "check_format: ${#files[@]} files follow .clang-format"
