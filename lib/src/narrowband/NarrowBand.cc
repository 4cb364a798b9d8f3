// NarrowBand.cc - band topology from the surface particles.
#include "narrowband/NarrowBand.h"

#include "util/LeafWords.h"
#include "util/MarkedNumbers.h"

#include <fluidsurf/Error.h>
#include <fluidsurf/ParticleSet.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

namespace fluidsurf {
namespace narrowband {

double effectiveBandWidth(const Params& params, const Level& level, double maxRadius)
{
    return std::max(params.bandWidth, maxRadius + level.voxelSize);
}

namespace {
struct BandBuilder
{
    const neighbors::CellIndex& particles;
    const std::vector<uint32_t>& seeds;
    double width, invDx;
    Context& ctx;
    openvdb::MaskTree::Ptr tree{new openvdb::MaskTree(false)};

    BandBuilder(const neighbors::CellIndex& p, const std::vector<uint32_t>& s, double w, double inv,
                Context& c)
        : particles(p), seeds(s), width(w), invDx(inv), ctx(c)
    {
    }
    BandBuilder(BandBuilder& o, tbb::split)
        : particles(o.particles), seeds(o.seeds), width(o.width), invDx(o.invDx), ctx(o.ctx)
    {
    }

    void operator()(const tbb::blocked_range<size_t>& r)
    {
        ctx.checkpoint();
        openvdb::tree::ValueAccessor<openvdb::MaskTree> acc(*tree);
        for (size_t s = r.begin(); s != r.end(); ++s) {
            const Vec3f& p = particles.positions[seeds[s]];
            int lo[3], hi[3];
            // Vertices within the width, inclusive up to 1e-6 voxel: a lattice particle exactly
            // 2r from a vertex must not fall in or out by the rounding of its float position.
            for (int a = 0; a < 3; ++a) {
                lo[a] = int(std::ceil((p[a] - width) * invDx - 1e-6));
                hi[a] = int(std::floor((p[a] + width) * invDx + 1e-6));
            }
            if (lo[0] > hi[0] || lo[1] > hi[1] || lo[2] > hi[2]) continue; // (no leaf made)
            // leaf by leaf (at most 2 an axis), a word of y and z bits an x (util/LeafWords.h):
            // a seed's box is about 5 x 5 x 5 voxels, set voxel by voxel a tenth of the frame's
            // work on 16 cores
            for (int lx = lo[0] & ~7; lx <= hi[0]; lx += 8)
                for (int ly = lo[1] & ~7; ly <= hi[1]; ly += 8)
                    for (int lz = lo[2] & ~7; lz <= hi[2]; lz += 8) {
                        const uint64_t word =
                            util::boxWord(std::max(lo[1], ly) - ly, std::min(hi[1], ly + 7) - ly,
                                          std::max(lo[2], lz) - lz, std::min(hi[2], lz + 7) - lz);
                        auto& mask = acc.touchLeaf(openvdb::Coord(lx, ly, lz))->getValueMask();
                        for (int x = std::max(lo[0], lx); x <= std::min(hi[0], lx + 7); ++x)
                            mask.template getWord<uint64_t>(x - lx) |= word;
                    }
        }
    }
    /// The other's nodes are moved in where this tree has none there (the threads' seeds are
    /// runs of the index's order, so their trees overlap only at their borders); a leaf both
    /// have gets the union of their masks. (topologyUnion copied every leaf of the other, one at
    /// a time: the joins were most of this step's time on 16 threads.)
    void join(BandBuilder& other) { tree->merge(*other.tree, openvdb::MERGE_ACTIVE_STATES); }
};
/// Bytes a band voxel costs at least on its way to the level set: its float value, its share
/// of the leaf's masks and of the field's block.
constexpr double kBytesPerBandVoxel = 8;

} // namespace

// (issue 63: a voxel of 0.03 r on a 32k-particle frame took 23.7 GB, and the machine with it)
void requireBandMemory(size_t seeds, const Params& params, const Level& level, double width,
                       Context& ctx)
{
    const double dx = level.voxelSize, spacing = 2 * params.radius;
    const double box = std::pow(2 * width / dx + 1, 3);
    const double perSeed = std::min(box, spacing * spacing * (2 * width + dx) / (dx * dx * dx));
    char what[200];
    std::snprintf(what, sizeof(what),
                  "the narrow band of %zu surface particles at a voxel of %g (%g r)", seeds, dx,
                  dx / params.radius);
    ctx.requireMemory(double(seeds) * perSeed * kBytesPerBandVoxel, what);
}

openvdb::MaskTree::Ptr buildNarrowBand(const neighbors::CellIndex& particles,
                                       const classify::Classification& classes,
                                       const Params& params, const Level& level, double width,
                                       Context& ctx)
{
    // the seeds in index order, listed on all threads (13.1M classes: 0.015 s on one)
    const util::MarkedNumbers marked(classes.classes.size(), [&](size_t i) {
        const uint8_t c = classes.classes[i];
        return classify::isSurface(c) || (params.keepIsolated && c == classify::Isolated);
    });
    requireBandMemory(marked.count(), params, level, width, ctx);
    std::vector<uint32_t> seeds(marked.count());
    marked.forEach([&](size_t i, bool seed, size_t k) {
        if (seed) seeds[k - 1] = uint32_t(i);
    });
    BandBuilder builder(particles, seeds, width, 1 / level.voxelSize, ctx);
    tbb::parallel_reduce(tbb::blocked_range<size_t>(0, seeds.size(), 256), builder);
    return builder.tree;
}

openvdb::CoordBBox boundingVolume(const neighbors::CellIndex& particles, const Params& params,
                                  const Level& level)
{
    if (particles.size() == 0) return openvdb::CoordBBox(); // empty
    const BBox3f box = boundsOf(particles.positions.data(), particles.size());
    const double inv = 1 / level.voxelSize, R = params.influenceRadius;
    openvdb::Coord lo, hi;
    for (int a = 0; a < 3; ++a) {
        lo[a] = int(std::floor((box.min[a] - R) * inv));
        hi[a] = int(std::ceil((box.max[a] + R) * inv));
    }
    return openvdb::CoordBBox(lo, hi);
}

double checkDenseMemory(const openvdb::CoordBBox& box, double bytesPerVertex, const char* what)
{
    const openvdb::Coord d = box.dim();
    const double bytes = double(d.x()) * double(d.y()) * double(d.z()) * bytesPerVertex;
    const double physical = double(sysconf(_SC_PHYS_PAGES)) * double(sysconf(_SC_PAGE_SIZE));
    if (physical > 0 && bytes > 0.8 * physical)
        throw ValueError(
            std::string(what) + " needs about " + std::to_string(int64_t(bytes / (1 << 20))) +
            " MiB for " + std::to_string(d.x()) + " x " + std::to_string(d.y()) + " x " +
            std::to_string(d.z()) + " vertices, more than this machine has; use the narrow band");
    return bytes;
}

} // namespace narrowband
} // namespace fluidsurf
