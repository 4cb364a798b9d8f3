#!/usr/bin/env bash
# farm_test.sh FLUIDSURF_BINARY - frame sequences as a farm runs them: a corrupt frame stops the
# run by default and is reported and passed over with --keep-going; --skip-existing leaves
# finished frames alone (their files untouched); --shard I/N splits a sequence into disjoint
# shares that cover it, --shard slurm takes the frame $SLURM_ARRAY_TASK_ID; a shard chooses r
# from the sequence's first frame, as a whole run does (the same mesh, byte for byte); mesh
# (and post, through the same loop) pass over a corrupt .vdb; convert takes the same options.
set -u
BIN=$1
T=$(mktemp -d /tmp/fluidsurf_farm_XXXXXX)
trap 'rm -rf "$T"' EXIT
source "$(dirname "$0")/checks.sh"
cd "$T"

# Six frames; frame 1 at r = 0.01, the others at r = 0.012 (so r estimated from frame 1 differs
# from r estimated from any other); frame 4 cut short.
for f in 1 2 3 4 5 6; do
    r=0.012; [ $f = 1 ] && r=0.01
    "$BIN" generate drop --count $((2000 + 100 * f)) -r $r -o "f_000$f.bgeo" >/dev/null
done
head -c 300 f_0001.bgeo >f_0004.bgeo
have() { for f in "$@"; do [ -s "$f" ] || return 1; done; }
lacks() { for f in "$@"; do [ ! -e "$f" ] || return 1; done; }

# --- the default: the first bad frame stops the run ------------------------------------------
expect_error "default: a corrupt frame stops the run" "f_0004.bgeo: header promises" \
    "$BIN" reconstruct 'f_{:04}.bgeo' -r 0.01 -o 'a_{:04}.ply' --raw -q
check "default: the frames before it are written" have a_0001.ply a_0002.ply a_0003.ply
check "default: none after it" lacks a_0004.ply a_0005.ply a_0006.ply

# --- --keep-going: reported, passed over, listed, exit 1 ---------------------------------------
out=$("$BIN" reconstruct 'f_{:04}.bgeo' -r 0.01 -o 'k_{:04}.ply' --raw --keep-going 2>k.err)
rc=$?
check "--keep-going: exit code 1 (got $rc)" test $rc -eq 1
check "--keep-going: every good frame written" have k_0001.ply k_0002.ply k_0003.ply k_0005.ply k_0006.ply
check "--keep-going: no output for the bad one" lacks k_0004.ply
check "--keep-going: the summary" grep -q "reconstruct 6 frames: 5 done, 0 skipped, 1 failed" <<<"$out"
check "--keep-going: the error at once, then the list" bash -c "grep -q 'error: f_0004.bgeo: header promises.*(left out: --keep-going)' k.err && grep -A1 '1 frame failed:' k.err | grep -q '^  f_0004.bgeo$'"
check "--keep-going: every frame's mesh watertight" bash -c "for f in 1 2 3 5 6; do '$BIN' info k_000\$f.ply | grep -q 'check .*watertight' || exit 1; done"

# --- frames in flight: the same meshes, lines and errors as one frame after the other ----------
"$BIN" reconstruct 'f_{:04}.bgeo' -r 0.01 -o 'n_{:04}.ply' --raw --keep-going --in-flight 1 >n1.out 2>n1.err
for n in 2 3 8; do
    "$BIN" reconstruct 'f_{:04}.bgeo' -r 0.01 -o "i${n}_{:04}.ply" --raw --keep-going --in-flight $n >i$n.out 2>i$n.err
    rc=$?
    check "--in-flight $n: exit 1 as one at a time (got $rc)" test $rc -eq 1
    check "--in-flight $n: the meshes of one at a time, byte for byte" bash -c \
        "for f in 1 2 3 5 6; do cmp -s n_000\$f.ply i${n}_000\$f.ply || exit 1; done; [ ! -e i${n}_0004.ply ]"
    check "--in-flight $n: the same lines, in the same order (times aside)" bash -c \
        "diff <(sed -e 's/i${n}_/n_/' i$n.out | sed -E 's/[0-9]+\.[0-9]+ s\$//') <(sed -E 's/[0-9]+\.[0-9]+ s\$//' n1.out) && diff i$n.err n1.err"
done
"$BIN" rasterize 'f_{:04}.bgeo' -r 0.01 -o 'rn_{:04}.vdb' --keep-going --in-flight 1 >rn.out 2>rn.err
"$BIN" rasterize 'f_{:04}.bgeo' -r 0.01 -o 'ri_{:04}.vdb' --keep-going >ri.out 2>ri.err
check "rasterize, 3 in flight: the level sets, lines and errors of one at a time" bash -c \
    "for f in 1 2 3 5 6; do cmp -s rn_000\$f.vdb ri_000\$f.vdb || exit 1; done; [ ! -e ri_0004.vdb ] && diff <(sed -e 's/ri_/rn_/' ri.out | sed -E 's/[0-9]+\.[0-9]+ s\$//') <(sed -E 's/[0-9]+\.[0-9]+ s\$//' rn.out) && diff ri.err rn.err"
"$BIN" mesh 'rn_{:04}.vdb' -o 'mn_{:04}.ply' --in-flight 1 >mn.out
"$BIN" mesh 'rn_{:04}.vdb' -o 'mi_{:04}.ply' --in-flight 8 >mi.out
"$BIN" post 'k_{:04}.ply' -o 'pn_{:04}.obj' --in-flight 1 >pn.out
"$BIN" post 'k_{:04}.ply' -o 'pi_{:04}.obj' >pi.out
check "mesh and post, frames in flight: the meshes and lines of one at a time" bash -c \
    "for f in 1 2 3 5 6; do cmp -s mn_000\$f.ply mi_000\$f.ply && cmp -s pn_000\$f.obj pi_000\$f.obj || exit 1; done; diff <(sed -e 's/mi_/mn_/' mi.out | sed -E 's/[0-9]+\.[0-9]+ s\$//') <(sed -E 's/[0-9]+\.[0-9]+ s\$//' mn.out) && diff <(sed -e 's/pi_/pn_/' pi.out | sed -E 's/[0-9]+\.[0-9]+ s\$//') <(sed -E 's/[0-9]+\.[0-9]+ s\$//' pn.out) && [ \$(grep -c ' -> ' pi.out) = 5 ]"
rm -f rn_* ri_* mn_* mi_* pn_* pi_*
out=$("$BIN" reconstruct 'f_{:04}.bgeo' -r 0.01 -o 'v_{:04}.ply' --raw --frames 1-3 -v)
check "--in-flight: -v shows a frame's wait for the frames before it" grep -q "^    waiting " <<<"$out"
expect_error "--in-flight 0 is refused" "--in-flight" \
    "$BIN" reconstruct 'f_{:04}.bgeo' -r 0.01 -o 'x_{:04}.ply' --in-flight 0
rm -f v_000*.ply

# --- --skip-existing: finished frames untouched ------------------------------------------------
before=$(stat -c '%Y.%N' k_000[12356].ply | md5sum)
sleep 1.1
out=$("$BIN" reconstruct 'f_{:04}.bgeo' -r 0.01 -o 'k_{:04}.ply' --raw --keep-going --skip-existing 2>/dev/null)
rc=$?
check "--skip-existing: the bad frame still fails (exit 1, got $rc)" test $rc -eq 1
check "--skip-existing: the summary" grep -q "reconstruct 6 frames: 0 done, 5 skipped, 1 failed" <<<"$out"
check "--skip-existing: the finished files untouched" test "$(stat -c '%Y.%N' k_000[12356].ply | md5sum)" = "$before"
rm k_0003.ply
out=$("$BIN" reconstruct 'f_{:04}.bgeo' -r 0.01 -o 'k_{:04}.ply' --raw --keep-going --skip-existing 2>/dev/null)
check "--skip-existing: a missing output is made again" bash -c "grep -q '1 done, 4 skipped, 1 failed' <<<'$out' && [ -s k_0003.ply ]"

# --- --shard I/N: disjoint shares that cover the sequence ------------------------------------
for i in 1 2 3; do
    "$BIN" reconstruct 'f_{:04}.bgeo' -r 0.01 -o "s${i}_{:04}.ply" --raw --keep-going --shard $i/3 -q 2>/dev/null
done
check "--shard i/3: frames 1 and 4 (failed) to shard 1" bash -c "have() { for f; do [ -s \$f ] || return 1; done; }; have s1_0001.ply && ! ls s1_* | grep -qv s1_0001"
check "--shard i/3: frames 2 and 5 to shard 2, 3 and 6 to shard 3" bash -c "[ \"\$(ls s2_* s3_* | tr '\n' ' ')\" = 's2_0002.ply s2_0005.ply s3_0003.ply s3_0006.ply ' ]"
check "--shard: the same meshes as the whole run" bash -c "cmp -s s2_0002.ply k_0002.ply && cmp -s s3_0006.ply k_0006.ply"

# --- a shard chooses r from the sequence's first frame ------------------------------------------
rm -f f_0004.bgeo
"$BIN" reconstruct 'f_{:04}.bgeo' -o 'e_{:04}.ply' --raw -q
"$BIN" reconstruct 'f_{:04}.bgeo' -o 'g_{:04}.ply' --raw -q --shard 2/2
check "--shard without -r: r from frame 1, the whole run's mesh byte for byte" cmp -s g_0002.ply e_0002.ply
"$BIN" reconstruct 'f_0002.bgeo' -o 'alone.ply' --raw -q
check "  (r from frame 2 alone gives another mesh)" bash -c "! cmp -s alone.ply e_0002.ply"
head -c 300 f_0002.bgeo >f_0001.bgeo
expect_error "--shard without -r and an unreadable first frame" "r is chosen from the sequence's first frame" \
    "$BIN" reconstruct 'f_{:04}.bgeo' -o 'h_{:04}.ply' --raw -q --shard 2/2 --keep-going

# --- --shard slurm --------------------------------------------------------------------------------
check "--shard slurm: the frame SLURM_ARRAY_TASK_ID only" bash -c "SLURM_ARRAY_TASK_ID=5 '$BIN' rasterize 'f_{:04}.bgeo' -r 0.01 -o 'v_{:04}.vdb' --shard slurm -q && [ \"\$(ls v_*)\" = v_0005.vdb ]"
# --- mesh (and post, the same loop): a corrupt .vdb passed over, finished frames skipped -------
head -c 200 v_0005.vdb >v_0006.vdb
out=$("$BIN" mesh 'v_{:04}.vdb' -o 'w_{:04}.ply' --keep-going 2>w.err)
rc=$?
check "mesh --keep-going: exit 1 (got $rc), the good frame meshed, the bad one listed" bash -c "[ $rc -eq 1 ] && [ -s w_0005.ply ] && [ ! -e w_0006.ply ] && grep -q '^  v_0006.vdb$' w.err"
check "mesh --keep-going: the summary" grep -q "mesh 2 frames: 1 done, 0 skipped, 1 failed" <<<"$out"
out=$("$BIN" mesh 'v_{:04}.vdb' -o 'w_{:04}.ply' --keep-going --skip-existing 2>/dev/null)
check "mesh --skip-existing: the summary" grep -q "mesh 2 frames: 0 done, 1 skipped, 1 failed" <<<"$out"

expect_error "--shard slurm outside an array job" "SLURM_ARRAY_TASK_ID is not set" \
    env -u SLURM_ARRAY_TASK_ID "$BIN" reconstruct 'f_{:04}.bgeo' -r 0.01 -o 'x_{:04}.ply' --shard slurm
expect_error "--shard slurm: a frame the sequence lacks" "frame 9 (SLURM_ARRAY_TASK_ID) is not in the sequence" \
    env SLURM_ARRAY_TASK_ID=9 "$BIN" reconstruct 'f_{:04}.bgeo' -r 0.01 -o 'x_{:04}.ply' --shard slurm
expect_error "--shard slurm: not a number" "is not a frame number" \
    env SLURM_ARRAY_TASK_ID=abc "$BIN" reconstruct 'f_{:04}.bgeo' -r 0.01 -o 'x_{:04}.ply' --shard slurm
expect_error "--shard 3/2" "expected I/N with 1 <= I <= N" \
    "$BIN" reconstruct 'f_{:04}.bgeo' -r 0.01 -o 'x_{:04}.ply' --shard 3/2
expect_error "--shard on a single file" "needs a frame pattern" \
    "$BIN" reconstruct f_0002.bgeo -r 0.01 -o x.ply --shard 1/2
check "--shard: nothing written by the refused runs" bash -c "! ls x_* x.ply 2>/dev/null | grep -q ."

# --- Ctrl-C in the middle of a sequence with frames in flight: 130, nothing half-written -----
# (sent once the first mesh is written, with three frames to go: after a fixed 1.5 s it could
# come after the end, the whole run taking 1.6-1.8 s on 2 cores)
for f in 1 2 3 4; do "$BIN" generate drop --count 400000 -r 0.01 --seed $f -o "big_000$f.xyz" >/dev/null; done
signal_when_written INT b_0001.ply b.err "$BIN" reconstruct 'big_{:04}.xyz' -r 0.01 -o 'b_{:04}.ply' -q
check "sequence: Ctrl-C exits with 130 (got $rc)" test $rc -eq 130
check "sequence: Ctrl-C says so in one line" bash -c "[ \$(wc -l <b.err) -eq 1 ] && grep -q interrupted b.err"
check "sequence: Ctrl-C leaves no temporary file, and every mesh it left whole" bash -c \
    "! ls | grep -q tmp && for m in \$(ls b_*.ply 2>/dev/null); do '$BIN' info \$m | grep -q 'check .*watertight' || exit 1; done"
rm -f big_* b_*

# --- convert: the same options (frames 1, 2, 3, 5, 6 now, frame 1 cut short) -------------------
out=$("$BIN" convert 'f_{:04}.bgeo' 'c_{:04}.xyz' --keep-going 2>c.err)
rc=$?
check "convert --keep-going: exit 1 (got $rc), every good frame converted, the bad one listed" \
    bash -c "[ $rc -eq 1 ] && [ -s c_0002.xyz ] && [ -s c_0006.xyz ] && [ ! -e c_0001.xyz ] && grep -q '^  f_0001.bgeo$' c.err"
check "convert --keep-going: the summary" grep -q "convert 5 frames: 4 done, 0 skipped, 1 failed" <<<"$out"
touch -d '2001-01-01' c_0002.xyz
out=$("$BIN" convert 'f_{:04}.bgeo' 'c_{:04}.xyz' --skip-existing --shard 2/3 2>/dev/null)
check "convert --skip-existing --shard 2/3: frames 2 and 6 skipped, untouched" bash -c \
    "grep -q 'convert 2 frames: 0 done, 2 skipped, 0 failed' <<<'$out' && [ \$(stat -c %Y c_0002.xyz) -lt 1000000000 ]"

echo "farm tests: $pass passed, $fail failed"
[ $fail -eq 0 ]
