#!/usr/bin/env bash
# compare-outputs.sh OLD_FLUIDSURF NEW_FLUIDSURF [SHARED_DATA] [--device cpu|cuda|OLD:NEW]
# Proof that a restructuring changed no output: both binaries reconstruct every real frame of
# SHARED_DATA/real and the generated scenes (default settings, and a few other field and mesher
# settings), writing .vdb, .obj and .ply; every pair of files must be byte-identical. Runs on the
# GPU machine too (no OpenVDB needed there), with --device cuda; --device cpu:cuda runs OLD on
# the CPU and NEW on the GPU (one binary twice: the GPU makes the CPU's files). Prints one line
# per case and 'compare: N passed, M failed'; exit 1 when any differ.
set -uo pipefail
OLD=$1 NEW=$2 SHARED=${3:-../shared/data}
DEVICE=cpu
[ "${4:-}" = "--device" ] && DEVICE=${5:-cpu}
OLD_DEVICE=${DEVICE%%:*} NEW_DEVICE=${DEVICE##*:}
T=$(mktemp -d /tmp/fluidsurf_compare_XXXXXX)
trap 'rm -rf "$T"' EXIT
pass=0 fail=0

# name input radius|estimate [extra options...]
run_case() {
    local name=$1 input=$2 radius=$3
    shift 3
    local ok=1
    for side in old new; do
        local bin=$OLD device=$OLD_DEVICE
        [ "$side" = new ] && bin=$NEW device=$NEW_DEVICE
        mkdir -p "$T/$side"
        local r=(-r "$radius")
        [ "$radius" = estimate ] && r=() # no -r: the radius is estimated
        if ! "$bin" reconstruct "$input" "${r[@]}" -o "$T/$side/$name.obj" \
            --vdb "$T/$side/$name.vdb" --device "$device" -q "$@" >"$T/$side/$name.log" 2>&1; then
            echo "FAIL $name: $side binary failed: $(tail -1 "$T/$side/$name.log")"
            ok=0
        fi
        "$bin" mesh "$T/$side/$name.vdb" -o "$T/$side/$name.ply" -q >/dev/null 2>&1 || ok=0
    done
    if [ $ok = 1 ]; then
        for ext in vdb obj ply; do
            if ! cmp -s "$T/old/$name.$ext" "$T/new/$name.$ext"; then
                echo "FAIL $name: .$ext differs"
                ok=0
            fi
        done
    fi
    if [ $ok = 1 ]; then
        echo "ok   $name ($(stat -c %s "$T/new/$name.vdb") + $(stat -c %s "$T/new/$name.obj") + $(stat -c %s "$T/new/$name.ply") bytes)"
        pass=$((pass + 1))
    else
        fail=$((fail + 1))
    fi
    rm -f "$T"/old/"$name".* "$T"/new/"$name".*
}

if [ -d "$SHARED/real" ]; then
    for f in "$SHARED"/real/*; do
        name=$(basename "$f")
        r=0.025
        [ "$name" = free_particles_1000_particles.vtk ] && r=0.5
        run_case "$name" "$f" "$r"
    done
    hilbert=$SHARED/real/hilbert_46843_particles.bgeo
    run_case hilbert_voxel0.5 "$hilbert" 0.025 --voxel 0.5
    run_case hilbert_voxel2_R8 "$hilbert" 0.025 --voxel 2 --influence 8
    run_case hilbert_zb05 "$hilbert" 0.025 --field zb05
    run_case hilbert_openvdb_mesher "$hilbert" 0.025 --mesher openvdb
    run_case dam_gather_full "$SHARED/real/dam_break_frame_9_6859_particles.bgeo" 0.025 --method gather-full
    run_case free_keep_isolated "$SHARED/real/free_particles_1000_particles.vtk" 0.5 --keep-isolated
else
    echo "note: $SHARED/real not found; only generated scenes compared"
fi
for scene in single:1 block:20000 ball:20000 slab:20000 drop:40000 drop:1000000; do
    s=${scene%%:*} n=${scene##*:}
    "$OLD" generate "$s" --count "$n" -o "$T/$s-$n.bgeo" >/dev/null
    run_case "generated_${s}_$n" "$T/$s-$n.bgeo" 0.025
done
run_case generated_drop_40000_estimated_radius "$T/drop-40000.bgeo" estimate
echo "compare ($DEVICE): $pass passed, $fail failed"
[ $fail = 0 ]
