#!/usr/bin/env bash
# build.sh [BUILD_DIR] - configure (Release, Ninja) and build fluidsurf. Re-running only rebuilds
# what changed. Extra CMake options can be passed in FLUIDSURF_CMAKE_ARGS.
set -euo pipefail
cd "$(dirname "$0")/../.."
BUILD=${1:-build}
JOBS=${FLUIDSURF_JOBS:-$(nproc)}
# shellcheck disable=SC2086
cmake -S . -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=Release ${FLUIDSURF_CMAKE_ARGS:-} >/dev/null
cmake --build "$BUILD" -j "$JOBS"
