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
# The Python package, where it was built: installed under the prefix's site-packages, importable
# with nothing else than that folder on PYTHONPATH.
passed=1
if [ -d "$BUILD/python" ]; then
    site=$(find "$T/prefix" -name 'fluidsurf*.so' -printf '%h\n' | head -1)
    case "$site" in */lib/python3.*/dist-packages) ;; *) echo "python package at '$site'"; exit 1 ;; esac
    PYTHONPATH=$site /usr/bin/python3 -c '
import fluidsurf
p = fluidsurf.generate("ball", count=1000, radius=0.01)["positions"]
m = fluidsurf.reconstruct(p, 0.01)
assert fluidsurf.__file__.startswith("'"$site"'"), fluidsurf.__file__
assert m.check()["watertight"], m.check()
print("installed python package: %d triangles, watertight" % len(m.triangles))'
    passed=2
fi
echo "install: $passed passed, 0 failed"
