#!/usr/bin/env bash
# Configures (once) and builds the fuzzing tree: clang 14, SCANPLAN_FUZZ=ON, no unit tests,
# -O1 with debug info and assertions on; warnings as errors when CI=true. Incremental.
# Usage: tests/fuzz/build.sh [SOURCE_DIR [BUILD_DIR]]   (default: the repo, SOURCE_DIR/build-fuzz)
set -euo pipefail
src=$(cd "${1:-$(dirname "$0")/../..}" && pwd)
dir=${2:-$src/build-fuzz}
extra=()
[ "${CI:-}" = "true" ] && extra+=(-DSCANPLAN_WERROR=ON)
if [ ! -f "$dir/CMakeCache.txt" ]; then
  cmake -S "$src" -B "$dir" -G Ninja -DCMAKE_CXX_COMPILER=clang++-14 -DCMAKE_BUILD_TYPE=Debug \
    "-DCMAKE_CXX_FLAGS_DEBUG=-O1 -g" -DSCANPLAN_FUZZ=ON -DSCANPLAN_BUILD_TESTS=OFF \
    "${extra[@]}" >/dev/null
elif ((${#extra[@]})); then
  cmake -S "$src" -B "$dir" "${extra[@]}" >/dev/null
fi
cmake --build "$dir" --parallel "$(nproc 2>/dev/null || echo 2)"
