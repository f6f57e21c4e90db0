#!/usr/bin/env bash
# lightvol's self-intersection and bounds-a-volume tests against CGAL's on N generated meshes
# (default 10,000; ctest runs 300 of them): the same refusals, pairs, components and verdicts.
# Usage: tests/check/self_intersection_all.sh BUILD_DIR [N]
set -euo pipefail
build=$(realpath "${1:?usage: self_intersection_all.sh BUILD_DIR [N]}")
LIGHTVOL_SI_MESHES=${2:-10000} "$build/tests/self_intersection_tests" \
  --gtest_filter='ExactSelfIntersections.GeneratedMeshesGiveCgalsPairs'
