#!/usr/bin/env bash
# cli_pipeline_test.sh FLUIDSURF_BINARY - end-to-end checks of what the CLI does around its one
# library call: `info` on .vdb files and meshes, the -v timing tree, --stats JSON (parsed and
# summed by /usr/bin/python3, independently of the code that wrote it), and Ctrl-C (SIGINT) as a
# clean stop: exit code 130, no output, no temporary file.
set -u
BIN=$1
T=$(mktemp -d /tmp/fluidsurf_clip_XXXXXX)
trap 'rm -rf "$T"' EXIT
source "$(dirname "$0")/checks.sh"

"$BIN" generate drop --count 20000 -r 0.01 -o "$T/drop.bgeo" >/dev/null
"$BIN" reconstruct "$T/drop.bgeo" -r 0.01 -o "$T/drop.obj" --vdb "$T/drop.vdb" -q

# --- info on a level set, OpenVDB's own sphere, a mesh ----------------------------------------
out=$("$BIN" info "$T/drop.vdb")
check "info .vdb: grid, class and type" grep -q "grid        'surface'  class level set, type float" <<<"$out"
check "info .vdb: voxel size" grep -q "voxel size  (0.01, 0.01, 0.01)" <<<"$out"
check "info .vdb: active voxels" grep -Eq "active      [0-9,]+ voxels in [0-9,]+ leaves" <<<"$out"
check "info .vdb: bounding box" grep -Eq "bbox        \[-?[0-9]+, -?[0-9]+, -?[0-9]+\] \.\. \[" <<<"$out"
check "info .vdb: metadata" grep -q "fluidsurf:particle_radius *0.01" <<<"$out"
if command -v vdb_print >/dev/null; then
    n=$(vdb_print -l "$T/drop.vdb" | sed -n 's/.*Number of active voxels: *\([0-9,]*\).*/\1/p')
    check "info .vdb: active voxels as vdb_print counts them ($n)" grep -q "active      $n voxels" <<<"$out"
fi
if /usr/bin/python3 -c 'import pyopenvdb' 2>/dev/null; then
    /usr/bin/python3 -c "
import pyopenvdb as vdb
g = vdb.createLevelSetSphere(radius=2.0, center=(1, 2, 3), voxelSize=0.1, halfWidth=3.0)
g.name = 'sphere'
vdb.write('$T/sphere.vdb', grids=[g])"
    out=$("$BIN" info "$T/sphere.vdb")
    check "info on OpenVDB's sphere: name and class" grep -q "grid        'sphere'  class level set, type float" <<<"$out"
    check "info on OpenVDB's sphere: voxel size" grep -q "voxel size  (0.1, 0.1, 0.1)" <<<"$out"
    check "mesh OpenVDB's sphere, then info on the OBJ: watertight" bash -c "'$BIN' mesh '$T/sphere.vdb' -o '$T/sphere.obj' -q && '$BIN' info '$T/sphere.obj' | grep -q 'check .*watertight'"
else
    echo "note: /usr/bin/python3 has no pyopenvdb; OpenVDB's sphere is checked by the unit tests only"
fi
out=$("$BIN" info "$T/drop.obj")
check "info .obj: vertices with normals" grep -Eq "vertices    [0-9,]+ \(with normals\)" <<<"$out"
check "info .obj: triangles" grep -Eq "triangles   [0-9,]+" <<<"$out"
check "info .obj: checkMesh report" grep -q "check .*watertight" <<<"$out"
"$BIN" mesh "$T/drop.vdb" -o "$T/drop.ply" -q
check "info .ply mesh" bash -c "'$BIN' info '$T/drop.ply' | grep -q 'PLY mesh'"
printf 'v 0 0 0\nv 1 0 0\nf 1 2 7\n' >"$T/bad.obj"
expect_error "info: corrupt OBJ" "outside the 2 vertices read so far (at line 3)" "$BIN" info "$T/bad.obj"
head -c 300 "$T/drop.vdb" >"$T/cut.vdb"
expect_error "info: truncated .vdb" "cut.vdb" "$BIN" info "$T/cut.vdb"

# --- -v: the timing tree; --stats: JSON whose stages add up to the total -----------------------
out=$("$BIN" reconstruct "$T/drop.bgeo" -r 0.01 -o "$T/v.obj" --vdb "$T/v.vdb" -v --check --stats "$T/stats.json")
check "-v: the tree's root and the top-level stages" bash -c "grep -Eq '^  total +[0-9.]+ s +100.0%' <<<'$out' && grep -Eq '^    read ' <<<'$out' && grep -Eq '^    rasterize ' <<<'$out' && grep -Eq '^    mesh ' <<<'$out' && grep -Eq '^    write mesh ' <<<'$out'"
check "-v: stages nested inside rasterize" grep -Eq '^      field +[0-9.]+ s +[0-9.]+%' <<<"$out"
check "-v: peak memory" grep -Eq 'peak memory [0-9.]+ MiB' <<<"$out"
check "--stats: JSON parses; stages add up to the total within 5%" /usr/bin/python3 - "$T/stats.json" <<'PY'
import json, sys
doc = json.load(open(sys.argv[1]))
frame = doc["frames"][0]
root = frame["timing"]
assert root["name"] == "total" and root["seconds"] > 0
top = sum(c["seconds"] for c in root["children"])
assert abs(top - root["seconds"]) <= 0.05 * root["seconds"], (top, root["seconds"])
names = [c["name"] for c in root["children"]]
assert names == ["read", "rasterize", "mesh", "post", "write vdb", "write mesh", "check"], names
assert frame["counts"]["isolated_spheres"] == frame["counts"]["isolated"], frame["counts"]
raster = root["children"][1]
assert sum(c["seconds"] for c in raster["children"]) <= raster["seconds"] * 1.0001
counts = frame["counts"]
assert counts["particles"] == 20000 or counts["particles"] > 19000, counts
assert counts["boundary_edges"] == 0 and counts["triangles"] > 0 and counts["active_voxels"] > 0
assert doc["peak_memory_mib"] > 0
PY
check "--stats for a sequence: one entry per frame" bash -c "cp '$T/drop.bgeo' '$T/s_0001.bgeo' && cp '$T/drop.bgeo' '$T/s_0002.bgeo' && '$BIN' rasterize '$T/s_{:04}.bgeo' -r 0.01 -o '$T/s_{:04}.vdb' -q --stats '$T/seq.json' && /usr/bin/python3 -c \"import json; assert len(json.load(open('$T/seq.json'))['frames']) == 2\""

# --- --adaptive: three grids in the .vdb, meshed by `mesh` as reconstruct meshes them ----------
"$BIN" reconstruct "$T/drop.bgeo" -r 0.01 -o "$T/adaptive.ply" --raw --isolated drop --adaptive \
    --vdb "$T/adaptive.vdb" --stats "$T/adaptive.json" -q
out=$("$BIN" info "$T/adaptive.vdb")
check "adaptive .vdb: level 2 grid" grep -q "grid        'surface'  class level set, type float" <<<"$out"
check "adaptive .vdb: level 2 voxel" grep -q "voxel size  (0.02, 0.02, 0.02)" <<<"$out"
check "adaptive .vdb: level 3 grid" grep -q "grid        'surface_fine'  class level set, type float" <<<"$out"
check "adaptive .vdb: level map" grep -q "grid        'levels'  class unknown, type int32" <<<"$out"
check "adaptive: the mesh is watertight" bash -c "'$BIN' info '$T/adaptive.ply' | grep -q 'check .*watertight'"
"$BIN" mesh "$T/adaptive.vdb" -o "$T/adaptive_again.ply" -q
check "adaptive: mesh of the .vdb is reconstruct's mesh, byte for byte" cmp -s "$T/adaptive.ply" "$T/adaptive_again.ply"
check "adaptive: --stats counts triangles per level and patches" /usr/bin/python3 -c "
import json
c = json.load(open('$T/adaptive.json'))['frames'][0]['counts']
assert c['level2_cells'] + c['level3_cells'] > 0 and c['open_cracks'] == 0, c
assert c['level2_triangles'] + c['level3_triangles'] + c['patch_triangles'] == c['raw_triangles'], c"
out=$("$BIN" mesh "$T/adaptive.vdb" -o "$T/adaptive_v.ply" -v --stats "$T/adaptive_mesh.json")
check "adaptive: -v prints cells and triangles per level, patches and merged points, as --stats counts them" \
    /usr/bin/python3 -c "
import json, re, sys
c = json.load(open('$T/adaptive_mesh.json'))['frames'][0]['counts']
m = re.search(r'adaptive grid: level 2 (\d+) cells, (\d+) triangles; level 3 (\d+) cells, (\d+) triangles; crack patches (\d+) triangles \([0-9.]+%\), (\d+) crack points merged', sys.argv[1])
assert m, 'no adaptive line in -v'
got = [int(g) for g in m.groups()]
assert got == [c['level2_cells'], c['level2_triangles'], c['level3_cells'], c['level3_triangles'], c['patch_triangles'], c['merged_crack_points']], (got, c)
assert got[0] > 0 and got[2] > 0 and got[4] + got[5] > 0, got" "$out"
expect_error "adaptive: refused with the gather-full baseline" "narrow-band method only" \
    "$BIN" reconstruct "$T/drop.bgeo" -r 0.01 -o "$T/x.ply" --adaptive --method gather-full

# --- the heap on huge pages: the process starts again (ProcessMemory.h), the same bytes out ----
FLUIDSURF_HUGE_PAGES=0 "$BIN" reconstruct "$T/drop.bgeo" -r 0.01 -o "$T/hp0.ply" -q
check "huge pages: the run started again writes the same mesh" bash -c "FLUIDSURF_HUGE_PAGES=1 '$BIN' reconstruct '$T/drop.bgeo' -r 0.01 -o '$T/hp1.ply' -q && cmp '$T/hp0.ply' '$T/hp1.ply'"
check "huge pages: the same with the user's own GLIBC_TUNABLES" bash -c "FLUIDSURF_HUGE_PAGES=1 GLIBC_TUNABLES=glibc.malloc.tcache_count=7 '$BIN' reconstruct '$T/drop.bgeo' -r 0.01 -o '$T/hp2.ply' -q && cmp '$T/hp0.ply' '$T/hp2.ply'"

# --- Ctrl-C: exit code 130, one line, nothing written -----------------------------------------
"$BIN" generate drop --count 1000000 -r 0.01 -o "$T/big.bgeo" >/dev/null
for cmd in reconstruct rasterize; do
    out=$T/int_$cmd
    if [ $cmd = reconstruct ]; then args=(-o "$out.obj" --vdb "$out.vdb"); else args=(-o "$out.vdb"); fi
    signal_after INT 0.6 "$T/int.err" "$BIN" $cmd "$T/big.bgeo" -r 0.01 --voxel 0.25 "${args[@]}" -q
    check "$cmd: Ctrl-C exits with 130 (got $rc)" test $rc -eq 130
    check "$cmd: Ctrl-C says so in one line" bash -c "[ \$(wc -l <'$T/int.err') -eq 1 ] && grep -q interrupted '$T/int.err'"
    check "$cmd: Ctrl-C leaves no output and no temporary file" bash -c "! ls -A '$T' | grep -Eq 'int_|fluidsurf-'"
done

echo "cli pipeline: $pass passed, $fail failed"
[ $fail -eq 0 ]
