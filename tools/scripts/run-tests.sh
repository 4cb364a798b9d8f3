#!/usr/bin/env bash
# run-tests.sh - install dependencies, build, and run the whole test suite (unit tests, CLI
# end-to-end tests, install + downstream find_package test; CUDA tests skip without a GPU).
set -euo pipefail
cd "$(dirname "$0")/../.."
bash tools/scripts/install-deps.sh
bash tools/scripts/build.sh build
cd build
ctest --output-on-failure -j "${FLUIDSURF_JOBS:-$(nproc)}"
