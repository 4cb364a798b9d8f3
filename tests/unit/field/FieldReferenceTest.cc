// The narrow-band field against the independent brute-force reference (BruteForce.h): real
// frames, a single particle (phi = |x - p| - r exactly), a lattice slab (a plane), and no
// particle centre outside the surface. The *Cuda tests run the same checks on the GPU pipeline.
#include "TestData.h"
#include "unit/field/BruteForce.h"
#include "unit/field/RequireGpu.h"

#include <fluidsurf/Rasterize.h>
#include <fluidsurf/Scenes.h>

#include <openvdb/tools/Interpolation.h>

#include <map>

using namespace fluidsurf;
using namespace fluidsurf::test;

namespace {

using Points = std::vector<std::array<double, 3>>;

/// Particles in double, sorted by x so a voxel only scans the x-slab within R (the others
/// cannot contribute); isolated ones (no neighbour within h) removed unless kept.
struct Reference
{
    Points pts;
    std::vector<double> radii;
    ReferenceParams params;

    Reference(const ParticleSet& ps, const Params& p)
    {
        Points all;
        for (const Vec3f& v : ps.positions)
            all.push_back({v.x, v.y, v.z});
        const std::vector<int> counts = referenceNeighbourCounts(all, p.smoothingLength);
        const Attribute* ra = p.perParticleRadii ? ps.find(AttributeRole::Radius) : nullptr;
        std::vector<size_t> keep;
        for (size_t i = 0; i < all.size(); ++i)
            if (counts[i] > 0 || p.keepIsolated) keep.push_back(i);
        std::sort(keep.begin(), keep.end(),
                  [&](size_t a, size_t b) { return all[a][0] < all[b][0]; });
        for (size_t i : keep) {
            pts.push_back(all[i]);
            if (ra) radii.push_back(ra->floats[i]);
        }
        params = {p.radius, p.influenceRadius, p.smoothingLength,          p.tLow,
                  p.tHigh,  p.background(),    p.field == FieldKind::Ssp07};
    }

    double phi(const std::array<double, 3>& x) const
    {
        const double R = params.influence;
        auto lo = std::lower_bound(pts.begin(), pts.end(), x[0] - R,
                                   [](const auto& p, double v) { return p[0] < v; });
        auto hi = std::upper_bound(pts.begin(), pts.end(), x[0] + R,
                                   [](double v, const auto& p) { return v < p[0]; });
        const size_t b = size_t(lo - pts.begin()), e = size_t(hi - pts.begin());
        Points slab(lo, hi);
        std::vector<double> r;
        if (!radii.empty()) r.assign(radii.begin() + b, radii.begin() + e);
        return referencePhi(slab, r, x, params);
    }
};

/// Compare every active voxel (or an even sample of maxVoxels) with the reference.
void expectMatchesReference(const openvdb::FloatGrid& grid, const Reference& ref, const Params& p,
                            const std::string& what, size_t maxVoxels = 40000)
{
    const size_t active = grid.activeVoxelCount();
    const size_t stride = std::max<size_t>(1, (active + maxVoxels - 1) / maxVoxels);
    size_t n = 0, checked = 0, bad = 0;
    double worst = 0;
    for (auto it = grid.cbeginValueOn(); it; ++it, ++n) {
        if (n % stride) continue;
        const openvdb::Coord c = it.getCoord();
        const double expected =
            ref.phi({c.x() * p.voxelSize, c.y() * p.voxelSize, c.z() * p.voxelSize});
        const double err = std::abs(double(*it) - expected);
        worst = std::max(worst, err);
        if (err > 1e-5 * p.radius && bad++ < 5)
            ADD_FAILURE() << what << ": voxel " << c << " phi " << *it << " reference " << expected;
        ++checked;
    }
    EXPECT_EQ(bad, 0u) << what;
    ::testing::Test::RecordProperty(what + "_worst_error_in_r", std::to_string(worst / p.radius));
}

using test::kRealFrames;

/// phi at every particle centre that is part of the field (trilinear in the level set; deep
/// inside, the sign-flood-filled background): how many lie outside, and the largest phi.
struct Containment
{
    size_t outside = 0, checked = 0;
    double maxPhi = -1e30;
};

Containment containment(const openvdb::FloatGrid& grid, const ParticleSet& ps,
                        const std::vector<uint32_t>& isolated)
{
    openvdb::tools::GridSampler<openvdb::FloatGrid, openvdb::tools::BoxSampler> sampler(grid);
    Containment c;
    size_t j = 0;
    for (size_t i = 0; i < ps.size(); ++i) {
        if (j < isolated.size() && isolated[j] == i) {
            ++j;
            continue;
        }
        const Vec3f& p = ps.positions[i];
        const double v = sampler.wsSample(openvdb::Vec3R(p.x, p.y, p.z));
        ++c.checked;
        c.maxPhi = std::max(c.maxPhi, v);
        if (!(v < 0)) ++c.outside;
    }
    return c;
}

void expectParticlesInside(const openvdb::FloatGrid& grid, const ParticleSet& ps,
                           const std::vector<uint32_t>& isolated, const std::string& what)
{
    const Containment c = containment(grid, ps, isolated);
    EXPECT_EQ(c.outside, 0u) << what << ": particle centres outside the surface (max phi "
                             << c.maxPhi << ")";
    EXPECT_GT(c.checked, 0u) << what;
}

} // namespace

static void realFramesMatchBruteForce(Device device)
{
    for (const test::RealFrame& f : kRealFrames) {
        const ParticleSet ps = io::readParticles(sharedData() + "/real/" + f.name);
        Params p = Params::fromRadius(f.radius);
        Context ctx(device);
        const RasterizeResult res = rasterizeParticles(ps, p, ctx, f.name);
        expectMatchesReference(*res.grid, Reference(ps, p), p, f.name);
        // Only the 20 x 20 grid at 15 r spacing is all isolated (no grid at all).
        EXPECT_EQ(res.grid->activeVoxelCount() == 0, res.stats.isolated == ps.size()) << f.name;
    }
}

TEST(FieldReference, RealFramesMatchBruteForce)
{
    FLUIDSURF_REQUIRE_SHARED_DATA();
    realFramesMatchBruteForce(Device::Cpu);
}

TEST(FieldReferenceCuda, RealFramesMatchBruteForce)
{
    FLUIDSURF_REQUIRE_GPU();
    FLUIDSURF_REQUIRE_SHARED_DATA();
    realFramesMatchBruteForce(Device::Cuda);
}

// SSP07 shrinks the surface (f < 1) where the neighbour centroid moves fast, and the centroid
// itself lies up to R inside a convex tip: at the thin sheets and filaments of real frames a few
// particle centres end up just outside the exact field. Measured with the defaults on the fluid
// frames: at most 20 of 7706 centres (0.26%, bunny), at most 0.13 r outside; on the scattered
// point sets (random, free particles) 1.3% and 3.6%, at most 0.19 r.
TEST(FieldReference, RealFramesKeepTheirParticlesInside)
{
    FLUIDSURF_REQUIRE_SHARED_DATA();
    for (const test::RealFrame& f : kRealFrames) {
        // A sampled sphere *shell* one particle thick at 0.53 of its pscale spacing: a boundary
        // model, not a fluid body. Its particles look interior to every density test.
        if (std::string(f.name).find("splishsplash_sphere") == 0) continue;
        const ParticleSet ps = io::readParticles(sharedData() + "/real/" + f.name);
        const RasterizeResult res = rasterizeParticles(ps, Params::fromRadius(f.radius), f.name);
        const Containment c = containment(*res.grid, ps, res.isolatedParticles);
        EXPECT_LE(c.outside, c.checked / (f.fluid ? 200 : 20))
            << f.name << ": " << c.outside << " of " << c.checked;
        EXPECT_LE(c.maxPhi, 0.2 * f.radius) << f.name;
    }
}

TEST(FieldReference, GeneratedScenesHaveNoParticleOutside)
{
    for (Scene scene : {Scene::Block, Scene::Ball, Scene::Slab, Scene::Drop}) {
        SceneParams sp;
        sp.count = 4000;
        const ParticleSet ps = generateScene(scene, sp);
        const RasterizeResult res = rasterizeParticles(ps, Params::fromRadius(sp.radius));
        expectParticlesInside(*res.grid, ps, res.isolatedParticles, sceneName(scene));
    }
}

TEST(FieldReference, Zb05MatchesBruteForce)
{
    FLUIDSURF_REQUIRE_SHARED_DATA();
    const ParticleSet ps =
        io::readParticles(sharedData() + "/real/dam_break_frame_9_6859_particles.bgeo");
    Params p = Params::fromRadius(0.025);
    p.field = FieldKind::Zb05;
    const RasterizeResult res = rasterizeParticles(ps, p);
    expectMatchesReference(*res.grid, Reference(ps, p), p, "zb05");
}

static void otherVoxelSizesAndSupports(Device device)
{
    SceneParams sp;
    sp.count = 3000;
    sp.droplets = 3;
    const ParticleSet ps = generateScene(Scene::Drop, sp);
    for (double voxel : {0.5, 2.0})
        for (double support : {4.0, 8.0}) {
            Params p = Params::fromRadius(sp.radius);
            p.voxelSize = voxel * sp.radius;
            p.influenceRadius = support * sp.radius;
            Context ctx(device);
            const RasterizeResult res = rasterizeParticles(ps, p, ctx);
            const std::string what =
                "voxel " + std::to_string(voxel) + "r R " + std::to_string(support) + "r";
            expectMatchesReference(*res.grid, Reference(ps, p), p, what, 20000);
            // With R = 8r the centroid of a lattice corner lies more than r inside it, so the
            // exact field rounds corners off past their particles: containment holds at 4r only.
            if (support == 4.0) expectParticlesInside(*res.grid, ps, res.isolatedParticles, what);
        }
}

TEST(FieldReference, OtherVoxelSizesAndSupports)
{
    otherVoxelSizesAndSupports(Device::Cpu);
}

TEST(FieldReferenceCuda, OtherVoxelSizesAndSupports)
{
    FLUIDSURF_REQUIRE_GPU();
    otherVoxelSizesAndSupports(Device::Cuda);
}

static void singleParticleIsASphere(Device device)
{
    SceneParams sp;
    sp.radius = 0.1;
    ParticleSet ps = generateScene(Scene::Single, sp);
    ps.positions[0] = Vec3f(0.0137f, -0.271f, 1.5f); // off the grid
    Params p = Params::fromRadius(sp.radius);
    p.keepIsolated = true;
    Context ctx(device);
    const RasterizeResult res = rasterizeParticles(ps, p, ctx);
    EXPECT_GE(res.grid->activeVoxelCount(), 64u); // +-2r around it at voxel r
    const Vec3f c = ps.positions[0];
    size_t n = 0;
    bool inside = false, outside = false;
    for (auto it = res.grid->cbeginValueOn(); it; ++it, ++n) {
        const openvdb::Vec3d x = res.grid->indexToWorld(it.getCoord());
        const double d = std::sqrt((x[0] - c.x) * (x[0] - c.x) + (x[1] - c.y) * (x[1] - c.y) +
                                   (x[2] - c.z) * (x[2] - c.z));
        ASSERT_NEAR(*it, d - sp.radius, 1e-5 * sp.radius) << it.getCoord();
        inside |= *it<0, outside |= *it> 0;
    }
    EXPECT_TRUE(inside && outside) << "the band must contain the zero crossing";
    // Left out by default: an isolated particle is not part of the grid.
    p.keepIsolated = false;
    const RasterizeResult left = rasterizeParticles(ps, p);
    EXPECT_EQ(left.grid->activeVoxelCount(), 0u);
    ASSERT_EQ(left.isolatedParticles.size(), 1u);
}

TEST(FieldReference, SingleParticleIsASphereOfRadiusR)
{
    singleParticleIsASphere(Device::Cpu);
}

TEST(FieldReferenceCuda, SingleParticleIsASphereOfRadiusR)
{
    FLUIDSURF_REQUIRE_GPU();
    singleParticleIsASphere(Device::Cuda);
}

namespace {
/// The lowest and highest zero crossing of phi along z above a 40 x 40 x 4 lattice slab's top
/// layer, in columns away from its edges (at least 100 of them).
struct Face
{
    double lo = 1e9, hi = -1e9, top = 0;
};

Face latticeFace(const ParticleSet& ps, const Params& p, const RasterizeResult& res, int layers)
{
    const double r = p.radius, dx = p.voxelSize;
    Face f;
    f.top = (layers - 1) * 2 * r;
    openvdb::FloatGrid::ConstAccessor acc = res.grid->getConstAccessor();
    const int margin = int(std::ceil((p.influenceRadius + 2 * r) / dx));
    const int extent = int(std::floor(39 * 2 * r / dx));
    size_t columns = 0;
    for (int i = margin; i <= extent - margin; ++i)
        for (int j = margin; j <= extent - margin; ++j) {
            for (int k = int(std::floor(f.top / dx)); k < int(std::ceil((f.top + 3 * r) / dx));
                 ++k) {
                const float a = acc.getValue({i, j, k}), b = acc.getValue({i, j, k + 1});
                if (a < 0 && b >= 0) {
                    EXPECT_TRUE(acc.isValueOn({i, j, k}) && acc.isValueOn({i, j, k + 1}));
                    const double z = (k + a / (a - b)) * dx;
                    f.lo = std::min(f.lo, z), f.hi = std::max(f.hi, z);
                    ++columns;
                }
            }
        }
    EXPECT_GT(columns, 100u);
    (void)ps;
    return f;
}
} // namespace

TEST(FieldReference, LatticeSlabIsAPlane)
{
    SceneParams sp;
    sp.count = 40 * 40 * 4;
    sp.layers = 4;
    sp.jitter = 0; // a pure lattice
    const ParticleSet ps = generateScene(Scene::Slab, sp);
    const Params p = Params::fromRadius(sp.radius);
    const RasterizeResult res = rasterizeParticles(ps, p);
    const double r = sp.radius;
    const Face f = latticeFace(ps, p, res, sp.layers);
    EXPECT_LE(f.hi - f.lo, 0.05 * r) << "plane deviation";
    EXPECT_GT(f.lo, f.top) << "surface above the outer particle centres";
    EXPECT_LT(f.hi, f.top + r) << "surface within r of the outer particle centres";
    RecordProperty("slab_surface_offset_in_r", std::to_string((0.5 * (f.lo + f.hi) - f.top) / r));
    expectParticlesInside(*res.grid, ps, res.isolatedParticles, "slab");
}

TEST(FieldReference, RadiusScalePutsALatticeFaceAtR)
{
    // SSP07's face lies 0.870 r above the top centres; |x - xbar| is 1.0866 r at height r and f
    // 0.9916 there (a separate double-precision computation over a half-space lattice), so a radius
    // scale of 1.096 puts the face at r. A voxel of r/4: phi is not linear in z, and at voxel r the
    // crossing interpolated between voxels lies 0.03 r lower.
    SceneParams sp;
    sp.count = 40 * 40 * 4;
    sp.layers = 4;
    sp.jitter = 0;
    const ParticleSet ps = generateScene(Scene::Slab, sp);
    const double r = sp.radius;
    Params p = Params::fromRadius(r);
    p.voxelSize = 0.25 * r;
    const Face plain = latticeFace(ps, p, rasterizeParticles(ps, p), sp.layers);
    EXPECT_NEAR(0.5 * (plain.lo + plain.hi) - plain.top, 0.870 * r, 0.02 * r);
    p.radiusScale = 1.096;
    const Face scaled = latticeFace(ps, p, rasterizeParticles(ps, p), sp.layers);
    EXPECT_NEAR(0.5 * (scaled.lo + scaled.hi) - scaled.top, r, 0.02 * r);
    EXPECT_LE(scaled.hi - scaled.lo, 0.05 * r) << "plane deviation";
    p.radiusScale = 2.5;
    EXPECT_THROW(p.validate(), ValueError);
}
