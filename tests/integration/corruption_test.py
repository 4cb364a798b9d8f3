#!/usr/bin/python3
"""corruption_test.py FLUIDSURF_BINARY [SHARED_DATA] - the corruption suite of issue 12.

Broken files are made at test time from real frames (../shared/data/real; generated frames when
it is absent) in every readable format: cuts, damaged magic and header fields, absurd counts,
NaN/Inf, empty files, bombs, files that are not regular files. Each goes through every command
that reads it (info, convert, rasterize, reconstruct; mesh for level sets), and every run must:
exit 1, print exactly one line (naming the file) and nothing on stdout, leave no file behind,
keep an existing output, and take < 2 s and < 300 MB peak.
"""
import os
import re
import shutil
import struct
import subprocess
import sys
import tempfile
import threading
import time
import zlib

BIN = os.path.abspath(sys.argv[1])
SHARED = sys.argv[2] if len(sys.argv) > 2 else os.path.join(os.path.dirname(__file__), "../../../shared/data")
MAX_SECONDS, MAX_MIB = 2.0, 300
R = "0.025"

work = tempfile.mkdtemp(prefix="fluidsurf_corrupt_")
src_dir, bad_dir, out_dir = (os.path.join(work, d) for d in ("src", "bad", "out"))
for d in (src_dir, bad_dir, out_dir):
    os.makedirs(d)


def run(args):
    subprocess.run([BIN] + args, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


def read(path):
    with open(path, "rb") as f:
        return f.read()


# --- valid sources -------------------------------------------------------------------------
real = os.path.join(SHARED, "real")
if os.path.isdir(real):
    frame = os.path.join(real, "dam_break_frame_9_6859_particles.bgeo")
    shutil.copy(frame, os.path.join(src_dir, "frame.bgeo"))
    for name in ("cube_2366_particles.vtk", "fluid_250_particles.vtu", "fluid_encoded_250_particles.vtu"):
        shutil.copy(os.path.join(real, name), src_dir)
    print("sources: real frames from", real)
else:
    print("sources: ../shared/data is absent, using a generated frame (the real frames are better)")
    run(["generate", "drop", "-n", "6000", "-o", os.path.join(src_dir, "frame.bgeo")])
S = lambda name: os.path.join(src_dir, name)
for ext in ("vdb", "bgeo.gz", "ply", "xyz", "vtk"):
    run(["convert", "-q", S("frame.bgeo"), S("frame." + ext)])
run(["convert", "-q", S("frame.bgeo"), S("plain.bgeo")])  # the real .bgeo is gzip'd
run(["rasterize", "-q", S("frame.bgeo"), "-r", R, "-o", S("surface.vdb")])
# raw marching-cubes meshes (the cut fractions below are placed for their layout)
RAW = ["--raw"]
run(["reconstruct", "-q", S("frame.bgeo"), "-r", R, "-o", S("mesh.obj")] + RAW)
run(["reconstruct", "-q", S("frame.bgeo"), "-r", R, "-o", S("mesh.ply")] + RAW)
xyz = read(S("frame.xyz"))
points = [struct.unpack_from("<3f", xyz, 12 * i) for i in range(len(xyz) // 12)]
with open(S("frame.csv"), "w") as f:
    f.write("x,y,z\n" + "".join("%r,%r,%r\n" % p for p in points))
npy_header = "{'descr': '<f4', 'fortran_order': False, 'shape': (%d, 3), }" % len(points)
npy_header += " " * (63 - (10 + len(npy_header)) % 64) + "\n"  # data aligned to 64 bytes
with open(S("frame.npy"), "wb") as f:
    f.write(b"\x93NUMPY\x01\x00" + struct.pack("<H", len(npy_header)) + npy_header.encode() + xyz)
with open(S("ascii.ply"), "w") as f:
    f.write("ply\nformat ascii 1.0\nelement vertex %d\nproperty float x\nproperty float y\n"
            "property float z\nend_header\n" % len(points) + "".join("%r %r %r\n" % p for p in points))

# --- broken files --------------------------------------------------------------------------
cases = []  # (file name, what is broken, commands[, what the message must say])
PARTICLE = ("info", "convert", "rasterize", "reconstruct")
LEVELSET = ("info", "mesh")


def add(name, data, why, commands=PARTICLE, expect=None):
    with open(os.path.join(bad_dir, name), "wb") as f:
        f.write(data)
    cases.append((name, why, commands, expect))


def cuts(stem, ext, data, fractions, commands=PARTICLE, floor=0):
    for frac in fractions:
        n = max(floor, int(len(data) * frac))
        add("%s_cut%02d.%s" % (stem, int(frac * 100), ext), data[:n], "cut at %d%%" % (frac * 100), commands)


def replaced(data, old, new, count=1):
    assert old in data, (old, data[:200])
    return data.replace(old, new, count)


def first_float_as(data, fmt, value):
    """data with one particle's x coordinate set to value: the first particle whose x, y, z
    bytes occur exactly once in data (a particle at the origin would match header zeros)."""
    for p in points:
        old = struct.pack(fmt[0] + 3 * fmt[1], *p)
        if data.count(old) == 1:
            i = data.index(old)
            return data[:i] + struct.pack(fmt, value) + data[i + 4:]
    raise AssertionError("no particle found by its bytes")


# empty files, every readable format
for ext in ("bgeo", "bgeo.gz", "vtk", "vtu", "ply", "xyz", "csv", "txt", "npy", "vdb"):
    add("empty." + ext, b"", "empty file")
add("empty_levelset.vdb", b"", "empty file", LEVELSET)
add("empty.obj", b"", "empty file", ("info",))

# BGEO (binary Houdini geometry, big-endian header: magic, version, point count, ...)
bgeo = read(S("plain.bgeo"))
cuts("bgeo", "bgeo", bgeo, (0.002, 0.1, 0.3, 0.5, 0.7, 0.9, 0.999), floor=8)
add("bgeo_magic.bgeo", b"Xgeo" + bgeo[4:], "damaged magic")
add("bgeo_version.bgeo", bgeo[:5] + struct.pack(">i", 99) + bgeo[9:], "unknown version")
add("bgeo_count_huge.bgeo", bgeo[:9] + struct.pack(">i", 0x7FFFFFFF) + bgeo[13:], "absurd point count")
add("bgeo_count_negative.bgeo", bgeo[:9] + struct.pack(">i", -5) + bgeo[13:], "negative point count")
add("bgeo_attrs_huge.bgeo", bgeo[:25] + struct.pack(">i", 0x7FFFFFF0) + bgeo[29:], "absurd attribute count")
add("bgeo_nan.bgeo", first_float_as(bgeo, ">f", float("nan")), "NaN position")
add("bgeo_inf.bgeo", first_float_as(bgeo, ">f", float("inf")), "Inf position")
add("bgeo_text.bgeo", b"PGEOMETRY V5\nNPoints 10 NPrims 0\n", "ASCII geometry (not supported)")

# BGEO.gz
gz = read(S("frame.bgeo.gz"))
cuts("gz", "bgeo.gz", gz, (0.005, 0.3, 0.6, 0.95), floor=4)
add("gz_not_gzip.bgeo.gz", b"\x1f\x8c" + gz[2:], "damaged gzip magic")
add("gz_flip.bgeo.gz", gz[:len(gz) // 2] + bytes([gz[len(gz) // 2] ^ 0xFF]) + gz[len(gz) // 2 + 1:],
    "flipped byte in the deflate stream")
bomb = zlib.compressobj(9, zlib.DEFLATED, 31)
hdr = bgeo[:9] + struct.pack(">i", 50000000) + bgeo[13:200]  # promises 50M points: ~1 GB
add("gz_bomb.bgeo.gz", bomb.compress(hdr) + bomb.compress(b"\0" * (64 << 20)) + bomb.flush(),
    "gzip bomb: a header promising 50M points, then 64 MiB of zeros (65 KB compressed)")

# PLY (binary little-endian from convert; ASCII written above)
ply = read(S("frame.ply"))
head = ply[:ply.index(b"end_header\n") + 11]
cuts("ply", "ply", ply, (0.01, 0.3, 0.6, 0.9), floor=3)
add("ply_magic.ply", b"plx" + ply[3:], "damaged magic")
add("ply_count_huge.ply", replaced(ply, b"element vertex %d" % len(points), b"element vertex 4000000000"),
    "absurd vertex count")
add("ply_count_more.ply", replaced(ply, b"element vertex %d" % len(points), b"element vertex %d" % (len(points) + 1)),
    "one vertex more than the data holds")
add("ply_format.ply", replaced(ply, b"binary_little_endian", b"binary_middle_endian"), "unknown format")
add("ply_type.ply", replaced(ply, b"property float x", b"property float128 x"), "unknown property type")
add("ply_no_end.ply", replaced(ply, b"end_header", b"end_headex"), "header never ends")
add("ply_nan.ply", head + struct.pack("<f", float("nan")) + ply[len(head) + 4:], "NaN position")
aply = read(S("ascii.ply"))
cuts("aply", "ply", aply, (0.3, 0.7), floor=3)
add("aply_word.ply", replaced(aply, b"end_header\n", b"end_header\n1.0 zwei 3.0\n"), "a word where a number belongs")
add("aply_inf.ply", replaced(aply, b"end_header\n", b"end_header\ninf 0 0\n"), "Inf position")
add("aply_short.ply", replaced(aply, b"end_header\n", b"end_header\n1.0 2.0\n"), "a vertex with two numbers")

# XYZ (raw little-endian float32 triples)
add("xyz_cut1.xyz", xyz[:-1], "one byte short of a whole triple")
add("xyz_cut5.xyz", xyz[:-5], "five bytes short")
add("xyz_extra.xyz", xyz + b"\0\0", "two bytes past a whole triple")
add("xyz_nan.xyz", struct.pack("<f", float("nan")) + xyz[4:], "NaN position")
add("xyz_inf.xyz", xyz[:12] + struct.pack("<f", float("-inf")) + xyz[16:], "-Inf position")
add("xyz_tiny.xyz", b"\1\2\3", "three bytes")

# CSV / TXT
csv = read(S("frame.csv"))
add("csv_header_only.csv", b"x,y,z\n", "header only")
add("csv_two_columns.csv", replaced(csv, b"x,y,z\n", b"x,y,z\n1.0,2.0\n"), "a row with two columns")
add("csv_word.csv", replaced(csv, b"x,y,z\n", b"x,y,z\n1.0,abc,2.0\n"), "a word where a number belongs")
add("csv_nan.csv", replaced(csv, b"x,y,z\n", b"x,y,z\nnan,0,0\n"), "NaN position")
add("csv_inf.csv", replaced(csv, b"x,y,z\n", b"x,y,z\n0,inf,0\n"), "Inf position")
add("csv_binary.csv", bgeo[:4000], "binary data named .csv")
add("txt_word.txt", b"1 2 3\n4 five 6\n", "a word where a number belongs")
add("txt_overflow.txt", b"1 2 3\n1e999 0 0\n", "a number past float range")

# NPY
npy = read(S("frame.npy"))
cuts("npy", "npy", npy, (0.05, 0.5, 0.99), floor=4)
add("npy_magic.npy", b"\x93NUMPX" + npy[6:], "damaged magic")
add("npy_shape_huge.npy", replaced(npy, b"(%d, 3)" % len(points), b"(%d, 3)" % 10**12), "absurd shape")
add("npy_shape_2.npy", replaced(npy, b"(%d, 3)" % len(points), b"(%d, 2)" % len(points)), "two columns")
add("npy_descr.npy", replaced(npy, b"'<f4'", b"'<c8'"), "complex values")
add("npy_header_len.npy", npy[:8] + struct.pack("<H", 65000) + npy[10:], "header length past the file")
data_at = 10 + struct.unpack_from("<H", npy, 8)[0]
add("npy_nan.npy", npy[:data_at] + struct.pack("<f", float("nan")) + npy[data_at + 4:], "NaN position")

# VTK legacy (binary big-endian from convert; the real cube is binary too)
for stem, name in (("vtk", "frame.vtk"), ("cube", "cube_2366_particles.vtk")):
    if not os.path.exists(S(name)):
        continue
    vtk = read(S(name))
    npts = int(re.search(rb"POINTS (\d+)", vtk).group(1))
    cuts(stem, "vtk", vtk, (0.01, 0.05, 0.3, 0.6, 0.95), floor=1)
    add(stem + "_magic.vtk", b"# vtk DataFilx" + vtk[14:], "damaged first line")
    add(stem + "_count_huge.vtk", replaced(vtk, b"POINTS %d" % npts, b"POINTS 999999999999"), "absurd point count")
    add(stem + "_count_more.vtk", replaced(vtk, b"POINTS %d" % npts, b"POINTS %d" % (npts + 10)), "ten points more than the data holds")
    add(stem + "_dataset.vtk", re.sub(rb"DATASET \w+", b"DATASET RECTILINEAR_GRIB", vtk, 1), "unknown dataset")
    add(stem + "_type.vtk", re.sub(rb"(POINTS \d+) \w+", rb"\1 quaternion", vtk, 1), "unknown value type")
    add(stem + "_encoding.vtk", re.sub(rb"\nBINARY\n", b"\nBINARX\n", vtk, 1), "unknown encoding")
if os.path.exists(S("cube_2366_particles.vtk")):
    cube = read(S("cube_2366_particles.vtk"))
    add("cube_cut_celltypes.vtk", cube[:cube.index(b"CELL_TYPES")], "cut right before CELL_TYPES (point data lost)")
for stem, name in (("vtk", "frame.vtk"),):
    vtk = read(S(name))
    add(stem + "_nan.vtk", first_float_as(vtk, ">f", float("nan")), "NaN position")

# VTK XML (.vtu): the real files, zlib-compressed appended raw and base64
for stem, name in (("vtu", "fluid_250_particles.vtu"), ("vtu64", "fluid_encoded_250_particles.vtu")):
    if not os.path.exists(S(name)):
        continue
    vtu = read(S(name))
    cuts(stem, "vtu", vtu, (0.02, 0.2, 0.5, 0.8, 0.98), floor=1)
    add(stem + "_count_huge.vtu", re.sub(rb'NumberOfPoints="\s*\d+"', b'NumberOfPoints="999999999999"', vtu, 1),
        "absurd point count")
    add(stem + "_root.vtu", replaced(vtu, b"<VTKFile", b"<VTKFilx"), "damaged root element")
    add(stem + "_type.vtu", replaced(vtu, b'type="Float64"', b'type="Float96"'), "unknown value type")
    add(stem + "_offset.vtu", re.sub(rb'offset="\s*0\s*"', b'offset="99999999"', vtu, 1), "offset past the data")
    add(stem + "_no_end.vtu", vtu[:vtu.index(b"</VTKFile>")], "root element never closed")
    if stem == "vtu64":
        at = vtu.index(b"_", vtu.index(b"<AppendedData")) + 1 + 30
        add("vtu64_char.vtu", vtu[:at] + b"!" + vtu[at + 1:], "invalid character in base64")
        add("vtu64_pad.vtu", vtu[:at] + b"=" + vtu[at + 1:], "'=' inside a base64 quad")
    if b"vtkZLibDataCompressor" in vtu and b'header_type="UInt64"' in vtu:
        # a zlib bomb: 250M points, the first array's one block promising all 6 GB of them
        at = vtu.index(b"_", vtu.index(b"<AppendedData")) + 1
        n = 250000000
        big = re.sub(rb'NumberOfPoints="\s*\d+"', b'NumberOfPoints="%d"' % n, vtu, 1)
        at += len(big) - len(vtu)
        blocks, size, last, csize = struct.unpack_from("<4Q", big, at)
        add(stem + "_zlib_bomb.vtu", big[:at] + struct.pack("<4Q", 1, 24 * n, 24 * n, csize) + big[at + 32:],
            "zlib block table promising 6 GB from 5 KB")
    if b"vtkZLibDataCompressor" in vtu:
        add(stem + "_compressor.vtu", replaced(vtu, b"vtkZLibDataCompressor", b"vtkLZ4DataCompressor"),
            "unsupported compressor")

# VDB points
vdb = read(S("frame.vdb"))
cuts("vdbp", "vdb", vdb, (0.01, 0.1, 0.5, 0.9), floor=8)
add("vdbp_magic.vdb", b"\x20\x42\x44\x57" + vdb[4:], "damaged magic")
add("vdbp_version.vdb", vdb[:8] + struct.pack("<I", 1) + vdb[12:], "unsupported version")
add("vdbp_gridcount.vdb", replaced(vdb, struct.pack("<i", 1) + struct.pack("<i", len(b"points")) + b"points",
                                   struct.pack("<i", 0x7FFFFFFF) + struct.pack("<i", len(b"points")) + b"points"),
    "absurd grid count")


def vdb_descriptor(data, name):
    """The offsets (grid, block, end) of the grid called name, and where they are."""
    at = data.index(struct.pack("<i", len(name)) + name) + 4 + len(name)
    for _ in range(2):  # grid type, instance parent
        at += 4 + struct.unpack_from("<i", data, at)[0]
    return at, struct.unpack_from("<3q", data, at)


# the leaf buffers of a point grid (io/VdbPointBuffers.cc): a pass count, a voxel chunk size per
# leaf, a header byte and the attribute descriptor, each leaf's array metadata, then each
# attribute's page headers
_, (_, pblock, _) = vdb_descriptor(vdb, b"points")
leaves = int(re.search(r"in (\d+) leaves", subprocess.run(
    [BIN, "info", "--no-spacing", S("frame.vdb")], capture_output=True, text=True).stdout).group(1))
pvdb = lambda at, b: vdb[:at] + b + vdb[at + len(b):]
header = pblock + 2 + 2 * leaves
at = header + 1
count = struct.unpack_from("<Q", vdb, at)[0]
at += 8


def vdb_string(at):
    return at + 4 + struct.unpack_from("<i", vdb, at)[0]


for _ in range(2 * count):  # type pairs
    at = vdb_string(at)
name_at = at + 4  # the first attribute name's first byte
for _ in range(count):  # names and positions
    at = vdb_string(at) + 8
groups = struct.unpack_from("<Q", vdb, at)[0]
at += 8
for _ in range(groups):
    at = vdb_string(at) + 8
metadata = struct.unpack_from("<i", vdb, at)[0]
at += 4
for _ in range(metadata):
    at = vdb_string(vdb_string(at))
    at += 4 + struct.unpack_from("<i", vdb, at)[0]
for _ in range(leaves * count):  # array metadata: byte count, flags, serialization flags, size
    at += 8 + 1 + 1 + 4 + (4 if vdb[at + 9] & 1 else 0)
page = at  # attribute 0, leaf 0: a page header (its arrays are blosc-paged)
stored = struct.unpack_from("<i", vdb, page)[0]
add("vdbp_passes.vdb", pvdb(pblock, struct.pack("<H", 2)), "point grid pass count 2", expect="pass count 2")
add("vdbp_leafheader.vdb", pvdb(header, b"\x07"), "unknown point leaf header", expect="point leaf header 7")
add("vdbp_attrcount.vdb", pvdb(header + 1, struct.pack("<Q", 1 << 40)), "absurd attribute count",
    expect="promises 1099511627776 attributes")
add("vdbp_attrname.vdb", pvdb(name_at, b"\n"), "attribute name with a newline (the message stays one line)",
    expect="corrupt attribute name '?")
add("vdbp_pagezero.vdb", pvdb(page, struct.pack("<i", 0)), "attribute page of size 0",
    expect="corrupt attribute page: 0 bytes stored")
if stored > 0:  # blosc: stored size, content size
    content = struct.unpack_from("<i", vdb, page + 4)[0]
    add("vdbp_pageshort.vdb", pvdb(page + 4, struct.pack("<i", content - 2)), "page shorter than its arrays",
        expect="runs past its page")
    add("vdbp_pagebomb.vdb", pvdb(page + 4, struct.pack("<i", 1 << 30)), "page promising 1 GiB",
        expect="bytes stored for 1073741824")
else:
    add("vdbp_pageshort.vdb", pvdb(page, struct.pack("<i", stored + 2)), "page shorter than its arrays",
        expect="runs past its page")

# VDB level sets, through info and mesh
ls = read(S("surface.vdb"))
cuts("ls", "vdb", ls, (0.01, 0.1, 0.3, 0.5, 0.7, 0.9, 0.999), LEVELSET, floor=8)
add("ls_magic.vdb", b"\x21" + ls[1:], "damaged magic", LEVELSET)
add("ls_version.vdb", ls[:8] + struct.pack("<I", 300) + ls[12:], "version from the future", LEVELSET)
desc, (grid_pos, block_pos, end_pos) = vdb_descriptor(ls, b"surface")
patch = lambda at, b: ls[:at] + b + ls[at + len(b):]
add("ls_endpos.vdb", patch(desc + 16, struct.pack("<q", end_pos - 1000)), "grid end offset wrong", LEVELSET)
add("ls_endpos_far.vdb", patch(desc + 16, struct.pack("<q", 1 << 40)), "grid end offset past the file", LEVELSET)
add("ls_blockpos.vdb", patch(desc + 8, struct.pack("<q", block_pos + 8)), "grid block offset wrong", LEVELSET)
add("ls_compression.vdb", patch(grid_pos, struct.pack("<I", 0x80)), "unknown compression flag", LEVELSET)
add("ls_compression_none.vdb", patch(grid_pos, struct.pack("<I", 0)), "compression flags cleared", LEVELSET)
add("ls_metacount.vdb", patch(grid_pos + 4, struct.pack("<i", 0x7FFFFFFF)), "absurd metadata count", LEVELSET)
# the first leaf buffer: value mask, a flag for what follows (inactive values, a selection
# mask: io/Compression.h), then the chunk: its int64 size, then (blosc) its 16-byte header
flag = ls[block_pos + 64]
chunk = block_pos + 65 + (4 if flag in (2, 4) else 8 if flag == 5 else 0) + (64 if flag in (3, 4, 5) else 0)
add("ls_leafmask.vdb", patch(block_pos, bytes([ls[block_pos] ^ 0xFF])), "leaf mask differs from the topology", LEVELSET)
add("ls_leafflag.vdb", patch(block_pos + 64, b"\x7f"), "unknown leaf compression flag", LEVELSET)
add("ls_leafchunk.vdb", patch(chunk, struct.pack("<q", -(1 << 20))), "leaf chunk longer than a leaf", LEVELSET)
add("ls_leafchunk_big.vdb", patch(chunk, struct.pack("<q", 1 << 40)), "leaf chunk past the file", LEVELSET)
add("ls_leafblosc.vdb", patch(chunk + 8 + 4, struct.pack("<I", 1 << 30)), "blosc header: 1 GiB inside", LEVELSET)
add("ls_points.vdb", vdb, "a points VDB where a level set belongs", ("mesh",))

# meshes, through info and post
MESH = ("info", "post")
obj = read(S("mesh.obj"))
add("mesh_index.obj", obj + b"f 1 2 99999999\n", "face index past the vertices", MESH)
add("mesh_zero.obj", obj + b"f 0 1 2\n", "face index 0", MESH)
add("mesh_vertex.obj", b"v 1 2\n" + obj, "a vertex with two coordinates", MESH)
add("mesh_word.obj", b"v 1 x 2\n" + obj, "a word where a number belongs", MESH)
# an OBJ has no counts: a cut is seen only where it leaves half a line, or (post) no faces; these
# fall among the vertices and normals, which come first
cuts("mesh", "obj", obj, (0.1,), MESH)
cuts("mesh", "obj", obj, (0.25,), ("post",))
cuts("mesh", "ply", read(S("mesh.ply")), (0.01, 0.3, 0.7, 0.999), MESH)

# files that are not regular files
os.mkfifo(os.path.join(bad_dir, "fifo.bgeo"))
cases.append(("fifo.bgeo", "a FIFO", PARTICLE))
os.mkfifo(os.path.join(bad_dir, "fifo_levelset.vdb"))
cases.append(("fifo_levelset.vdb", "a FIFO", LEVELSET))
os.mkdir(os.path.join(bad_dir, "directory.vtk"))
cases.append(("directory.vtk", "a directory", PARTICLE))
for dev, name in (("/dev/zero", "zero.xyz"), ("/dev/urandom", "urandom.bgeo"), ("/dev/zero", "zero_levelset.vdb")):
    os.symlink(dev, os.path.join(bad_dir, name))
    cases.append((name, dev, LEVELSET if name.endswith(".vdb") else PARTICLE))

# --- runs ----------------------------------------------------------------------------------
SENTINEL = b"an existing output: keep me\n"


def command(cmd, path):
    if cmd == "info":
        return ["info", "--no-spacing", path], None
    if cmd == "convert":
        return ["convert", path, os.path.join(out_dir, "out.xyz")], "out.xyz"
    if cmd == "rasterize":
        return ["rasterize", path, "-r", R, "-o", os.path.join(out_dir, "out.vdb")], "out.vdb"
    if cmd == "reconstruct":
        return ["reconstruct", path, "-r", R, "-o", os.path.join(out_dir, "out.obj"),
                "--vdb", os.path.join(out_dir, "out.vdb")], "out.obj"
    if cmd == "mesh":
        return ["mesh", path, "-o", os.path.join(out_dir, "out.obj")], "out.obj"
    if cmd == "post":
        return ["post", path, "-o", os.path.join(out_dir, "out.obj")], "out.obj"
    raise ValueError(cmd)


def measured(args):
    """exit code, stdout, stderr, seconds and peak MiB of one run (killed after 20 s)."""
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        start = time.monotonic()
        proc = subprocess.Popen([BIN] + args, stdout=out, stderr=err)
        timer = threading.Timer(20, proc.kill)
        timer.start()
        _, status, usage = os.wait4(proc.pid, 0)
        timer.cancel()
        proc.returncode = os.waitstatus_to_exitcode(status)  # reaped here, not by Popen
        seconds = time.monotonic() - start
        out.seek(0)
        err.seek(0)
        return proc.returncode, out.read(), err.read(), seconds, usage.ru_maxrss / 1024


failures, runs, slowest, biggest = [], 0, (0, ""), (0, "")
for name, why, commands, *expect in cases:
    path = os.path.join(bad_dir, name)
    for cmd in commands:
        args, output = command(cmd, path)
        for f in os.listdir(out_dir):
            os.remove(os.path.join(out_dir, f))
        for existing in ("out.xyz", "out.vdb", "out.obj"):
            with open(os.path.join(out_dir, existing), "wb") as f:
                f.write(SENTINEL)
        code, stdout, stderr, seconds, mib = measured(args)
        runs += 1
        label = "%s %s (%s)" % (cmd, name, why)
        lines = stderr.decode(errors="replace").splitlines()
        problems = []
        if code != 1:
            problems.append("exit %d" % code)
        if len(lines) != 1 or not lines[0].startswith("fluidsurf: error: ") or name not in lines[0]:
            problems.append("stderr %r" % lines[:3])
        elif expect and expect[0] and expect[0] not in lines[0]:
            problems.append("message %r lacks %r" % (lines[0], expect[0]))
        if stdout:
            problems.append("stdout %r" % stdout[:120])
        left = sorted(set(os.listdir(out_dir)) - {"out.xyz", "out.vdb", "out.obj"})
        if left:
            problems.append("left behind %s" % left)
        for existing in ("out.xyz", "out.vdb", "out.obj"):
            if read(os.path.join(out_dir, existing)) != SENTINEL:
                problems.append("%s overwritten" % existing)
        if seconds >= MAX_SECONDS:
            problems.append("took %.2f s" % seconds)
        if mib >= MAX_MIB:
            problems.append("peak %.0f MiB" % mib)
        slowest = max(slowest, (seconds, label))
        biggest = max(biggest, (mib, label))
        if problems:
            failures.append("%s: %s" % (label, "; ".join(problems)))
        print("%-4s %5.2f s %4.0f MiB  %s" % ("ok" if not problems else "FAIL", seconds, mib, label))

shutil.rmtree(work)
print("%d broken files, %d runs; slowest %.2f s (%s); largest peak %.0f MiB (%s)" %
      (len(cases), runs, slowest[0], slowest[1], biggest[0], biggest[1]))
if failures:
    print("%d FAILED:" % len(failures))
    for f in failures:
        print("  " + f)
    sys.exit(1)
print("all runs: exit 1, one line naming the file, nothing left, existing outputs kept")
