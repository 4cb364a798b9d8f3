// CudaBackend.cc - the backend on the GPU (cuda/, through its host facade): the narrow band from
// the sort on runs in cuda::NarrowBandPipeline, whose leaf blocks (origin + 8 mask words + the
// active values) become FloatTree leaves in parallel here; evaluate() sends the leaves of any
// tree to the device (band completion, the gather-full baseline) and fills in what comes back.
#include "backend/Backend.h"

#include <fluidsurf/Error.h>

#ifdef FLUIDSURF_HAS_CUDA
#include "backend/CpuStages.h"
#include "backend/PackKernels.h"
#include "classify/Classify.h"
#include "field/GatherField.h"
#include "mesh/MarchingCubes.h"
#include "util/Memory.h"

#include "facade/Device.h"
#include "facade/FieldGather.h"
#include "facade/MarchingCubes.h"
#include "facade/NarrowBandPipeline.h"
#include "facade/RayCrossings.h"
#include "facade/Smooth.h"
#include "narrowband/NarrowBand.h"

#include <openvdb/tree/LeafManager.h>

#include <tbb/parallel_for.h>

#include <cmath>
#endif

namespace fluidsurf {
namespace backend {

#ifdef FLUIDSURF_HAS_CUDA

namespace {

using LeafT = openvdb::FloatTree::LeafNodeType;

/// The values of every active voxel of tree from compute(origins, masks, leafCount), which
/// returns the active voxels' values, leaf after leaf in voxel order (the facade's). Returns the
/// number of active voxels.
template <typename Compute> size_t fillActiveVoxels(openvdb::FloatTree& tree, Compute&& compute)
{
    openvdb::tree::LeafManager<openvdb::FloatTree> leaves(tree);
    const size_t n = leaves.leafCount();
    std::vector<int32_t> origins(3 * n);
    std::vector<uint64_t> masks(8 * n);
    leaves.foreach ([&](const LeafT& leaf, size_t i) {
        for (int a = 0; a < 3; ++a)
            origins[3 * i + a] = leaf.origin()[a];
        for (int w = 0; w < 8; ++w)
            masks[8 * i + w] = leaf.getValueMask().template getWord<uint64_t>(w);
    });
    std::vector<size_t> before(n + 1, 0); // where each leaf's values start
    for (size_t i = 0; i < n; ++i) {
        size_t count = 0;
        for (int w = 0; w < 8; ++w)
            count += size_t(__builtin_popcountll(masks[8 * i + w]));
        before[i + 1] = before[i] + count;
    }
    const std::vector<float> values = compute(origins.data(), masks.data(), n);
    if (values.size() != before[n])
        throw Error("CUDA backend: the device returned " + std::to_string(values.size()) +
                    " values for " + std::to_string(before[n]) + " active voxels");
    leaves.foreach ([&](LeafT& leaf, size_t i) {
        float* buffer = leaf.buffer().data();
        const float* in = &values[before[i]];
        for (int w = 0; w < 8; ++w)
            for (uint64_t b = masks[8 * i + w]; b; b &= b - 1)
                buffer[64 * w + __builtin_ctzll(b)] = *in++;
    });
    return before[n];
}

cuda::FieldSettings fieldSettings(const Params& params, const Level& level)
{
    cuda::FieldSettings f;
    f.voxelSize = level.voxelSize;
    f.influenceRadius = params.influenceRadius;
    f.radius = params.radius;
    f.radiusScale = params.radiusScale;
    f.tLow = params.tLow, f.tHigh = params.tHigh;
    f.background = float(params.background(level));
    f.ssp07 = params.field != FieldKind::Zb05;
    f.density = params.field == FieldKind::Yt10, f.isoLevel = params.isoLevel;
    return f;
}

/// A tree from leaf blocks: leaves built in parallel, then linked in (cheap, serial).
openvdb::FloatTree::Ptr treeFromBlocks(const cuda::LeafBlocks& blocks, float background,
                                       Context& ctx)
{
    const size_t n = blocks.size();
    // Where each leaf's active values start in the compact array.
    std::vector<size_t> offsets(n + 1, 0);
    for (size_t i = 0; i < n; ++i) {
        size_t count = 0;
        for (int w = 0; w < 8; ++w)
            count += size_t(__builtin_popcountll(blocks.masks[8 * i + w]));
        offsets[i + 1] = offsets[i] + count;
    }
    if (offsets[n] != blocks.values.size())
        throw Error("CUDA pipeline: leaf blocks and values disagree");
    std::vector<std::unique_ptr<LeafT>> built(n); // freed if a cancel stops the loop
    tbb::parallel_for(
        tbb::blocked_range<size_t>(0, n, 64), [&](const tbb::blocked_range<size_t>& r) {
            ctx.checkpoint();
            for (size_t i = r.begin(); i != r.end(); ++i) {
                const openvdb::Coord origin(blocks.origins[3 * i], blocks.origins[3 * i + 1],
                                            blocks.origins[3 * i + 2]);
                auto leaf = std::make_unique<LeafT>(origin, background);
                float* buffer = leaf->buffer().data();
                LeafT::NodeMaskType mask;
                const float* value = &blocks.values[offsets[i]];
                for (int w = 0; w < 8; ++w) {
                    const uint64_t word = blocks.masks[8 * i + w];
                    mask.template getWord<uint64_t>(w) = word;
                    for (uint64_t bits = word; bits; bits &= bits - 1)
                        buffer[64 * w + __builtin_ctzll(bits)] = *value++;
                }
                leaf->setValueMask(mask);
                built[i] = std::move(leaf);
            }
        });
    auto tree = std::make_shared<openvdb::FloatTree>(background);
    for (std::unique_ptr<LeafT>& leaf : built)
        tree->addLeaf(leaf.release()); // the tree takes ownership
    return tree;
}

/// A tree's leaves as the GPU mesher's plain arrays (facade/MarchingCubes.h), gathered in
/// parallel; false where they span more leaves than its keys hold.
struct MeshLeaves
{
    std::vector<int32_t> origins;
    std::vector<uint64_t> active, valueStart;
    std::vector<float> values;

    bool gather(const openvdb::FloatTree& tree, cuda::MeshInput& in, Context& ctx)
    {
        openvdb::tree::LeafManager<const openvdb::FloatTree> leaves(tree);
        const size_t n = leaves.leafCount();
        origins.resize(3 * n), active.resize(8 * n), valueStart.assign(n + 1, 0);
        int32_t lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
        for (size_t i = 0; i < n; ++i) // the bounds first: serial, 3 compares a leaf
            for (int a = 0; a < 3; ++a) {
                const int32_t c = leaves.leaf(i).origin()[a] >> 3;
                lo[a] = i ? std::min(lo[a], c) : c, hi[a] = i ? std::max(hi[a], c) : c;
            }
        if (n && !cuda::leafKeysFit(lo, hi)) return false;
        tbb::parallel_for(
            tbb::blocked_range<size_t>(0, n, 256), [&](const tbb::blocked_range<size_t>& r) {
                ctx.checkpoint();
                for (size_t i = r.begin(); i != r.end(); ++i) {
                    const LeafT& leaf = leaves.leaf(i);
                    uint64_t count = 0;
                    for (int a = 0; a < 3; ++a)
                        origins[3 * i + a] = leaf.origin()[a];
                    for (int w = 0; w < 8; ++w) {
                        const uint64_t word = leaf.getValueMask().template getWord<uint64_t>(w);
                        active[8 * i + w] = word;
                        count += uint64_t(__builtin_popcountll(word));
                    }
                    valueStart[i + 1] = count;
                }
            });
        for (size_t i = 0; i < n; ++i)
            valueStart[i + 1] += valueStart[i];
        util::resizeInParallel(values, valueStart[n]);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 256),
                          [&](const tbb::blocked_range<size_t>& r) {
                              for (size_t i = r.begin(); i != r.end(); ++i) {
                                  const float* buffer = leaves.leaf(i).buffer().data();
                                  float* out = &values[valueStart[i]];
                                  for (int w = 0; w < 8; ++w)
                                      for (uint64_t b = active[8 * i + w]; b; b &= b - 1)
                                          *out++ = buffer[64 * w + __builtin_ctzll(b)];
                              }
                          });
        in.leafOrigins = origins.data(), in.leafActive = active.data();
        in.valueStart = valueStart.data(), in.values = values.data();
        in.leafCount = n;
        for (int a = 0; a < 3; ++a)
            in.keyOrigin[a] = lo[a];
        return true;
    }
};

/// Why a frame's field is the CPU's: the device gather keeps a counter for each of a leaf's
/// slab-and-column bins in shared memory (cuda::gatherFits).
constexpr const char* kSupportTooWide = "the support spans more voxels than the GPU's gather holds";

class CudaBackend : public Backend
{
public:
    explicit CudaBackend(std::string name) : mName(std::move(name)) {}

    std::string name() const override { return mName; }

    bool narrowBand(const Particles& particles, const Params& params, const Level& level,
                    double width, Context& ctx, Band& out, std::string& whyNot) override
    {
        if (isAnisotropic(params.field)) {
            // The classes, the band and the kernels' shapes on the CPU (their device versions
            // are issue 65's), the field on the device.
            Classified c = classifyOnCpu(particles, params, ctx, out);
            narrowBandOnCpu(c, params, level, width, ctx, out);
            mAnisoGather.reset();
            mAniso = anisotropicStage(std::move(c), params, ctx);
            mPipeline.reset(), mIndex = nullptr, mCpuField = false;
            const auto t = ctx.scope("field");
            out.evaluations = evaluate(*out.tree, params, level, ctx);
            return true;
        }
        mAniso.reset(), mAnisoGather.reset();
        const std::vector<Vec3f>& positions = particles.positions;
        const std::vector<float>& radii = particles.radii;
        if (positions.empty()) { // nothing for the device to do
            out.tree = std::make_shared<openvdb::FloatTree>(float(params.background(level)));
            mPipeline.reset();
            return true;
        }
        if (positions.size() >= (size_t(1) << 32) - 1)
            throw ValueError("more than 2^32 - 2 particles in one frame");
        // A support of very many voxels: the device's gather lacks the shared memory (the CPU's
        // band, and its field below).
        if (!cuda::gatherFits(level.voxelSize, params.influenceRadius)) {
            whyNot = kSupportTooWide;
            return false;
        }
        auto pipeline = std::make_unique<cuda::NarrowBandPipeline>();
        Vec3f lo, hi;
        {
            const auto t = ctx.scope("upload");
            pipeline->upload(positions.data(), radii.empty() ? nullptr : radii.data(),
                             positions.size(), lo, hi);
        }
        // Leaf keys on the device hold 21 bits per axis around leaf 0.
        const double dx = level.voxelSize, limit = double(1 << 20) * 8 * dx;
        for (int a = 0; a < 3; ++a)
            if (!(std::abs(double(lo[a]) - width) < limit - 16 * dx &&
                  std::abs(double(hi[a]) + width) < limit - 16 * dx)) {
                whyNot = "the frame lies beyond the GPU's leaf keys";
                return false;
            }
        ctx.throwIfCancelled();

        cuda::PipelineSettings s;
        s.cellSize = std::min(params.influenceRadius, params.smoothingLength);
        BBox3f box;
        box.expand(lo), box.expand(hi);
        neighbors::cellGrid(box, s.cellSize, s.cellOrigin, s.cellDims);
        const classify::KernelConstants k = classify::kernelConstants(params);
        s.h2 = k.h2;
        s.smoothingLength = k.h, s.poly6 = k.poly6, s.gradientScale = k.gradientScale;
        s.uniformVolume = float(k.uniformVolume);
        s.splashNeighbours = params.splashNeighbours,
        s.surfaceNeighbours = params.surfaceNeighbours;
        s.colorFieldThreshold = params.colorFieldThreshold,
        s.colorGradientThreshold = params.colorGradientThreshold;
        s.keepIsolated = params.keepIsolated;
        s.bandWidth = width;
        s.field = fieldSettings(params, level);
        s.beforeBand = [&](const cuda::ClassCounts& c) { // the CPU's seeds: surface and splash
            narrowband::requireBandMemory(c.surface + c.splash +
                                              (params.keepIsolated ? c.isolated : 0),
                                          params, level, width, ctx);
        };
        cuda::LeafBlocks blocks;
        {
            const auto t = ctx.scope("device field");
            blocks = pipeline->run(s);
        }
        ctx.throwIfCancelled();
        const cuda::ClassCounts& counts = pipeline->classCounts();
        out.interior = counts.interior, out.surface = counts.surface;
        out.splash = counts.splash, out.isolated = counts.isolated;
        out.isolatedParticles.clear();
        if (!params.keepIsolated) out.isolatedParticles = pipeline->isolatedParticles();
        {
            const auto t = ctx.scope("vdb build");
            out.tree = treeFromBlocks(blocks, s.field.background, ctx);
        }
        out.evaluations = out.tree->activeVoxelCount();
        mPipeline = std::move(pipeline);
        mIndex = nullptr;
        return true;
    }

    void useParticles(const neighbors::CellIndex& particles) override
    {
        mIndex = &particles;
        mPipeline.reset(), mAniso.reset(), mAnisoGather.reset();
    }

    /// The ssp07-aniso field of tree's active voxels on the device, from the kernels narrowBand
    /// made (uploaded on the first call, kept for the band's completion).
    size_t evaluateAnisotropic(openvdb::FloatTree& tree, const Params& params, const Level& level)
    {
        if (!mAniso) throw Error("CUDA backend: evaluate() before the kernels were made");
        const bool first = !mAnisoGather; // (the band; then its completion's rounds add up)
        cuda::GatherTimes times;
        const size_t evaluations =
            fillActiveVoxels(tree, [&](const int32_t* origins, const uint64_t* masks, size_t n) {
                if (!mAnisoGather) {
                    const PackedKernels packed = packKernels(mAniso->table);
                    cuda::AnisotropicInput in;
                    in.gather =
                        gatherInput(mAniso->kernels.centres, nullptr, nullptr, 0, params, level);
                    in.a = packed.a.data(), in.extent = packed.extent.data();
                    in.weight = packed.weight.empty() ? nullptr : packed.weight.data();
                    in.fresh = packed.fresh.data(), in.freshBefore = packed.freshBefore.data();
                    in.freshCount = packed.freshCount();
                    in.reach = mAniso->table.reach;
                    mAnisoGather = std::make_unique<cuda::AnisotropicGather>(in);
                }
                return mAnisoGather->evaluate(origins, masks, n, &times);
            });
        const std::vector<StageTime> before = mGatherStages;
        noteGather(times);
        if (!first && before.size() == mGatherStages.size())
            for (size_t k = 0; k < before.size(); ++k)
                mGatherStages[k].seconds += before[k].seconds;
        return evaluations;
    }

    size_t evaluate(openvdb::FloatTree& tree, const Params& params, const Level& level,
                    Context& ctx) override
    {
        ctx.throwIfCancelled();
        if (isAnisotropic(params.field)) return evaluateAnisotropic(tree, params, level);
        if (mPipeline) // the particles are on the device already
            return fillActiveVoxels(tree,
                                    [&](const int32_t* origins, const uint64_t* masks, size_t n) {
                                        return mPipeline->evaluate(origins, masks, n);
                                    });
        if (!mIndex) throw Error("CUDA backend: evaluate() before the particles were given");
        const neighbors::CellIndex& particles = *mIndex;
        mCpuField = !cuda::gatherFits(level.voxelSize, params.influenceRadius); // (narrowBand)
        if (mCpuField) return field::evaluateField(tree, particles, params, level, ctx);
        cuda::GatherTimes times;
        const size_t evaluations =
            fillActiveVoxels(tree, [&](const int32_t* origins, const uint64_t* masks, size_t n) {
                return cuda::gatherField(gatherInput(particles, origins, masks, n, params, level),
                                         &times);
            });
        noteGather(times);
        return evaluations;
    }

    /// The facade's view of a cell index and of the leaves to fill.
    static cuda::GatherInput gatherInput(const neighbors::CellIndex& particles,
                                         const int32_t* origins, const uint64_t* masks, size_t n,
                                         const Params& params, const Level& level)
    {
        cuda::GatherInput in;
        in.positions = particles.positions.data();
        in.radii = particles.radii.empty() ? nullptr : particles.radii.data();
        in.particleCount = particles.size();
        in.tableKeys = particles.tableKeys.data();
        in.tableCells = particles.tableCells.data();
        in.tableSize = particles.tableKeys.size();
        in.cellStarts = particles.starts.data();
        in.cellCount = particles.cellCount();
        in.cellSize = particles.cellSize;
        for (int a = 0; a < 3; ++a)
            in.cellOrigin[a] = particles.origin[a], in.cellDims[a] = particles.dims[a];
        in.leafOrigins = origins;
        in.leafActive = masks;
        in.leafCount = n;
        in.field = fieldSettings(params, level);
        return in;
    }

    void noteGather(const cuda::GatherTimes& times)
    {
        mGatherStages = {{"upload", times.uploadMs * 1e-3},
                         {"gather", times.kernelMs * 1e-3},
                         {"download", times.downloadMs * 1e-3}};
        mGatherBytes = times.deviceBytes;
    }

    void deviceStats(RasterizeStats& stats) const override
    {
        if (mCpuField && !mPipeline) stats.device = "cpu (" + std::string(kSupportTooWide) + ")";
        if (mPipeline) {
            stats.gpuStages.clear();
            for (const auto& st : mPipeline->stageMs())
                stats.gpuStages.push_back({st.first, st.second * 1e-3});
            stats.gpuBytes = mPipeline->peakBytes();
        } else {
            stats.gpuStages = mGatherStages;
            stats.gpuBytes = mGatherBytes;
        }
    }

    bool marchingCubes(const openvdb::FloatGrid& grid, RawNormals normals, Context& ctx,
                       TriangleMesh& out, size_t& cells) override
    {
        openvdb::FloatTree::Ptr voxelized;
        const openvdb::FloatTree& tree = mesh::leafOnlyTree(grid, voxelized, ctx);
        cuda::MeshInput in;
        MeshLeaves leaves;
        {
            const auto t = ctx.scope("gather");
            if (!leaves.gather(tree, in, ctx)) return false;
        }
        const mesh::Affine affine(grid.transform());
        const openvdb::Mat3d linearT = affine.linear.transpose(),
                             jacobianT = affine.jacobianInverse.transpose();
        for (int k = 0; k < 9; ++k)
            in.linearT[k] = linearT.asPointer()[k],
            in.jacobianInverseT[k] = jacobianT.asPointer()[k];
        for (int a = 0; a < 3; ++a)
            in.translation[a] = affine.translation[a];
        in.normals = normals == RawNormals::Gradient;
        ctx.throwIfCancelled();
        TriangleMesh mesh;
        {
            const auto t = ctx.scope("device mesh");
            cuda::MarchingCubesRun run(in);
            leaves = MeshLeaves(); // on the device now
            const uint64_t vertices = run.vertexCount();
            mesh::checkVertexCount(vertices);
            util::resizeInParallel(mesh.points, vertices);
            if (in.normals) util::resizeInParallel(mesh.normals, vertices);
            util::resizeInParallel(mesh.triangles, run.triangleCount());
            static_assert(sizeof(mesh.triangles[0]) == 3 * sizeof(uint32_t), "3 indices");
            run.finish(mesh.points.data(), in.normals ? mesh.normals.data() : nullptr,
                       mesh.triangles.empty() ? nullptr : mesh.triangles[0].data());
            cells = run.cellCount();
        }
        mesh::dropUnusedVertices(mesh, ctx);
        out = std::move(mesh);
        return true;
    }

    void smoothMesh(TriangleMesh& mesh, const post::SmoothParams& params, Context&) override
    {
        if (post::smoothingLeaves(mesh, params)) return;
        mesh.normals.clear(); // (as the CPU's: see post/Normals.h)
        const post::SmoothRings rings = post::smoothRings(mesh);
        cuda::SmoothInput in;
        in.points = mesh.points.data(), in.pointCount = mesh.points.size();
        static_assert(sizeof(mesh.triangles[0]) == 3 * sizeof(uint32_t), "3 indices");
        in.triangles = mesh.triangles[0].data(), in.triangleCount = mesh.triangles.size();
        in.cornerStart = rings.corners.start.data(), in.cornerTris = rings.corners.tris.data();
        in.ringStart = rings.ringStart.data(), in.ring = rings.ring.data();
        in.fixed = rings.fixed.data();
        in.rounds = params.rounds, in.maxMove = params.maxMove;
        in.flatten = params.flatten, in.flatMove = params.flatMove, in.voxel = params.voxel;
        in.cellGrid = [](const float lo[3], const float hi[3], double cellSize, double origin[3],
                         uint32_t dims[3]) {
            BBox3f box; // (the CPU's cell index of the same points: neighbors/CellIndex)
            box.expand(Vec3f(lo[0], lo[1], lo[2])), box.expand(Vec3f(hi[0], hi[1], hi[2]));
            neighbors::cellGrid(box, cellSize, origin, dims);
        };
        std::vector<Vec3f> points(mesh.points.size());
        cuda::smoothPoints(in, points.data());
        mesh.points.swap(points);
    }

    std::vector<uint32_t> componentsOfParticles(const TriangleMesh& mesh,
                                                const std::vector<uint32_t>& ofPoint,
                                                const post::Components& c,
                                                const ParticleVolumes& particles, double cellSize,
                                                Context&) override
    {
        std::vector<uint32_t> out(particles.count, post::kNoComponent);
        const post::RayColumns g = post::rayColumns(mesh, particles, cellSize);
        if (g.start.empty() || g.sorted.empty()) return out;
        std::vector<uint8_t> outward(c.volume.size());
        for (size_t k = 0; k < outward.size(); ++k)
            outward[k] = c.volume[k] > 0;
        cuda::RayInput in;
        in.points = mesh.points.data(), in.pointCount = mesh.points.size();
        in.triangles = mesh.triangles[0].data(), in.triangleCount = mesh.triangles.size();
        in.ofPoint = ofPoint.data();
        in.outward = outward.data(), in.componentCount = outward.size();
        in.particles = particles.positions, in.particleCount = particles.count;
        in.axis = g.axis, in.u = g.u, in.v = g.v;
        in.u0 = g.u0, in.v0 = g.v0, in.cell = g.cell, in.nudgeU = g.nudgeU, in.nudgeV = g.nudgeV;
        in.nu = g.nu, in.columnCount = g.start.size() - 1;
        in.start = g.start.data(), in.tris = g.tris.data();
        in.first = g.first.data(), in.sorted = g.sorted.data();
        // a ray through more components than a device thread keeps: the CPU's answer
        if (!cuda::componentsOnDevice(in, out.data()))
            return post::componentsOfParticles(mesh, ofPoint, c, particles, cellSize);
        return out;
    }

private:
    std::string mName;
    std::unique_ptr<cuda::NarrowBandPipeline> mPipeline; // holds the particles on the device
    const neighbors::CellIndex* mIndex = nullptr;
    std::unique_ptr<AnisotropicStage> mAniso;              ///< ssp07-aniso: the kernels (CPU-made)
    std::unique_ptr<cuda::AnisotropicGather> mAnisoGather; ///< and on the device
    std::vector<StageTime> mGatherStages;
    size_t mGatherBytes = 0;
    bool mCpuField = false; ///< evaluate() ran the CPU's gather (see kSupportTooWide)
};

} // namespace

bool cudaUsable(std::string* reason, std::string* deviceName)
{
    const cuda::DeviceInfo info = cuda::openDevice();
    if (reason) *reason = info.reason;
    if (deviceName) *deviceName = info.name;
    return info.usable;
}

std::unique_ptr<Backend> makeCudaBackend()
{
    std::string reason, name;
    if (!cudaUsable(&reason, &name))
        throw Error("CUDA was requested but there is no usable GPU: " + reason);
    return std::make_unique<CudaBackend>(name);
}

#else

bool cudaUsable(std::string* reason, std::string*)
{
    if (reason) *reason = "this build of fluidsurf has no CUDA backend";
    return false;
}

std::unique_ptr<Backend> makeCudaBackend()
{
    throw Error(
        "CUDA was requested but this build of fluidsurf has no CUDA backend (rebuild with nvcc)");
}

#endif

} // namespace backend
} // namespace fluidsurf
