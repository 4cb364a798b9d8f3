// ActiveTiles.cc - level sets stored with active tiles, meshed as what they are (issue 63).
//
// Other tools prune a level set's uniform parts into tiles and may leave them active. Those
// used to be voxelized whole: a tiled 512^3 box became 134M voxels, and its cells across the
// box's faces still met inactive background corners, so our mesher gave 0 triangles. Here a
// tile's inside has no surface (its value is one number); only its faces can, where the value
// across the face has the other sign, or where an active voxel of the band meets it. Those face
// voxels and the ones across from them are seeds; the seeds grown by one voxel (26 neighbours:
// every corner of a cell around a crossing edge) become active voxels of a copy of the tree,
// with the values the grid has there; every tile is then made inactive. The mesh is the surface
// of the voxelized grid, at a cost in the tiles' faces, not their volume.
#include "mesh/MarchingCubes.h"

#include <fluidsurf/Error.h>

#include <openvdb/tools/Morphology.h>
#include <openvdb/tree/LeafManager.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <atomic>
#include <climits>
#include <cmath>
#include <memory>
#include <unordered_set>
#include <vector>

namespace fluidsurf {
namespace mesh {

namespace {

using openvdb::Coord;
using openvdb::CoordBBox;
using openvdb::FloatTree;
using openvdb::MaskTree;
using FloatLeaf = FloatTree::LeafNodeType;

struct Tile
{
    CoordBBox box;
    float value;
};

/// Bytes a float leaf costs: its node and its 512 values (held apart from the node).
constexpr double kLeafBytes = double(sizeof(FloatLeaf) + FloatLeaf::SIZE * sizeof(float));
/// Bytes a seeded 8 x 8 face block ((p, q) pairs across a tile's face where the surface can
/// pass) may cost at the end: a float leaf and a mask leaf on each side, half as much again for
/// the one-voxel growth around them, and its share of the mesh (a flat 8 x 8 face: 128
/// triangles, 64 vertices with normals). A checkerboard of a million 8^3 tiles, every face a
/// surface, took 14 GB and 122 s to a 464M-triangle, 30 GB OBJ before this refused it.
constexpr double kBytesPerBlock =
    1.5 * 2 * (kLeafBytes + double(sizeof(MaskTree::LeafNodeType))) + 128 * 12 + 64 * 24;

struct Seeder
{
    const FloatTree& tree;
    const std::vector<Tile>& tiles;
    Context& ctx;
    std::atomic<size_t>& seededBlocks;
    const std::string& what;
    MaskTree seeds;

    Seeder(const FloatTree& t, const std::vector<Tile>& ts, Context& c, std::atomic<size_t>& n,
           const std::string& w)
        : tree(t), tiles(ts), ctx(c), seededBlocks(n), what(w), seeds(false)
    {
    }
    Seeder(Seeder& o, tbb::split)
        : tree(o.tree), tiles(o.tiles), ctx(o.ctx), seededBlocks(o.seededBlocks), what(o.what),
          seeds(false)
    {
    }
    void join(Seeder& o) { seeds.topologyUnion(o.seeds); }

    void operator()(const tbb::blocked_range<size_t>& r)
    {
        ctx.checkpoint();
        openvdb::tree::ValueAccessor<const FloatTree> acc(tree);
        openvdb::tree::ValueAccessor<MaskTree> out(seeds);
        size_t blocks = 0;
        for (size_t t = r.begin(); t != r.end(); ++t) {
            const Tile& tile = tiles[t];
            const bool inside = tile.value < 0;
            for (int a = 0; a < 3; ++a) {
                const int b = (a + 1) % 3, c = (a + 2) % 3;
                for (int side = -1; side <= 1; side += 2) {
                    const int pa = side < 0 ? tile.box.min()[a] : tile.box.max()[a];
                    if ((side < 0 && pa == INT_MIN) || (side > 0 && pa == INT_MAX)) continue;
                    for (int jb = tile.box.min()[b]; jb <= tile.box.max()[b]; jb += 8)
                        for (int jc = tile.box.min()[c]; jc <= tile.box.max()[c]; jc += 8) {
                            Coord q0;
                            q0[a] = pa + side, q0[b] = jb, q0[c] = jc;
                            const FloatLeaf* leaf = acc.probeConstLeaf(q0);
                            // no leaf across: one tile or the background covers the block
                            if (!leaf && (acc.getValue(q0) < 0) == inside) continue;
                            bool any = false;
                            for (int u = 0; u < 8; ++u)
                                for (int v = 0; v < 8; ++v) {
                                    Coord q = q0;
                                    q[b] += u, q[c] += v;
                                    if (leaf && (leaf->getValue(q) < 0) == inside &&
                                        !leaf->isValueOn(q))
                                        continue;
                                    Coord p = q;
                                    p[a] = pa;
                                    out.setValueOn(p);
                                    out.setValueOn(q);
                                    any = true;
                                }
                            blocks += any;
                        }
                }
            }
        }
        const size_t total = seededBlocks += blocks;
        ctx.requireMemory(double(total) * kBytesPerBlock, what);
    }
};

/// Bytes of the internal nodes the seeds of these tiles will need, before one is made: every
/// node (of 128^3 and of 4096^3 voxels) that a tile's faces or the voxels across them reach,
/// once in the seeds' mask and once in the float copy. Far-apart tiles need nodes of their own on
/// each side (4,096 tiles 4,096 voxels apart took 7.7 GB and 29 s): the faces' blocks alone did
/// not see that.
double nodeBytes(const std::vector<Tile>& tiles)
{
    using Upper = FloatTree::RootNodeType::ChildNodeType; // 4096^3
    using Lower = Upper::ChildNodeType;                   // 128^3
    using MaskUpper = MaskTree::RootNodeType::ChildNodeType;
    using MaskLower = MaskUpper::ChildNodeType;
    std::unordered_set<Coord> upper, lower;
    auto cover = [](std::unordered_set<Coord>& set, const CoordBBox& box, int dim) {
        const auto down = [dim](int v) { return int(std::floor(double(v) / dim)) * dim; };
        for (int x = down(box.min().x()); x <= box.max().x(); x += dim)
            for (int y = down(box.min().y()); y <= box.max().y(); y += dim)
                for (int z = down(box.min().z()); z <= box.max().z(); z += dim)
                    set.insert(Coord(x, y, z));
    };
    for (const Tile& t : tiles) {
        CoordBBox grown = t.box; // the faces and one voxel past them
        grown.expand(1);
        cover(upper, grown, int(Upper::DIM));
        if (t.box.dim().x() <= int(Lower::DIM)) { // (a larger tile's faces: counted as blocks)
            cover(lower, grown, int(Lower::DIM));
        }
    }
    return double(upper.size()) * double(sizeof(Upper) + sizeof(MaskUpper)) +
           double(lower.size()) * double(sizeof(Lower) + sizeof(MaskLower));
}

} // namespace

const FloatTree& leafOnlyTree(const openvdb::FloatGrid& grid, FloatTree::Ptr& keep, Context& ctx)
{
    const FloatTree& tree = grid.tree();
    if (!tree.hasActiveTiles()) return tree;
    std::vector<Tile> tiles;
    {
        FloatTree::ValueOnCIter it = tree.cbeginValueOn();
        it.setMaxDepth(FloatTree::ValueOnCIter::LEAF_DEPTH - 1);
        for (; it; ++it)
            tiles.push_back({it.getBoundingBox(), *it});
    }
    const std::string what = "meshing the " + std::to_string(tiles.size()) +
                             " active tiles of grid '" + grid.getName() + "'";
    ctx.requireMemory(double(tree.memUsage()) + nodeBytes(tiles), what);
    std::atomic<size_t> seededBlocks{0};
    Seeder seeder(tree, tiles, ctx, seededBlocks, what);
    tbb::parallel_reduce(tbb::blocked_range<size_t>(0, tiles.size(), 64), seeder);
    MaskTree& seeds = seeder.seeds;
    // before the growth: the copy, the seeds' internal nodes three times over (the mask grown,
    // and the float tree's), and the blocks' leaves and mesh
    ctx.requireMemory(double(tree.memUsage()) + 3 * double(seeds.memUsage()) +
                          double(seededBlocks.load()) * kBytesPerBlock,
                      what);
    openvdb::tools::dilateActiveValues(seeds, 1, openvdb::tools::NN_FACE_EDGE_VERTEX,
                                       openvdb::tools::IGNORE_TILES);
    // Now with the growth counted: the copy of the tree, the seeds' leaves as float leaves, the
    // internal nodes they need (as many as the mask's, and as large: tiles far apart each need
    // nodes of their own beside them, 300 KB a pair), the mask itself, and the mesh's share.
    const double maskBytes = double(seeds.memUsage()),
                 maskLeafBytes = double(seeds.leafCount()) * sizeof(MaskTree::LeafNodeType);
    ctx.requireMemory(double(tree.memUsage()) + double(seeds.leafCount()) * kLeafBytes +
                          2 * (maskBytes - maskLeafBytes) + maskBytes +
                          double(seededBlocks.load()) * (128 * 12 + 64 * 24),
                      what);

    keep = std::make_shared<FloatTree>(tree);
    // Seed leaves where the copy has a leaf: their voxels made active in place (each its own
    // leaf, so in parallel); elsewhere a new leaf with the grid's values there (a tile's, or the
    // background), its seeds active, added one by one below.
    openvdb::tree::LeafManager<MaskTree> seedLeaves(seeds);
    std::vector<std::unique_ptr<FloatLeaf>> fresh(seedLeaves.leafCount());
    tbb::parallel_for(seedLeaves.leafRange(), [&](const auto& range) {
        ctx.checkpoint();
        openvdb::tree::ValueAccessor<const FloatTree> original(tree);
        for (auto s = range.begin(); s; ++s) {
            const Coord origin = s->origin();
            if (FloatLeaf* have = keep->probeLeaf(origin)) {
                for (auto on = s->cbeginValueOn(); on; ++on)
                    have->setValueOn(on.pos());
                continue;
            }
            auto leaf = std::make_unique<FloatLeaf>(origin, 0.0f, false);
            for (openvdb::Index i = 0; i < FloatLeaf::SIZE; ++i)
                leaf->setValueOnly(i, original.getValue(leaf->offsetToGlobalCoord(i)));
            for (auto on = s->cbeginValueOn(); on; ++on)
                leaf->setValueOn(on.pos());
            fresh[s.pos()] = std::move(leaf);
        }
    });
    for (std::unique_ptr<FloatLeaf>& leaf : fresh)
        if (leaf) keep->addLeaf(leaf.release()); // (a tile there is split around it)
    FloatTree::ValueOnIter tile = keep->beginValueOn();
    tile.setMaxDepth(FloatTree::ValueOnIter::LEAF_DEPTH - 1);
    for (; tile; ++tile)
        tile.setValueOff();
    return *keep;
}

} // namespace mesh
} // namespace fluidsurf
