#!/usr/bin/env bash
# Installs the Debian 12 packages scanplan needs (only the missing ones), then configures and
# builds Release into build/. Idempotent: quiet when everything is already there.
set -euo pipefail
cd "$(dirname "$0")"

packages=(
  cmake g++ ninja-build pkg-config
  libeigen3-dev libfcl-dev
  libompl-dev libboost-dev libboost-serialization-dev libboost-filesystem-dev libboost-system-dev
  libnlopt-dev libnlopt-cxx-dev libyaml-cpp-dev libembree-dev libnanoflann-dev libassimp-dev
  libcli11-dev libspdlog-dev libfmt-dev libtbb-dev libpng-dev nlohmann-json3-dev
  liburdfdom-dev libqhull-dev libglpk-dev
  # for tests: the function-length check reads the sources with Universal Ctags
  universal-ctags
  libgtest-dev libgmock-dev libcairo2-dev fonts-dejavu-core
  # the Python module and its tests
  python3-dev pybind11-dev python3-numpy python3-pytest
  # for tests: OMPL's ompl_benchmark_statistics reads `batch`'s log, GNU parallel runs shards
  ompl-demos parallel
)
# Web assets and the schema test's validator come from the npm registry (web/package.json):
# Debian's node and npm when the machine has no npm of its own.
command -v npm >/dev/null || packages+=(nodejs npm)
# CI also builds with the second compiler, and runs the fuzz tests with its libFuzzer (.ci/run).
# CI also runs the replay.html browser test in Debian's chromium and opens the clouds in the
# viewers users open them with: CloudCompare, MeshLab (under xvfb), Open3D and PCL's tools (each
# test skips where its tool is absent).
if [ "${CI:-}" = "true" ]; then
  packages+=(clang-14 libclang-rt-14-dev chromium python3-open3d cloudcompare meshlab xvfb xauth
             pcl-tools)
fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed'; then
    missing+=("$p")
  fi
done

if ((${#missing[@]})); then
  echo "bootstrap: installing ${missing[*]}"
  sudo_cmd=()
  if [ "$(id -u)" -ne 0 ]; then
    command -v sudo >/dev/null || { echo "bootstrap: need root or sudo to install packages" >&2; exit 1; }
    sudo_cmd=(sudo)
  fi
  export DEBIAN_FRONTEND=noninteractive
  "${sudo_cmd[@]}" apt-get update -qq >/dev/null
  "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# three.js (vendored into replay.html by the build), ajv and yaml (the job schema test), as
# web/package-lock.json pins them. Without the registry the build goes on: the schema test
# skips and plan writes no replay.html (it says so).
if [ ! -f web/node_modules/.package-lock.json ] || [ web/package-lock.json -nt web/node_modules/.package-lock.json ]; then
  echo "bootstrap: installing web assets (npm ci in web/) …"
  npm ci --prefix web --no-audit --no-fund --loglevel=error >/dev/null 2>&1 ||
    echo "bootstrap: warning: npm ci in web/ failed: no replay.html, the schema test skips" >&2
fi

build_type=${SCANPLAN_BUILD_TYPE:-Release}
extra=()
[ "${CI:-}" = "true" ] && extra+=(-DSCANPLAN_WERROR=ON)
if [ ! -f build/CMakeCache.txt ]; then
  cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE="$build_type" "${extra[@]}" >/dev/null
elif ((${#extra[@]})); then
  cmake -S . -B build "${extra[@]}" >/dev/null
fi
jobs=$(nproc 2>/dev/null || echo 2)
# Quiet when up to date; otherwise show only what went wrong.
if ! ninja -C build -n 2>/dev/null | grep -q '^ninja: no work to do'; then
  echo "bootstrap: building scanplan (Release) in build/ …"
  if ! cmake --build build --parallel "$jobs" >build/last-build.log 2>&1; then
    grep -E 'error|Error|FAILED' -A3 build/last-build.log | head -60 >&2
    echo "bootstrap: build failed; full log in build/last-build.log" >&2
    exit 1
  fi
fi
