#!/usr/bin/env bash
# run-fuzzers.sh [SECONDS_PER_TARGET] [PARALLEL] - build the libFuzzer targets with clang +
# AddressSanitizer in build-fuzz/ and run each for a bounded time (default 60 s), PARALLEL at a
# time (default 2), on a seed corpus made by `fluidsurf` itself (plus ../shared/data frames when
# present). Not part of CI. Exit code != 0 when any target found a crash; reproducers land in
# build-fuzz/fuzz/findings/, logs in build-fuzz/fuzz/<target>.log. The corpora are kept, so a
# second run goes on where the first stopped.
set -euo pipefail
cd "$(dirname "$0")/../.."
SECS=${1:-60}
PARALLEL=${2:-2}
command -v clang++ >/dev/null || { echo "run-fuzzers: needs clang (apt-get install clang libclang-rt-14-dev)" >&2; exit 2; }
# The SIMD paths keep AVX vectors in templates that only run inlined into functions built for
# AVX2 (target attributes); clang checks those types and builtins before inlining, where GCC
# checks after, so the fuzzers' build is for AVX2 throughout.
grep -qw avx2 /proc/cpuinfo || { echo "run-fuzzers: needs a CPU with AVX2 (the fuzz build is for AVX2)" >&2; exit 2; }
CC=clang CXX=clang++ cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DFLUIDSURF_FUZZ=ON \
    -DFLUIDSURF_WITH_CUDA=OFF -DFLUIDSURF_BUILD_TESTS=OFF "-DCMAKE_CXX_FLAGS=-mavx2 -mfma" >/dev/null
cmake --build build-fuzz -j "$(nproc)" >/dev/null
bash tools/scripts/build.sh build >/dev/null # the release CLI makes the seeds
CLI=$PWD/build/fluidsurf
F=build-fuzz/fuzz
mkdir -p $F/findings

# Seeds: small frames of each scene in every writable format, a level set and its meshes.
SEEDS=$(mktemp -d /tmp/fluidsurf_seeds_XXXXXX)
trap 'rm -rf "$SEEDS"' EXIT
for scene in ball slab drop; do
    $CLI generate $scene -n 300 -o "$SEEDS/$scene.bgeo" >/dev/null
    for ext in vdb ply xyz vtk bgeo.gz; do $CLI convert -q "$SEEDS/$scene.bgeo" "$SEEDS/$scene.$ext"; done
    $CLI reconstruct -q "$SEEDS/$scene.bgeo" -r 0.05 -o "$SEEDS/$scene.obj"
done
# Level sets and point grids under -max_len: a few particles moved off the origin, so the grid has
# one root child (a grid straddling the origin has eight, each with 9 to 12 KB of masks).
for n in 10 40; do
    $CLI generate ball -n $n -o "$SEEDS/b$n.xyz" >/dev/null
    /usr/bin/python3 -c "
import struct, sys
d = open(sys.argv[1], 'rb').read()
v = struct.unpack('<%df' % (len(d) // 4), d)
open(sys.argv[1], 'wb').write(struct.pack('<%df' % len(v), *[x + 1.0 for x in v]))" "$SEEDS/b$n.xyz"
    $CLI rasterize -q "$SEEDS/b$n.xyz" -r 0.05 -o "$SEEDS/b${n}_ls.vdb"
    $CLI mesh -q "$SEEDS/b${n}_ls.vdb" -o "$SEEDS/b${n}_mesh.ply"
    $CLI convert -q "$SEEDS/b$n.xyz" "$SEEDS/b${n}_pts.vdb"
    rm "$SEEDS/b$n.xyz"
done
[ -d ../shared/data/real ] && cp ../shared/data/real/*.vtu ../shared/data/real/splishsplash_particle_grid_400_particles.bgeo \
    ../shared/data/real/cube_2366_particles.vtk "$SEEDS/" 2>/dev/null || true
# point grids with attributes (id, velocity): 19 KB
[ -f "$SEEDS/fluid_250_particles.vtu" ] && $CLI convert -q "$SEEDS/fluid_250_particles.vtu" "$SEEDS/fluid_pts.vdb"
printf '\x93NUMPY\x01\x00\x76\x00{'"'"'descr'"'"': '"'"'<f4'"'"', '"'"'fortran_order'"'"': False, '"'"'shape'"'"': (1, 3), }%*s\n' 60 '' > "$SEEDS/a.npy"
head -c 12 /dev/zero >> "$SEEDS/a.npy"
printf 'x,y,z,id\n0,0,0,1\n1.5,2,3e-2,2\n' > "$SEEDS/a.csv"
printf '1 2 3\n4 5 6\n' > "$SEEDS/b.csv"

seed() { # target -> the seed files it starts from
    case $1 in
        bgeo) ls "$SEEDS"/*.bgeo "$SEEDS"/*.bgeo.gz ;;
        vdb) ls "$SEEDS"/*_pts.vdb ;;
        levelset) ls "$SEEDS"/*_ls.vdb ;;
        ply) ls "$SEEDS"/{ball,slab,drop}.ply ;;
        mesh_ply) ls "$SEEDS"/*_mesh.ply ;;
        mesh_obj) ls "$SEEDS"/*.obj ;;
        *) ls "$SEEDS"/*."$1" 2>/dev/null || true ;;
    esac
}

fuzz() { # target: run it, then print one line
    local t=$1 corpus=$F/corpus_$1 log=$F/$1.log
    mkdir -p "$corpus"
    seed "$t" | xargs -r cp -t "$corpus"
    # OpenVDB is not exception-safe (a read that throws leaks the half-read tree): no leak checks
    # for the VDB targets.
    local asan=""
    [ "$t" = vdb ] || [ "$t" = levelset ] && asan="detect_leaks=0"
    if ASAN_OPTIONS=$asan ./$F/fuzz_$t "$corpus" -max_total_time="$SECS" -rss_limit_mb=2048 -timeout=10 \
        -max_len=65536 -artifact_prefix=$F/findings/${t}_ >"$log" 2>&1; then
        echo "fuzz_$t: ok, $(grep -Eo '^#[0-9]+' "$log" | tail -1 | tr -d '#') runs in ${SECS} s, corpus $(ls "$corpus" | wc -l)"
    else
        echo "fuzz_$t: FINDING (see $log)"; return 1
    fi
}
export -f fuzz seed
export F SECS SEEDS CLI
printf '%s\n' levelset mesh_obj mesh_ply bgeo vtk vtu ply npy xyz csv vdb |
    xargs -P "$PARALLEL" -I{} bash -c 'fuzz {}' && exit 0
exit 1
