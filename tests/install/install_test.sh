#!/usr/bin/env bash
# install_test.sh BUILD_DIR DOWNSTREAM_SRC - `cmake --install` the built project into a temporary
# prefix, then configure, build and run a tiny downstream project that finds it with
# find_package(fluidsurf CONFIG), links fluidsurf::fluidsurf and calls reconstruct().
set -euo pipefail
BUILD=$1
SRC=$2
T=$(mktemp -d /tmp/fluidsurf_install_XXXXXX)
trap 'rm -rf "$T"' EXIT
cmake --install "$BUILD" --prefix "$T/prefix" >/dev/null
test -f "$T/prefix/include/fluidsurf/ParticleSet.h"
test -f "$T/prefix/include/fluidsurf/Version.h"
test -f "$T/prefix/include/fluidsurf/MeshLevelSet.h"
test -f "$T/prefix/include/fluidsurf/Reconstruct.h"
test ! -e "$T/prefix/include/fluidsurf/cuda" # the CUDA facade is private
test -f "$T/prefix/lib/cmake/fluidsurf/fluidsurfConfig.cmake"
GEN=()
command -v ninja >/dev/null && GEN=(-G Ninja)
cmake -S "$SRC" -B "$T/build" "${GEN[@]}" -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$T/prefix" >/dev/null
cmake --build "$T/build" >/dev/null
out=$("$T/build/downstream" "$T/p.ply")
echo "$out"
grep -q "downstream read 1000 particles" <<<"$out"
grep -q "watertight" <<<"$out"
echo "install: 1 passed, 0 failed"
