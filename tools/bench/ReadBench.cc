// ReadBench.cc - `fluidsurf_bench io`: writes one generated frame (the drop scene, ids and
// velocities stripped to positions only so every format carries the same bytes of payload) in
// each writable format, then reads each file `repeat` times through the public API (the points
// .vdb and a level set also through OpenVDB's own reader, in the same run). The file
// is in the page cache (one untimed warm-up read), so this measures parsing and copying, not
// the disk.
#include "Bench.h"

#include <fluidsurf/Rasterize.h>
#include <fluidsurf/Scenes.h>
#include <fluidsurf/io/LevelSetIO.h>
#include <fluidsurf/io/ParticleIO.h>

#include <openvdb/io/File.h>
#include <openvdb/points/PointDataGrid.h>

#include <sys/stat.h>
#include <unistd.h>

namespace fluidsurf {
namespace bench {

namespace {
struct Row
{
    std::string name, file;
    double bytes = 0, secs = 0;
    size_t particles = 0;
};

Row timeRead(const std::string& name, const std::string& path, int repeat)
{
    Row row{name, path};
    std::vector<double> t;
    io::readParticles(path); // untimed warm-up: page cache and first-touch allocations
    for (int k = 0; k < repeat; ++k) {
        ParticleSet ps;
        t.push_back(seconds([&] { ps = io::readParticles(path); }));
        row.particles = ps.size();
    }
    struct stat st;
    if (::stat(path.c_str(), &st) == 0) row.bytes = double(st.st_size);
    row.secs = median(t);
    return row;
}
/// A level set of the same frame: io::readLevelSet (our walk of every node, then OpenVDB from
/// memory) against OpenVDB's own io::File reader (delayed loading, every leaf then touched so
/// that it is decoded too), in the same run.
void timeLevelSetReads(const ParticleSet& ps, double radius, const std::string& base, int repeat,
                       std::vector<Row>& rows)
{
    const std::string path = base + "_surface.vdb";
    io::writeLevelSet({rasterizeParticles(ps, Params::fromRadius(radius)).grid}, path);
    Row ours{"level set .vdb: io::readLevelSet", path},
        theirs{"level set .vdb: OpenVDB io::File", path};
    std::vector<double> a, b;
    io::readLevelSet(path); // warm-up
    for (int k = 0; k < repeat; ++k) {
        a.push_back(seconds([&] { io::readLevelSet(path); }));
        b.push_back(seconds([&] {
            openvdb::io::File f(path);
            f.open();
            auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>((*f.getGrids())[0]);
            float sum = 0;
            for (auto leaf = grid->tree().cbeginLeaf(); leaf; ++leaf)
                sum += leaf->getValue(0);
            f.close();
            if (sum == 12345.f) std::printf(" "); // keep the loop
        }));
    }
    struct stat st;
    if (::stat(path.c_str(), &st) == 0) ours.bytes = theirs.bytes = double(st.st_size);
    ours.secs = median(a), theirs.secs = median(b);
    rows.push_back(ours), rows.push_back(theirs);
    ::unlink(path.c_str());
}
/// OpenVDB's own io::File reader doing what io::readParticles does with a points .vdb: every
/// leaf's positions decoded and turned into world space; the baseline of the row before it.
Row timeOpenVdbPointRead(const std::string& path, int repeat)
{
    Row row{"VDB points: OpenVDB io::File + world positions", path};
    std::vector<double> t;
    for (int k = 0; k <= repeat; ++k) { // the first read is an untimed warm-up
        std::vector<openvdb::Vec3f> positions;
        const double s = seconds([&] {
            openvdb::io::File f(path);
            f.open();
            auto grid = openvdb::gridPtrCast<openvdb::points::PointDataGrid>((*f.getGrids())[0]);
            const openvdb::math::Transform& xform = grid->transform();
            for (auto leaf = grid->tree().cbeginLeaf(); leaf; ++leaf) {
                openvdb::points::AttributeHandle<openvdb::Vec3f> h(leaf->constAttributeArray("P"));
                for (auto idx = leaf->beginIndexAll(); idx; ++idx)
                    positions.push_back(openvdb::Vec3f(xform.indexToWorld(
                        idx.getCoord().asVec3d() + openvdb::Vec3d(h.get(*idx)))));
            }
            f.close();
        });
        if (k > 0) t.push_back(s);
        row.particles = positions.size();
    }
    struct stat st;
    if (::stat(path.c_str(), &st) == 0) row.bytes = double(st.st_size);
    row.secs = median(t);
    return row;
}
} // namespace

int runReadBench(const ReadBenchOptions& o)
{
    SceneParams sp;
    sp.count = o.count;
    sp.radius = 0.01;
    ParticleSet ps = generateScene(Scene::Drop, sp);
    ps.attributes.clear();
    const std::string base = o.dir + "/fluidsurf_bench_" + std::to_string(::getpid());
    struct Case
    {
        const char* name;
        const char* ext;
    };
    const Case cases[] = {{"VTK legacy binary", ".vtk"},     {"PLY binary LE", ".ply"},
                          {"BGEO v5 uncompressed", ".bgeo"}, {"xyz (raw float32)", ".xyz"},
                          {"BGEO v5 gzip", ".bgeo.gz"},      {"VDB points (Blosc)", ".vdb"}};
    std::vector<Row> rows;
    for (const Case& c : cases) {
        const std::string path = base + c.ext;
        io::writeParticles(ps, path);
        rows.push_back(timeRead(c.name, path, o.repeat));
        if (std::string(c.ext) == ".vdb") rows.push_back(timeOpenVdbPointRead(path, o.repeat));
        ::unlink(path.c_str());
    }
    timeLevelSetReads(ps, sp.radius, base, o.repeat, rows);
    if (!o.shared.empty()) {
        const char* real[] = {"large/dam_obstacle_t0.20_1704086_particles.xyz",
                              "large/dam_obstacle_t0.50_398850_particles.vtk",
                              "real/hilbert_46843_particles.bgeo"};
        for (const char* r : real) {
            const std::string path = o.shared + "/" + r;
            if (::access(path.c_str(), R_OK) == 0) rows.push_back(timeRead(r, path, o.repeat));
        }
    }
    if (o.json) {
        std::printf(
            "{\"benchmark\": \"io\", \"generated_particles\": %zu, \"repeat\": %d, \"rows\": [\n",
            ps.size(), o.repeat);
        for (size_t i = 0; i < rows.size(); ++i)
            std::printf("  {\"case\": \"%s\", \"particles\": %zu, \"bytes\": %.0f, \"median_s\": "
                        "%.6f, \"MBps\": %.1f}%s\n",
                        rows[i].name.c_str(), rows[i].particles, rows[i].bytes, rows[i].secs,
                        rows[i].bytes / rows[i].secs / 1e6, i + 1 < rows.size() ? "," : "");
        std::printf("], \"peak_rss_MiB\": %.1f}\n", peakRssMiB());
        return 0;
    }
    std::printf("| case | particles | file MB | median read s | MB/s | Mparticles/s "
                "|\n|---|---:|---:|---:|---:|---:|\n");
    for (const Row& r : rows)
        std::printf("| %s | %zu | %.1f | %.4f | %.0f | %.1f |\n", r.name.c_str(), r.particles,
                    r.bytes / 1e6, r.secs, r.bytes / r.secs / 1e6,
                    double(r.particles) / r.secs / 1e6);
    std::printf("\nmedian of %d reads each; peak RSS %.0f MiB\n", o.repeat, peakRssMiB());
    return 0;
}

} // namespace bench
} // namespace fluidsurf
