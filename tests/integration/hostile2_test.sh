#!/usr/bin/env bash
# hostile2_test.sh FLUIDSURF_BINARY - issue 63, hostile input and faults round 2, through the
# command line: a disk that fills up (RLIMIT_FSIZE, the same failing writes as ENOSPC), --stats
# onto an input or another output, outputs that are not regular files, thread counts past any
# machine, --skip-existing of cut outputs, the longest valid output name. Every refusal is one
# 'fluidsurf: error:' line naming the file, a non-zero exit, and every older file unchanged.
set -u
BIN=$1
T=$(mktemp -d /tmp/fluidsurf_hostile2_XXXXXX)
trap 'rm -rf "$T"' EXIT
source "$(dirname "$0")/checks.sh"
no_temporaries() { ! ls -A "$T" | grep -q '^\.fluidsurf-'; }
# full_disk KBYTES CMD...: CMD with KBYTES KiB of disk left to each file it writes
full_disk() { local kb=$1; shift; bash -c 'trap "" XFSZ; ulimit -f "$0"; exec "$@"' "$kb" "$@"; }

"$BIN" generate ball --count 20000 -r 0.025 -o "$T/x.bgeo" >/dev/null
cp "$T/x.bgeo" "$T/x.orig"

# --- a full disk: an error naming the output, the older file kept (1a) ------------------------
"$BIN" rasterize "$T/x.bgeo" -r 0.025 -o "$T/f.vdb" -q
cp "$T/f.vdb" "$T/f.good"
expect_error "rasterize on a full disk" "f.vdb: write failed" full_disk 16 "$BIN" rasterize "$T/x.bgeo" -r 0.025 -o "$T/f.vdb" -q
check "rasterize on a full disk: the older f.vdb kept" cmp -s "$T/f.vdb" "$T/f.good"
"$BIN" reconstruct "$T/x.bgeo" -r 0.025 -o "$T/m.obj" --vdb "$T/m.vdb" -q
cp "$T/m.obj" "$T/m.good" && cp "$T/m.vdb" "$T/mv.good"
expect_error "reconstruct --vdb on a full disk" "m.vdb: write failed" full_disk 16 "$BIN" reconstruct "$T/x.bgeo" -r 0.025 -o "$T/m.obj" --vdb "$T/m.vdb" -q
check "reconstruct on a full disk: both older outputs kept" bash -c "cmp -s '$T/m.obj' '$T/m.good' && cmp -s '$T/m.vdb' '$T/mv.good'"
"$BIN" convert "$T/x.bgeo" "$T/pts.vdb" --no-compress -q
cp "$T/pts.vdb" "$T/pts.good"
expect_error "convert to .vdb on a full disk" "pts.vdb: write failed" full_disk 16 "$BIN" convert "$T/x.bgeo" "$T/pts.vdb" --no-compress -q
check "convert on a full disk: the older pts.vdb kept" cmp -s "$T/pts.vdb" "$T/pts.good"
expect_error "mesh on a full disk" "m.obj: write failed" full_disk 16 "$BIN" mesh "$T/m.vdb" -o "$T/m.obj" -q
check "mesh on a full disk: the older m.obj kept" cmp -s "$T/m.obj" "$T/m.good"
echo '{"old": 1}' >"$T/s.json"
for i in 1 2 3; do # three frames of two isolated particles: empty meshes, 4 KB of --stats
    /usr/bin/python3 -c "import struct; open('$T/e_000$i.xyz', 'wb').write(struct.pack('<6f', 0, 0, 0, 5, 5, 5))"
done
expect_error "--stats on a full disk" "s.json: write failed" full_disk 2 "$BIN" reconstruct "$T/e_{:04}.xyz" -r 0.025 -o "$T/e_{:04}.obj" --isolated drop --stats "$T/s.json" -q
check "--stats on a full disk: the older JSON kept" grep -q '"old"' "$T/s.json"
check "a full disk leaves no temporary" no_temporaries

# --- --stats is an output like the others (1b) ---------------------------------------------
"$BIN" reconstruct "$T/x.bgeo" -r 0.025 -o "$T/e.obj" -q --raw
cp "$T/e.obj" "$T/e.orig"
expect_error "reconstruct --stats onto the input" "refusing to overwrite an input" "$BIN" reconstruct "$T/x.bgeo" -r 0.025 -o "$T/e2.obj" --stats "$T/x.bgeo"
expect_error "rasterize --stats onto the input" "refusing to overwrite an input" "$BIN" rasterize "$T/x.bgeo" -r 0.025 -o "$T/e2.vdb" --stats "$T/x.bgeo"
expect_error "mesh --stats onto the input" "refusing to overwrite an input" "$BIN" mesh "$T/f.vdb" -o "$T/e2.obj" --stats "$T/f.vdb"
expect_error "post --stats onto the input" "refusing to overwrite an input" "$BIN" post "$T/e.obj" -o "$T/e2.obj" --stats "$T/e.obj"
expect_error "--stats onto the mesh output" "are the same file" "$BIN" reconstruct "$T/x.bgeo" -r 0.025 -o "$T/e.obj" --stats "$T/e.obj"
expect_error "--stats onto --vdb" "are the same file" "$BIN" reconstruct "$T/x.bgeo" -r 0.025 -o "$T/e2.obj" --vdb "$T/f.vdb" --stats "$T/f.vdb"
cp "$T/x.bgeo" "$T/q_0001.bgeo" && cp "$T/x.bgeo" "$T/q_0002.bgeo"
expect_error "--stats onto a sequence's frame" "refusing to overwrite an input" "$BIN" rasterize "$T/q_{:04}.bgeo" -r 0.025 -o "$T/q_{:04}.vdb" --stats "$T/q_0002.bgeo"
check "--stats refusals: inputs and outputs unchanged" bash -c "cmp -s '$T/x.bgeo' '$T/x.orig' && cmp -s '$T/e.obj' '$T/e.orig' && cmp -s '$T/f.vdb' '$T/f.good' && cmp -s '$T/q_0002.bgeo' '$T/x.orig'"
check "--stats refusals: nothing written" bash -c "! ls '$T' | grep -q '^e2\.\|^q_.*vdb'"

# --- outputs that are not regular files are never replaced (2) -------------------------------
mkdir "$T/dir.obj" && mkfifo "$T/fifo.vdb"
expect_error "an output that is a folder" "not a regular file" "$BIN" reconstruct "$T/x.bgeo" -r 0.025 -o "$T/dir.obj"
expect_error "an output that is a FIFO" "not a regular file" timeout 20 "$BIN" rasterize "$T/x.bgeo" -r 0.025 -o "$T/fifo.vdb"
expect_error "--stats that is a FIFO" "not a regular file" timeout 20 "$BIN" rasterize "$T/x.bgeo" -r 0.025 -o "$T/g.vdb" --stats "$T/fifo.vdb"
check "the folder and the FIFO are still there" bash -c "[ -d '$T/dir.obj' ] && [ -p '$T/fifo.vdb' ]"
echo old >"$T/target.obj" && ln -s target.obj "$T/link.obj"
"$BIN" reconstruct "$T/x.bgeo" -r 0.025 -o "$T/link.obj" -q --raw
check "an output through a link: the link stays, its file is replaced" bash -c "[ -L '$T/link.obj' ] && cmp -s '$T/target.obj' '$T/e.obj'"

# --- thread counts (3) ------------------------------------------------------------------------
for j in 65537 70000 1000000 -1; do
    expect_error "-j $j is refused" "threads" "$BIN" rasterize "$T/x.bgeo" -r 0.025 -o "$T/j.vdb" -j "$j"
done
check "-j 4096 runs" "$BIN" rasterize "$T/x.bgeo" -r 0.025 -o "$T/j.vdb" -j 4096 -q

# --- --skip-existing counts only outputs that read back whole ---------------------------------
"$BIN" generate ball --count 2000 -r 0.025 -o "$T/k_0001.bgeo" >/dev/null
cp "$T/k_0001.bgeo" "$T/k_0002.bgeo" && cp "$T/k_0001.bgeo" "$T/k_0003.bgeo"
"$BIN" rasterize "$T/k_{:04}.bgeo" -r 0.025 -o "$T/k_{:04}.vdb" -q
: >"$T/k_0001.vdb"                                           # zero bytes
head -c 300 "$T/k_0003.vdb" >"$T/k_cut" && mv "$T/k_cut" "$T/k_0003.vdb" # cut short
out=$("$BIN" rasterize "$T/k_{:04}.bgeo" -r 0.025 -o "$T/k_{:04}.vdb" --skip-existing 2>&1)
check "--skip-existing redoes the empty and the cut output, skips the whole one ($out)" grep -q "2 done, 1 skipped" <<<"$out"
check "--skip-existing: the redone outputs read back" bash -c "'$BIN' info '$T/k_0001.vdb' >/dev/null && '$BIN' info '$T/k_0003.vdb' >/dev/null"

# --- NaN, Inf and absurd values: refused or dropped with a message, never written (7) ---------
/usr/bin/python3 - "$T" <<'PY'
import struct, sys
t = sys.argv[1]
lattice = [(0.05 * i, 0.05 * j, 0.05 * k) for i in range(12) for j in range(12) for k in range(12)]
pack = lambda pts: b"".join(struct.pack("<3f", *p) for p in pts)
open(t + "/far1.xyz", "wb").write(pack(lattice + [(1e20, 0, 0)]))
open(t + "/huge.xyz", "wb").write(pack([(x * 1e22, y * 1e22, z * 1e22) for x, y, z in lattice]))
tetra = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
for name, bad in (("nan", "nan"), ("inf", "inf"), ("far", "1e38")):
    open("%s/%s.obj" % (t, name), "w").write(tetra.replace("v 1 0 0", "v 1 %s 0" % bad))
rows = ["%g %g %g 0.025" % p for p in lattice] + ["0.3 0.3 0.3 1e30"]
open(t + "/pscale.ply", "w").write("ply\nformat ascii 1.0\nelement vertex %d\nproperty float x\n"
    "property float y\nproperty float z\nproperty float pscale\nend_header\n%s\n" % (len(rows), "\n".join(rows)))
PY
expect_error "one pscale of 1e30 (it emptied the mesh)" "over 1000 times the median" "$BIN" reconstruct "$T/pscale.ply" -o "$T/n.obj"
expect_error "a particle at 1e20: refused, naming it" "particle 1728 lies at (1e+20, 0, 0), beyond +-1e+15" "$BIN" reconstruct "$T/far1.xyz" -r 0.025 -o "$T/n.obj"
check "a particle at 1e20: --drop-nonfinite drops it and the rest reconstructs" bash -c "'$BIN' reconstruct '$T/far1.xyz' -r 0.025 -o '$T/n.obj' --drop-nonfinite -q && [ -s '$T/n.obj' ]"
expect_error "a lattice at scale 1e22 (r estimated)" "beyond +-1e+15" "$BIN" reconstruct "$T/huge.xyz" -o "$T/h.obj"
expect_error "--voxel 1e38" "voxel size" "$BIN" rasterize "$T/x.bgeo" -r 0.025 --voxel 1e38 -o "$T/h.vdb"
for name in nan inf far; do
    expect_error "post of a mesh with a $name vertex" "vertex 2 of 4" "$BIN" post "$T/$name.obj" -o "$T/p_$name.obj"
done
check "no output from the refused values" bash -c "! ls '$T' | grep -q '^\(h\.\|p_\)'"

# a block beside 150,000 particles at one point: the estimate took minutes (quadratic in the pile)
/usr/bin/python3 -c "
import struct
block = b''.join(struct.pack('<3f', 0.05 * i, 0.05 * j, 0.05 * k) for i in range(20) for j in range(20) for k in range(20))
open('$T/pile.xyz', 'wb').write(block + struct.pack('<3f', 3, 3, 3) * 150000)"
expect_error "a pile at one point, r estimated: says so" "most particles lie on top of each other" timeout 60 "$BIN" reconstruct "$T/pile.xyz" -o "$T/pile.obj"
check "a pile at one point, -r given: the block's mesh" bash -c "timeout 60 '$BIN' reconstruct '$T/pile.xyz' -r 0.025 -o '$T/pile.obj' -q && '$BIN' info '$T/pile.obj' | grep -q '1 component.*watertight'"

# --- memory: refused with the estimate before the budget is passed (4) -------------------------
peak_ok() { # peak_ok LIMIT_MIB PATTERN CMD...: fails with PATTERN in its error, its peak under LIMIT
    /usr/bin/python3 - "$@" <<'PY'
import resource, subprocess, sys
limit, pattern, cmd = float(sys.argv[1]), sys.argv[2], sys.argv[3:]
r = subprocess.run(cmd, capture_output=True, text=True, timeout=60)
peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
ok = r.returncode == 1 and pattern in r.stderr and r.stderr.count("fluidsurf: error:") == 1
if not ok or peak > limit:
    sys.exit("exit %d, peak %.0f MiB, stderr %r" % (r.returncode, peak, r.stderr))
PY
}
"$BIN" generate ball --count 24000 -r 0.025 -o "$T/b24k.bgeo" >/dev/null
check "--voxel 0.02 on 24k particles: refused with the band's estimate, < 300 MB" peak_ok 300 "narrow band of" "$BIN" rasterize "$T/b24k.bgeo" -r 0.025 --voxel 0.02 -o "$T/v.vdb"
check "--max-memory 64M: a fine voxel refused with the estimate" peak_ok 300 "more than the memory budget of 64 MiB (--max-memory)" "$BIN" reconstruct "$T/b24k.bgeo" -r 0.025 --voxel 0.1 --max-memory 64M -o "$T/v.obj"
expect_error "--max-memory of no size" "max-memory" "$BIN" rasterize "$T/x.bgeo" -r 0.025 -o "$T/v.vdb" --max-memory lots
# A .bgeo.gz whose header promises 1e9 points, then 16 MB of zeros: 11.5 GB and 103 s before
/usr/bin/python3 - "$T/promise.bgeo.gz" <<'PY'
import gzip, struct, sys
head = b"BgeoV" + struct.pack(">i", 5) + struct.pack(">8i", 1000000000, 0, 0, 0, 0, 0, 0, 0)
open(sys.argv[1], "wb").write(gzip.compress(head + bytes(16 << 20), 6))
PY
check "a .bgeo.gz promising 1e9 points: refused, < 300 MB" peak_ok 300 "promise.bgeo.gz" "$BIN" info "$T/promise.bgeo.gz"
check "no output after the memory refusals" bash -c "! ls '$T' | grep -q '^v\.'"

# --- level sets of tiles, and grids with no surface (3, 7) ------------------------------------
/usr/bin/python3 - "$T" <<'PY'
import sys
import pyopenvdb as vdb
t = sys.argv[1]
def level_set(background):
    g = vdb.FloatGrid(background)
    g.gridClass, g.name = vdb.GridClass.LEVEL_SET, "surface"
    return g
box = level_set(3.0)  # a 512^3 box of active tiles: 0 triangles before, 262k leaves voxelized
box.fill((0, 0, 0), (511, 511, 511), -3.0, True)
vdb.write(t + "/box.vdb", grids=[box])
board = level_set(3.0)  # 40^3 tiles of alternate signs: every face a surface
for i in range(40):
    for j in range(40):
        for k in range(40):
            board.fill((8 * i, 8 * j, 8 * k), (8 * i + 7, 8 * j + 7, 8 * k + 7), -1.0 if (i + j + k) % 2 else 1.0, True)
vdb.write(t + "/board.vdb", grids=[board])
spread = level_set(3.0)  # 512 tiles 4096 voxels apart: 5 MB of file, 150 MB of OpenVDB nodes
for i in range(8):
    for j in range(8):
        for k in range(8):
            o = (4096 * i, 4096 * j, 4096 * k)
            spread.fill(o, (o[0] + 7, o[1] + 7, o[2] + 7), -1.0, True)
vdb.write(t + "/spread.vdb", grids=[spread])
fog = vdb.FloatGrid(0.0)
fog.gridClass, fog.name = vdb.GridClass.FOG_VOLUME, "density"
fog.fill((0, 0, 0), (20, 20, 20), 1.0, True)
vdb.write(t + "/fog.vdb", grids=[fog])
vdb.write(t + "/empty.vdb", grids=[level_set(3.0)])
negative = level_set(-3.0)
negative.fill((0, 0, 0), (7, 7, 7), -1.0, True)
vdb.write(t + "/negative.vdb", grids=[negative])
PY
for mesher in mc openvdb; do
    check "a tiled 512^3 box meshes to one closed box ($mesher)" bash -c "'$BIN' mesh '$T/box.vdb' -o '$T/box_$mesher.ply' --mesher $mesher -q && '$BIN' info '$T/box_$mesher.ply' | grep -q 'watertight'"
    check "tiles of alternate signs past --max-memory: refused with the estimate ($mesher), < 300 MB" peak_ok 300 "active tiles of grid 'surface' needs about" "$BIN" mesh "$T/board.vdb" -o "$T/board.obj" --mesher $mesher --max-memory 16M
done
check "info --max-memory: far-apart tiles' tree refused before OpenVDB reads it, < 100 MB" peak_ok 100 "a grid's tree needs about" "$BIN" info "$T/spread.vdb" --max-memory 64M
"$BIN" generate ball --count 200000 -r 0.01 -o "$T/b200k.bgeo.gz" >/dev/null
check "convert --max-memory: 200k points (2.3 MiB) past 1M refused with the estimate" peak_ok 100 "reading the 200" "$BIN" convert "$T/b200k.bgeo.gz" "$T/b200k.ply" --max-memory 1M
check "far-apart tiles whose nodes pass --max-memory: refused by the file's walk, < 100 MB" peak_ok 100 "a grid's tree needs about" "$BIN" mesh "$T/spread.vdb" -o "$T/spread.obj" --max-memory 64M
for g in fog empty negative; do
    err=$("$BIN" mesh "$T/$g.vdb" -o "$T/$g.obj" -q 2>&1 >/dev/null)
    check "mesh of a $g grid: a warning says why there is no surface ($err)" grep -q "warning: .*$g.vdb: no surface in grid" <<<"$err"
done

# --- signals reach every command within a second (5) -------------------------------------------
# (6M particles: info takes about 1 s, convert to .bgeo.gz 2 s on 2 cores; neither checks for a
# stop in its loops, so the watchdog ends them)
"$BIN" generate drop --count 6000000 -r 0.01 -o "$T/big.xyz" >/dev/null
for cmd in "info $T/big.xyz" "convert $T/big.xyz $T/big_out.bgeo.gz"; do
    start=$(date +%s%N)
    signal_after TERM 0.2 "$T/sig.err" $BIN $cmd
    ms=$((($(date +%s%N) - start) / 1000000))
    check "SIGTERM stops '${cmd%% *}' with 143 (got $rc)" test $rc -eq 143
    check "SIGTERM stops '${cmd%% *}' within 2 s of the signal ($ms ms in all)" test $ms -lt 2200
done
check "SIGTERM: convert left no output and no temporary" bash -c "[ ! -e '$T/big_out.bgeo.gz' ] && ! ls -A '$T' | grep -q '^\.fluidsurf-'"

# --- names -------------------------------------------------------------------------------------
long=$(printf 'n%.0s' $(seq 251)).obj
check "a 255-byte output name is written" "$BIN" reconstruct "$T/x.bgeo" -r 0.025 -o "$T/$long" -q --raw
check "a 255-byte output name: the file is there" test -s "$T/$long"
check "no temporary is left anywhere" no_temporaries

echo "hostile2: $pass passed, $fail failed"
[ $fail -eq 0 ]
