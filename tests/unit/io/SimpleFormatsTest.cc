// Raw .xyz, CSV/text and NumPy .npy readers.
#include "TestData.h"

using namespace fluidsurf;
using namespace fluidsurf::test;
using io::ParticleFormat;

TEST(Xyz, RawFloat32Triples)
{
    ByteBuilder b;
    for (float v : {1.f, 2.f, 3.f, -0.5f, 1e-20f, 4e20f})
        b.le(v);
    const ParticleSet ps = readBytes(b.s, ParticleFormat::Xyz);
    ASSERT_EQ(ps.size(), 2u);
    EXPECT_EQ(ps.positions[1], Vec3f(-0.5f, 1e-20f, 4e20f));
    EXPECT_NE(readError(b.s.substr(0, 13), ParticleFormat::Xyz).find("not a multiple of 12"),
              std::string::npos);
}

TEST(Xyz, TextXyzIsRecognised)
{
    const ParticleSet ps = readBytes("1 2 3\n4 5 6\n", ParticleFormat::Xyz);
    ASSERT_EQ(ps.size(), 2u);
    EXPECT_EQ(ps.positions[1], Vec3f(4.f, 5.f, 6.f));
}

TEST(Csv, HeaderWithVectorColumnsAndComments)
{
    const std::string f =
        "# exported\nid,Points:0,Points:1,Points:2,velocity:0,velocity:1,velocity:2\n"
        "0,1.5,2,3,0,0,-1\n1,-1,-2,-3,1,1,1\n\n";
    const ParticleSet ps = readBytes(f, ParticleFormat::Csv);
    ASSERT_EQ(ps.size(), 2u);
    EXPECT_EQ(ps.positions[0], Vec3f(1.5f, 2.f, 3.f));
    ASSERT_NE(ps.find(AttributeRole::Velocity), nullptr);
    EXPECT_EQ(ps.find("velocity")->floats[2], -1.f);
    EXPECT_EQ(ps.find("id")->floats, (std::vector<float>{0.f, 1.f}));
}

TEST(Csv, NoHeaderWhitespaceAndSemicolon)
{
    EXPECT_EQ(readBytes("1\t2\t3\n4\t5\t6\n", ParticleFormat::Csv).positions[1],
              Vec3f(4.f, 5.f, 6.f));
    const ParticleSet ps = readBytes("x;y;z;rho\n1;2;3;1000\n", ParticleFormat::Csv);
    EXPECT_EQ(ps.positions[0], Vec3f(1.f, 2.f, 3.f));
    EXPECT_EQ(ps.find(AttributeRole::Density)->floats[0], 1000.f);
}

TEST(Csv, RaggedRowsAndBadNumbersNamed)
{
    EXPECT_NE(readError("1,2,3\n4,5\n", ParticleFormat::Csv).find("line 2 has 2 columns"),
              std::string::npos);
    EXPECT_NE(readError("1,2,3\n4,5,abc\n", ParticleFormat::Csv).find("'abc' is not a number"),
              std::string::npos);
    EXPECT_NE(readError("a,b,c\n1,2,3\n", ParticleFormat::Csv).find("no x, y, z"),
              std::string::npos);
}

TEST(Csv, ManyPiecesInOrderAndTheFirstBadLineNamed)
{
    // 200,000 rows (about 5 MB: the reader parses it in pieces of 1 MiB on all threads), a
    // comment every 1,000 rows and CRLF line ends. Values exact in float, from the row number.
    const size_t n = 200000;
    std::vector<std::string> lines = {"x,y,z,v_0,v_1"};
    std::vector<size_t> rowLine(n); // the file's line number (from 1) of each row
    for (size_t i = 0; i < n; ++i) {
        if (i % 1000 == 0) lines.push_back("# rows from " + std::to_string(i));
        lines.push_back(std::to_string(i) + ".25," + std::to_string(i % 977) + ",-" +
                        std::to_string(i) + ".5, " + std::to_string(i % 13) + " ,\"7\"");
        rowLine[i] = lines.size();
    }
    const auto join = [](const std::vector<std::string>& l) {
        std::string s;
        for (const std::string& x : l)
            s += x + "\r\n";
        return s;
    };
    TempDir dir;
    for (const auto& [way, ps] :
         readFromMemoryAndFile(join(lines), ParticleFormat::Csv, dir.path("many.csv"))) {
        SCOPED_TRACE(way);
        ASSERT_EQ(ps.size(), n);
        const Attribute* v = ps.find("v");
        ASSERT_TRUE(v && v->components == 2);
        size_t bad = 0;
        for (size_t i = 0; i < n; ++i) {
            bad += ps.positions[i] != Vec3f(float(i) + 0.25f, float(i % 977), -(float(i) + 0.5f));
            bad += v->floats[2 * i] != float(i % 13) || v->floats[2 * i + 1] != 7.f;
        }
        EXPECT_EQ(bad, 0u);
    }

    // Two bad rows in different pieces: the first one in the file is named, by its line.
    std::vector<std::string> two = lines;
    two[rowLine[150000] - 1] = "1,2";
    two[rowLine[180000] - 1] = "1,2,3,4,abc";
    EXPECT_NE(readError(join(two), ParticleFormat::Csv)
                  .find("line " + std::to_string(rowLine[150000]) +
                        " has 2 columns, the first data line had 5"),
              std::string::npos);
    writeFile(dir.path("two.csv"), join(two));
    try {
        io::readParticles(dir.path("two.csv"));
        ADD_FAILURE() << "a bad file was read";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("line " + std::to_string(rowLine[150000]) +
                                             " has 2 columns"),
                  std::string::npos)
            << e.what();
    }
    two[rowLine[150000] - 1] = lines[rowLine[150000] - 1];
    EXPECT_NE(readError(join(two), ParticleFormat::Csv)
                  .find("line " + std::to_string(rowLine[180000]) + ": 'abc' is not a number"),
              std::string::npos);
    // A line past 1 MiB (2^20 + 1 bytes before its end) is refused where it starts; one byte
    // shorter, it is read (here: as a comment). One of 3 MiB spans pieces that end inside it.
    for (const int length : {-1, 0, 3 << 20}) {
        const bool tooLong = length >= 0;
        std::vector<std::string> l = lines;
        l[rowLine[120000] - 1] =
            "#" +
            std::string(length > 0 ? size_t(length) : (size_t(1) << 20) - size_t(-length), 'c');
        const std::string file = join(l);
        size_t at = 0;
        for (size_t k = 0; k + 1 < rowLine[120000]; ++k)
            at += l[k].size() + 2;
        writeFile(dir.path("long.csv"), file);
        const std::string e = readError(file, ParticleFormat::Csv);
        std::string fromFile;
        try {
            io::readParticles(dir.path("long.csv"));
        } catch (const InputError& x) {
            fromFile = x.what();
        }
        EXPECT_EQ(fromFile.empty(), !tooLong);
        if (tooLong) EXPECT_EQ(fromFile.substr(fromFile.find(": ")), e.substr(e.find(": ")));
        if (tooLong)
            EXPECT_NE(e.find("line too long in a text line (at byte " + std::to_string(at) + ")"),
                      std::string::npos)
                << e;
        else
            EXPECT_EQ(readBytes(file, ParticleFormat::Csv).size(), n - 1);
    }
}

namespace {
std::string npy(const std::string& descr, bool fortran, const std::string& shape,
                const std::string& data, int version = 1)
{
    std::string dict = "{'descr': '" + descr +
                       "', 'fortran_order': " + (fortran ? "True" : "False") +
                       ", 'shape': " + shape + ", }";
    const size_t pre = version == 1 ? 10 : 12;
    while ((pre + dict.size() + 1) % 64)
        dict += ' ';
    dict += '\n';
    ByteBuilder b;
    b.text("\x93NUMPY").le(uint8_t(version)).le(uint8_t(0));
    if (version == 1)
        b.le(uint16_t(dict.size()));
    else
        b.le(uint32_t(dict.size()));
    return b.s + dict + data;
}
} // namespace

TEST(Npy, Float32CAndFloat64FortranAndBigEndian)
{
    ByteBuilder f4;
    for (float v : {1.f, 2.f, 3.f, 4.f, 5.f, 6.f})
        f4.le(v);
    ParticleSet ps = readBytes(npy("<f4", false, "(2, 3)", f4.s), ParticleFormat::Npy);
    ASSERT_EQ(ps.size(), 2u);
    EXPECT_EQ(ps.positions[1], Vec3f(4.f, 5.f, 6.f));

    ByteBuilder f8; // Fortran order: all x, then all y, then all z
    for (double v : {1.0, 4.0, 2.0, 5.0, 3.0, 6.0})
        f8.le(v);
    ps = readBytes(npy("<f8", true, "(2, 3)", f8.s, 2), ParticleFormat::Npy);
    EXPECT_EQ(ps.positions[0], Vec3f(1.f, 2.f, 3.f));
    EXPECT_EQ(ps.positions[1], Vec3f(4.f, 5.f, 6.f));

    ByteBuilder be;
    for (float v : {7.f, 8.f, 9.f})
        be.be(v);
    EXPECT_EQ(readBytes(npy(">f4", false, "(1, 3)", be.s), ParticleFormat::Npy).positions[0],
              Vec3f(7.f, 8.f, 9.f));
}

TEST(Npy, WrongShapeOrTypeNamed)
{
    EXPECT_NE(readError(npy("<f4", false, "(2, 4)", std::string(32, '\0')), ParticleFormat::Npy)
                  .find("not (N, 3)"),
              std::string::npos);
    EXPECT_NE(readError(npy("<i4", false, "(1, 3)", std::string(12, '\0')), ParticleFormat::Npy)
                  .find("unsupported dtype"),
              std::string::npos);
    EXPECT_NE(readError(npy("<f4", false, "(5, 3)", std::string(12, '\0')), ParticleFormat::Npy)
                  .find("promises 5"),
              std::string::npos);
}

TEST(Npy, FilesAreReadFromWhereTheArrayLies)
{
    // 200,003 rows: several slices of the file, and in Fortran order a slice holds the end of
    // one axis and the start of the next. Every value differs.
    const size_t n = 200003;
    const auto value = [](size_t i, int c) { return double(i) * 0.125 + c * 1e6 + 1.0 / 3; };
    TempDir dir;
    for (const bool fortran : {false, true})
        for (const bool wide : {false, true})
            for (const bool big : {false, true}) {
                SCOPED_TRACE(std::string(fortran ? "Fortran" : "C") + (wide ? " f8" : " f4") +
                             (big ? " big-endian" : ""));
                ByteBuilder a;
                for (size_t k = 0; k < 3 * n; ++k) {
                    const size_t i = fortran ? k % n : k / 3;
                    const int c = int(fortran ? k / n : k % 3);
                    if (wide)
                        big ? a.be(value(i, c)) : a.le(value(i, c));
                    else
                        big ? a.be(float(value(i, c))) : a.le(float(value(i, c)));
                }
                const std::string bytes =
                    npy(std::string(big ? ">" : "<") + (wide ? "f8" : "f4"), fortran,
                        "(" + std::to_string(n) + ", 3)", a.s, fortran ? 2 : 1);
                writeFile(dir.path("a.npy"), bytes);
                const ParticleSet ps = io::readParticles(dir.path("a.npy"));
                ASSERT_EQ(ps.size(), n);
                size_t bad = 0;
                for (size_t i = 0; i < n; ++i)
                    for (int c = 0; c < 3; ++c)
                        bad += ps.positions[i][c] != float(value(i, c));
                EXPECT_EQ(bad, 0u);
                // cut inside the last value: the message the same bytes give from memory
                const std::string cut = bytes.substr(0, bytes.size() - 3);
                writeFile(dir.path("cut.npy"), cut);
                std::string fromFile;
                try {
                    io::readParticles(dir.path("cut.npy"));
                } catch (const InputError& e) {
                    fromFile = e.what();
                }
                const std::string fromMemory = readError(cut, ParticleFormat::Npy);
                ASSERT_NE(fromMemory.find("header promises 200003 rows"), std::string::npos)
                    << fromMemory;
                EXPECT_EQ(fromFile.substr(fromFile.find(": ")),
                          fromMemory.substr(fromMemory.find(": ")));
            }
}

TEST(Xyz, FilesAreReadByChunksStraightIntoThePositions)
{
    // A raw .xyz file is read by all threads in 4 MiB chunks into the positions: 1,000,003
    // particles (12 MB, not a whole number of chunks), every coordinate a different value.
    TempDir dir;
    const size_t n = 1000003;
    std::string bytes(12 * n, '\0');
    auto coordinate = [](size_t i, int a) { return float(3 * i + size_t(a)) * 0.25f - 1e5f; };
    for (size_t i = 0; i < n; ++i)
        for (int a = 0; a < 3; ++a) {
            const float v = coordinate(i, a);
            std::memcpy(&bytes[12 * i + 4 * size_t(a)], &v, 4);
        }
    writeFile(dir.path("big.xyz"), bytes);
    io::ReadInfo info;
    const ParticleSet ps = io::readParticles(dir.path("big.xyz"), {}, &info);
    ASSERT_EQ(ps.size(), n);
    for (size_t i = 0; i < n; ++i)
        ASSERT_EQ(ps.positions[i], Vec3f(coordinate(i, 0), coordinate(i, 1), coordinate(i, 2)))
            << i;
    EXPECT_EQ(info.fileBytes, 12 * n);
    EXPECT_EQ(info.detail, "raw float32 little-endian");

    // the common checks still apply: two non-finite particles, the first one named
    const float nan = std::nanf(""), inf = INFINITY;
    std::memcpy(&bytes[12 * 700001 + 4], &nan, 4);
    std::memcpy(&bytes[12 * 900000], &inf, 4);
    writeFile(dir.path("nan.xyz"), bytes);
    try {
        io::readParticles(dir.path("nan.xyz"));
        ADD_FAILURE() << "non-finite positions were read";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("2 particle(s) have NaN/Inf coordinates (first: "
                                             "particle 700001)"),
                  std::string::npos)
            << e.what();
    }
    io::ReadOptions drop;
    drop.dropNonFinite = true;
    EXPECT_EQ(io::readParticles(dir.path("nan.xyz"), drop, &info).size(), n - 2);
    EXPECT_EQ(info.droppedNonFinite, 2u);

    // and the refusals by size, by content and of an empty file; text is still CSV
    auto error = [&](const std::string& name, const std::string& content) {
        writeFile(dir.path(name), content);
        try {
            io::readParticles(dir.path(name));
        } catch (const InputError& e) {
            return std::string(e.what());
        }
        return std::string();
    };
    EXPECT_NE(error("cut.xyz", bytes.substr(0, 12 * 1000 + 5)).find("not a multiple of 12"),
              std::string::npos);
    EXPECT_NE(error("ply.xyz",
                    "ply\nformat binary_little_endian 1.0\nend_header\n" + bytes.substr(0, 120))
                  .find("the name says raw XYZ but the content is PLY"),
              std::string::npos);
    EXPECT_NE(error("empty.xyz", "").find("file is empty"), std::string::npos);
    writeFile(dir.path("text.xyz"), "1 2 3\n4 5 6\n");
    EXPECT_EQ(io::readParticles(dir.path("text.xyz")).positions[1], Vec3f(4.f, 5.f, 6.f));
}
