#!/usr/bin/env bash
# run-fuzzers.sh [SECONDS_PER_TARGET] - build the libFuzzer targets with clang + AddressSanitizer
# in build-fuzz/ and run each for a bounded time (default 60 s) on a seed corpus made by
# `fluidsurf generate` (plus ../shared/data frames when present). Not part of CI.
# Exit code != 0 when any target found a crash; reproducers land in build-fuzz/fuzz/findings/.
set -euo pipefail
cd "$(dirname "$0")/../.."
SECS=${1:-60}
command -v clang++ >/dev/null || { echo "run-fuzzers: needs clang (apt-get install clang libclang-rt-14-dev)" >&2; exit 2; }
CC=clang CXX=clang++ cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DFLUIDSURF_FUZZ=ON \
    -DFLUIDSURF_WITH_CUDA=OFF -DFLUIDSURF_BUILD_TESTS=OFF >/dev/null
cmake --build build-fuzz -j "$(nproc)" >/dev/null
# Seeds: a small frame of each scene in every writable format, converted by a plain build.
bash tools/scripts/build.sh build >/dev/null
SEEDS=$(mktemp -d /tmp/fluidsurf_seeds_XXXXXX)
trap 'rm -rf "$SEEDS"' EXIT
for scene in ball slab drop; do
    ./build/fluidsurf generate $scene -n 300 -o "$SEEDS/$scene.bgeo" >/dev/null
    for ext in vdb ply xyz vtk bgeo.gz; do ./build/fluidsurf convert -q "$SEEDS/$scene.bgeo" "$SEEDS/$scene.$ext"; done
done
[ -d ../shared/data/real ] && cp ../shared/data/real/*.vtu ../shared/data/real/splishsplash_particle_grid_400_particles.bgeo \
    ../shared/data/real/cube_2366_particles.vtk "$SEEDS/" 2>/dev/null || true
printf '\x93NUMPY\x01\x00\x76\x00{'"'"'descr'"'"': '"'"'<f4'"'"', '"'"'fortran_order'"'"': False, '"'"'shape'"'"': (1, 3), }%*s\n' 60 '' > "$SEEDS/a.npy"
head -c 12 /dev/zero >> "$SEEDS/a.npy"
mkdir -p build-fuzz/fuzz/findings
status=0
for fmt in bgeo vtk vtu ply npy xyz vdb; do
    corpus=build-fuzz/fuzz/corpus_$fmt
    mkdir -p "$corpus"
    case $fmt in
        bgeo) cp "$SEEDS"/*.bgeo "$SEEDS"/*.bgeo.gz "$corpus/" ;;
        vtu) cp "$SEEDS"/*.vtu "$corpus/" 2>/dev/null || true ;;
        *) cp "$SEEDS"/*.$fmt "$corpus/" 2>/dev/null || true ;;
    esac
    log=build-fuzz/fuzz/$fmt.log
    if [ $fmt != vdb ]; then
        if ./build-fuzz/fuzz/fuzz_$fmt "$corpus" -max_total_time="$SECS" -rss_limit_mb=2048 -timeout=10 \
            -max_len=65536 -artifact_prefix=build-fuzz/fuzz/findings/${fmt}_ >"$log" 2>&1; then
            echo "fuzz_$fmt: ok, $(grep -Eo '#[0-9]+' "$log" | tail -1) runs in ${SECS}s"
        else
            echo "fuzz_$fmt: FINDING (see $log)"; status=1
        fi
        continue
    fi
    # fuzz_vdb mostly exercises OpenVDB's own reader. It sizes buffers from fields inside the grid
    # data (e.g. Blosc block sizes) that cannot be checked beforehand; outside ASan an absurd size
    # throws std::bad_alloc, which the reader reports as a corrupt file, but ASan aborts instead.
    # OpenVDB also leaks the partly read tree when a read throws (not exception-safe). So this
    # target runs in fork mode past such reports, and every artifact is then replayed through the
    # release CLI: a finding is only an input that crashes it, hangs, or fails without one message.
    export ASAN_OPTIONS=detect_leaks=0
    ./build-fuzz/fuzz/fuzz_vdb "$corpus" -fork=1 -ignore_crashes=1 -ignore_ooms=1 -ignore_timeouts=1 \
        -max_total_time="$SECS" -rss_limit_mb=2048 -timeout=10 -max_len=65536 \
        -artifact_prefix=build-fuzz/fuzz/findings/vdb_ >"$log" 2>&1 || true
    unset ASAN_OPTIONS
    replayed=0; real=0
    for art in build-fuzz/fuzz/findings/vdb_*; do
        [ -f "$art" ] || continue
        replayed=$((replayed + 1))
        cp "$art" /tmp/fluidsurf_replay.vdb
        rc=0
        msg=$(timeout 20 ./build/fluidsurf info --no-spacing /tmp/fluidsurf_replay.vdb 2>&1 >/dev/null) || rc=$?
        if [ $rc -ne 1 ] || [ "$(grep -c 'fluidsurf: error:' <<<"$msg")" -ne 1 ]; then
            echo "  release CLI failed on $art (rc $rc): $msg"; real=$((real + 1))
        fi
    done
    rm -f /tmp/fluidsurf_replay.vdb
    echo "fuzz_vdb: $(grep -Eo '^#[0-9]+' "$log" | tail -1) runs in ${SECS}s, $replayed ASan reports replayed, $real fail the release build"
    [ $real -eq 0 ] || status=1
done
exit $status
