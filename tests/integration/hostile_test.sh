#!/usr/bin/env bash
# hostile_test.sh FLUIDSURF_BINARY - input a careless or hostile user would give (issue 12):
# outputs that would overwrite an input, non-regular files behind particle names, empty files,
# radii and lengths that cannot work, SIGTERM. Every refusal is one 'fluidsurf: error:' line with
# a non-zero exit and the inputs unchanged.
set -u
BIN=$1
T=$(mktemp -d /tmp/fluidsurf_hostile_XXXXXX)
trap 'rm -rf "$T"' EXIT
source "$(dirname "$0")/checks.sh"

"$BIN" generate ball --count 2000 -r 0.025 -o "$T/x.ply" >/dev/null
cp "$T/x.ply" "$T/x.orig"
"$BIN" convert "$T/x.ply" "$T/p.vdb" >/dev/null
cp "$T/p.vdb" "$T/p.orig"

# --- an output that is an input of the same run --------------------------------------------
expect_error "reconstruct x.ply -o x.ply" "refusing to overwrite an input" "$BIN" reconstruct "$T/x.ply" -r 0.025 -o "$T/x.ply"
check "reconstruct x.ply -o x.ply: input unchanged" cmp -s "$T/x.ply" "$T/x.orig"
expect_error "rasterize p.vdb -o p.vdb" "refusing to overwrite an input" "$BIN" rasterize "$T/p.vdb" -r 0.025 -o "$T/p.vdb"
check "rasterize p.vdb -o p.vdb: input unchanged" cmp -s "$T/p.vdb" "$T/p.orig"
expect_error "convert x.ply x.ply" "refusing to overwrite an input" "$BIN" convert "$T/x.ply" "$T/x.ply"
expect_error "the same file by another path" "is the input" "$BIN" reconstruct "$T/x.ply" -r 0.025 -o "$T/./x.ply"
ln -s "$T/x.ply" "$T/link.ply"
expect_error "the same file through a link" "is the input" "$BIN" reconstruct "$T/x.ply" -r 0.025 -o "$T/link.ply"
check "through a link: input unchanged" cmp -s "$T/x.ply" "$T/x.orig"
cp "$T/x.ply" "$T/s_0001.ply" && cp "$T/x.ply" "$T/s_0002.ply"
expect_error "a pattern onto its own frames" "is the input" "$BIN" convert "$T/s_{:04}.ply" "$T/s_####.ply"
"$BIN" rasterize "$T/x.ply" -r 0.025 -o "$T/ls.vdb" -q
cp "$T/ls.vdb" "$T/ls.orig"
expect_error "mesh ls.vdb -o ls.vdb" "must end in .obj" "$BIN" mesh "$T/ls.vdb" -o "$T/ls.vdb"
check "mesh: level set unchanged" cmp -s "$T/ls.vdb" "$T/ls.orig"

# --- files that are not regular files, empty files ------------------------------------------
mkfifo "$T/fifo.bgeo"
start=$(date +%s)
expect_error "a FIFO named .bgeo is refused at once" "not a regular file" timeout 10 "$BIN" info "$T/fifo.bgeo"
check "the FIFO did not block" test $(($(date +%s) - start)) -lt 5
ln -s /dev/zero "$T/zero.bgeo"
expect_error "/dev/zero behind a particle name" "not a regular file" timeout 10 "$BIN" rasterize "$T/zero.bgeo" -r 0.025 -o "$T/z.vdb"
: >"$T/empty.xyz"
expect_error "an empty .xyz in info" "file is empty" "$BIN" info "$T/empty.xyz"
: >"$T/empty.bgeo"
expect_error "an empty .bgeo in info" "file is empty" "$BIN" info "$T/empty.bgeo"

truncate -s 400000001 "$T/big_odd.xyz" # sparse: 400 MB of zeros, one byte past a whole triple
check "a 400 MB .xyz of the wrong size is refused from its first bytes (< 50 MB peak)" /usr/bin/python3 - "$BIN" "$T/big_odd.xyz" <<'PY'
import resource, subprocess, sys
r = subprocess.run([sys.argv[1], "info", sys.argv[2]], capture_output=True, text=True)
peak_mib = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
assert r.returncode != 0 and "not a multiple of 12" in r.stderr, r.stderr
assert peak_mib < 50, peak_mib
PY

# A gzip bomb: a valid BGEO header with 3 points, then 1 GiB of zeros (1 MB compressed).
/usr/bin/python3 - "$T/bomb.bgeo.gz" <<'PY'
import struct, sys, zlib
c = zlib.compressobj(9, zlib.DEFLATED, 31)
out = [c.compress(b"BgeoV" + struct.pack(">i", 5) + struct.pack(">8i", 3, 0, 0, 0, 0, 0, 0, 0) +
                  b"".join(struct.pack(">4f", i, 0, 0, 1) for i in range(3)))]
out += [c.compress(bytes(1 << 24)) for _ in range(64)]
open(sys.argv[1], "wb").write(b"".join(out) + c.flush())
PY
check "a BGEO gzip bomb: refused past what its header promises (64 MiB more), < 100 MB peak" /usr/bin/python3 - "$BIN" "$T/bomb.bgeo.gz" <<'PY'
import resource, subprocess, sys
r = subprocess.run([sys.argv[1], "info", "--no-spacing", sys.argv[2]], capture_output=True, text=True)
assert r.returncode == 1 and "past what the header promises" in r.stderr, (r.stdout, r.stderr)
assert resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024 < 100
PY

# --- radii and lengths that cannot work ------------------------------------------------------
for r in 0 -1 nan inf 1x; do
    expect_error "-r $r" "radius" "$BIN" rasterize "$T/x.ply" -r "$r" -o "$T/r.vdb"
done
expect_error "--voxel nan" "voxel" "$BIN" rasterize "$T/x.ply" -r 0.025 --voxel nan -o "$T/r.vdb"
"$BIN" generate ball --count 2000 -r 1e-6 -o "$T/tiny.bgeo" >/dev/null
expect_error "a voxel too small for OpenVDB" "voxel size 1e-06 is too small" "$BIN" rasterize "$T/tiny.bgeo" -r 1e-6 -o "$T/r.vdb"
check "no output after the refusals" bash -c "! ls -A '$T' | grep -Eq '^(r|z)\.vdb|fluidsurf-'"
err=$("$BIN" reconstruct "$T/x.ply" -r 1e6 -o "$T/huge.obj" -q 2>&1 >/dev/null)
check "-r 1e6: a warning names the likely cause" grep -q "warning: .*no surface from 2007 particles: r = 1e+06 is" <<<"$err"
err=$("$BIN" reconstruct "$T/x.ply" -r 0.025 --influence 1000 -o "$T/huge.obj" -q 2>&1 >/dev/null)
check "--influence 1000: a warning names the lengths" grep -q "warning: .*check the lengths relative to it" <<<"$err"

# --- particles far away ----------------------------------------------------------------------
"$BIN" generate drop --count 20000 -r 0.025 -o "$T/near.xyz" >/dev/null
/usr/bin/python3 -c "
import struct, sys
d = open('$T/near.xyz', 'rb').read()
open('$T/far.xyz', 'wb').write(d + struct.pack('<3f', 0.025 * 1e7, 0, 0))
open('$T/farpair.xyz', 'wb').write(d + struct.pack('<6f', 0.025 * 1e7, 0, 0, 0.025 * 1e7 + 0.05, 0, 0))"
"$BIN" reconstruct "$T/near.xyz" -r 0.025 -o "$T/near.obj" -q
check "one particle 1e7 r away: the frame still reconstructs" "$BIN" reconstruct "$T/far.xyz" -r 0.025 -o "$T/far.obj" -q
check "one particle 1e7 r away: the same mesh as without it" cmp -s "$T/near.obj" "$T/far.obj"
expect_error "a far cluster the grid cannot hold: the error names the file" "farpair.xyz: the particles span" "$BIN" reconstruct "$T/farpair.xyz" -r 0.025 -o "$T/fp.obj"

/usr/bin/python3 -c "import struct; open('$T/coincident.xyz', 'wb').write(struct.pack('<3f', 1, 2, 3) * 120000)"
err=$("$BIN" reconstruct "$T/coincident.xyz" -r 0.025 -o "$T/coincident.obj" -q 2>&1 >/dev/null)
check "120,000 coincident particles: done, with a warning that says so" grep -q "warning: .*no surface from 120000 particles: most particles coincide" <<<"$err"
# the same pile with float noise (+-1e-6, 4e-5 r): one neighbourhood pass per spot, not per
# particle (it took 17 s before; the timeout only stops a hang)
/usr/bin/python3 -c "
import random, struct
random.seed(1)
u = lambda: random.uniform(-1e-6, 1e-6)
open('$T/near.xyz', 'wb').write(b''.join(struct.pack('<3f', 1 + u(), 2 + u(), 3 + u()) for _ in range(120000)))"
check "120,000 near-coincident particles: done" timeout 60 "$BIN" reconstruct "$T/near.xyz" -r 0.025 -o "$T/near.obj" -q

# --- SIGTERM: exit 143, nothing written ------------------------------------------------------
"$BIN" generate drop --count 1000000 -r 0.01 -o "$T/big.bgeo" >/dev/null
echo old >"$T/term_old.obj" && echo old >"$T/term_old.vdb"
"$BIN" reconstruct "$T/big.bgeo" -r 0.01 --voxel 0.25 -o "$T/term_old.obj" --vdb "$T/term_old.vdb" -q 2>/dev/null &
pid=$!
sleep 0.6
kill -TERM $pid
wait $pid
check "SIGTERM keeps both existing outputs of the frame" bash -c "[ \"\$(cat '$T/term_old.obj')\" = old ] && [ \"\$(cat '$T/term_old.vdb')\" = old ]"
# A temporary left by a killed run (unlocked, untouched for an hour) is removed by the next run
# there; a recent one is not (issue 63: it may be a live run's in another PID namespace).
echo stale >"$T/.fluidsurf-0123456789ab.x.obj" && touch -d '2 hours ago' "$T/.fluidsurf-0123456789ab.x.obj"
echo recent >"$T/.fluidsurf-abcdefghijkl.x.obj"
"$BIN" reconstruct "$T/x.ply" -r 0.025 -o "$T/fresh.obj" -q
check "a killed run's temporary is removed by the next run" test ! -e "$T/.fluidsurf-0123456789ab.x.obj"
check "a recent temporary is left alone" test -e "$T/.fluidsurf-abcdefghijkl.x.obj"
rm -f "$T/.fluidsurf-abcdefghijkl.x.obj"
signal_after TERM 0.6 "$T/term.err" \
    "$BIN" reconstruct "$T/big.bgeo" -r 0.01 --voxel 0.25 -o "$T/term.obj" --vdb "$T/term.vdb" -q
check "SIGTERM exits with 143 (got $rc)" test $rc -eq 143
check "SIGTERM leaves no output and no temporary file" bash -c "! ls -A '$T' | grep -Eq 'term\.(obj|vdb)|fluidsurf-'"

echo "hostile: $pass passed, $fail failed"
[ $fail -eq 0 ]
