// Anisotropic kernels (issue 64, [YT10]): the Jacobi eigen-solver against built matrices, and
// each particle's shape and centre against a brute-force PCA over all particles, with its own
// eigenvalues (the trigonometric roots of the characteristic polynomial) and clamping.
#include "TestData.h"

#include "anisotropy/KernelShapes.h"
#include "anisotropy/SymmetricEigen.h"

#include <fluidsurf/Scenes.h>
#include <fluidsurf/io/ParticleIO.h>

#include <tbb/global_control.h>

#include <array>
#include <cmath>
#include <cstring>

using namespace fluidsurf;
using namespace fluidsurf::test;

namespace {

using Mat = std::array<std::array<double, 3>, 3>;

Mat fromSym(const double a[6])
{
    return Mat{{{a[0], a[1], a[2]}, {a[1], a[3], a[4]}, {a[2], a[4], a[5]}}};
}

double det(const Mat& m)
{
    return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
           m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
           m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

Mat inverse(const Mat& m)
{
    Mat r;
    const double d = det(m);
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            const int i1 = (j + 1) % 3, i2 = (j + 2) % 3, j1 = (i + 1) % 3, j2 = (i + 2) % 3;
            r[i][j] = (m[i1][j1] * m[i2][j2] - m[i1][j2] * m[i2][j1]) / d;
        }
    return r;
}

/// Eigenvalues of a symmetric matrix, descending: the trigonometric roots of its cubic.
std::array<double, 3> eigenvalues(const Mat& a)
{
    const double q = (a[0][0] + a[1][1] + a[2][2]) / 3;
    const double p1 = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
    const double p2 =
        std::pow(a[0][0] - q, 2) + std::pow(a[1][1] - q, 2) + std::pow(a[2][2] - q, 2) + 2 * p1;
    const double p = std::sqrt(p2 / 6);
    if (p == 0) return {q, q, q};
    Mat b = a;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            b[i][j] = (a[i][j] - (i == j ? q : 0)) / p;
    const double phi = std::acos(std::clamp(det(b) / 2, -1.0, 1.0)) / 3;
    const double e1 = q + 2 * p * std::cos(phi), e3 = q + 2 * p * std::cos(phi + 2 * M_PI / 3);
    return {e1, 3 * q - e1 - e3, e3};
}

/// The unit eigenvector of a simple eigenvalue: the longest cross product of two rows of A - eI.
std::array<double, 3> eigenvector(const Mat& a, double e)
{
    Mat m = a;
    for (int i = 0; i < 3; ++i)
        m[i][i] -= e;
    std::array<double, 3> best{};
    double bestLength = -1;
    for (int i = 0; i < 3; ++i) {
        const auto& u = m[i];
        const auto& v = m[(i + 1) % 3];
        const std::array<double, 3> c = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                                         u[0] * v[1] - u[1] * v[0]};
        const double l = std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
        if (l > bestLength) bestLength = l, best = {c[0] / l, c[1] / l, c[2] / l};
    }
    return best;
}

struct Reference
{
    bool sparse = true;
    bool nearClamp = false; ///< an eigenvalue within 0.1% of the clamp: either side is right
    Mat g{};
    double centre[3] = {0, 0, 0};
};

/// The PCA of particle i by brute force over all particles (KernelShapes.h's formulas).
Reference reference(const ParticleSet& ps, size_t i, const anisotropy::ShapeParams& p)
{
    const Vec3f xi = ps.positions[i];
    double w = 0, m[3] = {0, 0, 0};
    int neighbours = -1;
    std::vector<std::pair<double, size_t>> near;
    for (size_t j = 0; j < ps.size(); ++j) {
        double d2 = 0;
        for (int k = 0; k < 3; ++k)
            d2 += std::pow(double(ps.positions[j][k]) - xi[k], 2);
        const double s = std::sqrt(d2) / p.pcaRadius;
        if (!(s < 1)) continue;
        const double wj = 1 - s * s * s;
        near.push_back({wj, j});
        ++neighbours, w += wj;
        for (int k = 0; k < 3; ++k)
            m[k] += wj * ps.positions[j][k];
    }
    Reference r;
    for (int k = 0; k < 3; ++k)
        r.centre[k] = xi[k];
    if (neighbours < p.minNeighbours) return r;
    r.sparse = false;
    for (int k = 0; k < 3; ++k)
        m[k] /= w;
    Mat c{};
    for (const auto& [wj, j] : near)
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b)
                c[a][b] += wj * (ps.positions[j][a] - m[a]) * (ps.positions[j][b] - m[b]) / w;
    const auto s = eigenvalues(c);
    const double floor = s[0] / p.maxAxisRatio;
    for (int k = 1; k < 3; ++k)
        r.nearClamp |= std::fabs(s[k] - floor) < 1e-3 * s[0];
    Mat clamped = c;
    if (s[1] < floor) { // both short axes clamped: floor off the longest axis
        const auto v = eigenvector(c, s[0]);
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b)
                clamped[a][b] = (a == b ? floor : 0) + (s[0] - floor) * v[a] * v[b];
    } else if (s[2] < floor) { // the shortest only
        const auto v = eigenvector(c, s[2]);
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b)
                clamped[a][b] += (floor - s[2]) * v[a] * v[b];
    }
    // G = R diag(1 / e_k) R^T with e_k = R_inf t_k / t3: t3 / R_inf * inverse, t3 the smallest
    // eigenvalue after clamping
    const Mat inv = inverse(clamped);
    const double scale = std::max(s[2], floor) / p.influenceRadius;
    for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b)
            r.g[a][b] = scale * inv[a][b];
    for (int k = 0; k < 3; ++k)
        r.centre[k] = xi[k] + p.centreSmoothing * (m[k] - xi[k]);
    return r;
}

anisotropy::ShapeParams shapeParams(const Params& p)
{
    anisotropy::ShapeParams s;
    // YT10's PCA radius, twice the SPH support: within h = 4r a face particle has about 17
    // neighbours, fewer than N_eps = 25
    s.influenceRadius = p.influenceRadius, s.pcaRadius = 2 * p.smoothingLength;
    return s;
}

/// Shapes of ps with cells of cellSize; the index and classes come back too.
anisotropy::KernelShapes shapesOf(const ParticleSet& ps, const Params& p, double cellSize,
                                  const anisotropy::ShapeParams& sp, neighbors::CellIndex& index,
                                  classify::Classification& classes)
{
    Context ctx;
    neighbors::CellIndex byH =
        neighbors::buildCellIndex(ps.positions.data(), nullptr, ps.size(), p.smoothingLength, ctx);
    classify::Classification c = classify::classifyParticles(byH, p, ctx);
    index = neighbors::buildCellIndex(ps.positions.data(), nullptr, ps.size(), cellSize, ctx);
    // the classes in this index's order
    std::vector<uint8_t> ofInput(ps.size());
    for (size_t k = 0; k < ps.size(); ++k)
        ofInput[byH.order[k]] = c.classes[k];
    classes = std::move(c);
    for (size_t k = 0; k < ps.size(); ++k)
        classes.classes[k] = ofInput[index.order[k]];
    return anisotropy::kernelShapes(index, classes, sp, ctx);
}

void expectMatchesReference(const ParticleSet& ps, const Params& p, double cellSize,
                            const std::string& what)
{
    SCOPED_TRACE(what);
    const anisotropy::ShapeParams sp = shapeParams(p);
    neighbors::CellIndex index;
    classify::Classification classes;
    const anisotropy::KernelShapes shapes = shapesOf(ps, p, cellSize, sp, index, classes);
    ASSERT_EQ(shapes.shapes.size(), 6 * ps.size());
    size_t checked = 0, stretched = 0, sparse = 0, bad = 0;
    for (size_t k = 0; k < ps.size(); ++k) {
        const size_t i = index.order[k];
        const float* g = &shapes.shapes[6 * k];
        const Vec3f c = shapes.centres[k];
        if (!classify::isSurface(classes.classes[k])) {
            const float iso = float(1 / sp.influenceRadius);
            bad += !(g[0] == iso && g[3] == iso && g[5] == iso && g[1] == 0 && g[2] == 0 &&
                     g[4] == 0 && c == ps.positions[i]);
            continue;
        }
        const Reference r = reference(ps, i, sp);
        stretched += !r.sparse, sparse += r.sparse;
        if (r.nearClamp) continue;
        ++checked;
        const double s[6] = {g[0], g[1], g[2], g[3], g[4], g[5]};
        const Mat got = fromSym(s);
        double norm = 0, err = 0;
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b) {
                const double want = r.sparse ? (a == b ? 1 / sp.influenceRadius : 0) : r.g[a][b];
                norm = std::max(norm, std::fabs(want));
                err = std::max(err, std::fabs(got[a][b] - want));
            }
        double move = 0;
        for (int a = 0; a < 3; ++a)
            move = std::max(move, std::fabs(double(c[a]) - r.centre[a]));
        if (err > 1e-4 * norm || move > 1e-6 * (1 + std::fabs(r.centre[0]))) {
            if (bad < 5)
                ADD_FAILURE() << "particle " << i << ": G off by " << err / norm
                              << " (relative), centre by " << move;
            ++bad;
        }
    }
    EXPECT_EQ(bad, 0u);
    EXPECT_EQ(shapes.stretched, stretched) << "of " << checked << " checked";
    EXPECT_GT(stretched, checked / 4) << "most surface particles have a full neighbourhood";
    (void)sparse;
}

} // namespace

TEST(SymmetricEigen, RecoversBuiltMatrices)
{
    // Q diag(l) Q^T for rotations about skew axes, with distinct, double and triple eigenvalues
    const double values[][3] = {{3, 2, 1}, {5, 5, 1}, {4, 1, 1}, {2, 2, 2}, {1e-6, 3e-7, 0}};
    for (const auto& l : values)
        for (double angle : {0.0, 0.3, 1.7, 2.9}) {
            const double ax[3] = {0.48, -0.6, 0.64}; // a unit axis
            const double c = std::cos(angle), s = std::sin(angle);
            Mat q;
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) {
                    const double cross =
                        (i == j) ? 0 : ((j == (i + 1) % 3) ? -1 : 1) * ax[3 - i - j];
                    q[i][j] = (i == j ? c : 0) + (1 - c) * ax[i] * ax[j] + s * cross;
                }
            double a[6];
            const int row[6] = {0, 0, 0, 1, 1, 2}, col[6] = {0, 1, 2, 1, 2, 2};
            for (int k = 0; k < 6; ++k) {
                a[k] = 0;
                for (int m = 0; m < 3; ++m)
                    a[k] += q[row[k]][m] * l[m] * q[col[k]][m];
            }
            const anisotropy::Eigen3 e = anisotropy::symmetricEigen(a);
            const double size = l[0] + 1e-300;
            for (int k = 0; k < 3; ++k)
                EXPECT_NEAR(e.values[k], l[k], 1e-12 * size);
            // orthonormal and right-handed; V diag V^T = A
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) {
                    double dot = 0, back = 0;
                    for (int m = 0; m < 3; ++m) {
                        dot += e.vectors[i][m] * e.vectors[j][m];
                        back += e.vectors[m][i] * e.values[m] * e.vectors[m][j];
                    }
                    EXPECT_NEAR(dot, i == j ? 1 : 0, 1e-12);
                    EXPECT_NEAR(back, fromSym(a)[i][j], 1e-12 * size);
                }
            const Mat v = {{{e.vectors[0][0], e.vectors[0][1], e.vectors[0][2]},
                            {e.vectors[1][0], e.vectors[1][1], e.vectors[1][2]},
                            {e.vectors[2][0], e.vectors[2][1], e.vectors[2][2]}}};
            EXPECT_NEAR(det(v), 1, 1e-12);
        }
}

TEST(KernelShapes, MatchBruteForcePcaOnSheetsJetsAndAFrame)
{
    SceneParams s;
    s.radius = 0.025, s.count = 3000, s.jitter = 0.3, s.layers = 2;
    const Params p = Params::fromRadius(s.radius);
    // cells of h (the classification's) and of 0.6 h: the walk covers the PCA radius either way
    expectMatchesReference(generateScene(Scene::Sheet, s), p, p.smoothingLength, "sheet");
    expectMatchesReference(generateScene(Scene::Sheet, s), p, 0.6 * p.smoothingLength, "sheet");
    s.layers = 2, s.count = 1500; // 4 a slice: 32 neighbours or so within the PCA radius
    expectMatchesReference(generateScene(Scene::Jet, s), p, p.smoothingLength, "jet");
    s.layers = 6, s.count = 3000, s.jitter = 0.25;
    expectMatchesReference(generateScene(Scene::Slab, s), p, p.smoothingLength, "slab");
    if (!sharedData().empty())
        expectMatchesReference(
            io::readParticles(sharedData() + "/real/double_dam_break_frame_26_4732_particles.vtk"),
            p, p.smoothingLength, "double_dam_break_frame_26");
}

TEST(KernelShapes, AFlatFaceGivesAFlatKernelAndAHeavierCentreBelow)
{
    // a lattice slab without jitter: a top particle away from the edges sees a half ball, so its
    // kernel is shortest along z (R_inf), round and longer in x-y; its centre moves down only
    SceneParams s;
    s.radius = 0.025, s.count = 6 * 20 * 20, s.jitter = 0, s.layers = 6;
    const ParticleSet slab = generateScene(Scene::Slab, s);
    const Params p = Params::fromRadius(s.radius);
    neighbors::CellIndex index;
    classify::Classification classes;
    const anisotropy::KernelShapes shapes =
        shapesOf(slab, p, p.smoothingLength, shapeParams(p), index, classes);
    const double spacing = 2 * s.radius, top = 5 * spacing;
    size_t checked = 0;
    for (size_t k = 0; k < slab.size(); ++k) {
        const Vec3f x = slab.positions[index.order[k]];
        if (!(x.z == float(top) && x.x > 5.5 * spacing && x.x < 13.5 * spacing &&
              x.y > 5.5 * spacing && x.y < 13.5 * spacing))
            continue;
        ++checked;
        const float* g = &shapes.shapes[6 * k];
        EXPECT_NEAR(g[1], 0, 1e-3 * g[0]);
        EXPECT_NEAR(g[2], 0, 1e-3 * g[0]);
        EXPECT_NEAR(g[4], 0, 1e-3 * g[0]);
        EXPECT_NEAR(g[0], g[3], 1e-4 * g[0]) << "round in x-y";
        EXPECT_GT(g[5], 1.5 * g[0]) << "shortest along z";
        EXPECT_NEAR(g[5] * p.influenceRadius, 1, 1e-5) << "the shortest axis is R";
        EXPECT_NEAR(shapes.centres[k].x, x.x, 1e-6);
        EXPECT_NEAR(shapes.centres[k].y, x.y, 1e-6);
        EXPECT_LT(shapes.centres[k].z, x.z - 0.1 * spacing) << "moved towards the fluid";
    }
    EXPECT_EQ(checked, 64u);
}

TEST(KernelShapes, SameBytesForAnyThreadCountAndBadParamsRefused)
{
    SceneParams s;
    s.radius = 0.025, s.count = 20000, s.jitter = 0.3;
    const ParticleSet ps = generateScene(Scene::Drop, s);
    const Params p = Params::fromRadius(s.radius);
    neighbors::CellIndex index;
    classify::Classification classes;
    const anisotropy::KernelShapes all =
        shapesOf(ps, p, p.smoothingLength, shapeParams(p), index, classes);
    {
        tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
        Context ctx;
        const anisotropy::KernelShapes single =
            anisotropy::kernelShapes(index, classes, shapeParams(p), ctx);
        EXPECT_EQ(std::memcmp(all.shapes.data(), single.shapes.data(), 4 * all.shapes.size()), 0);
        EXPECT_EQ(std::memcmp(all.centres.data(), single.centres.data(), 12 * all.centres.size()),
                  0);
    }
    EXPECT_GT(all.stretched, 0u);
    Context ctx;
    anisotropy::ShapeParams bad = shapeParams(p);
    bad.maxAxisRatio = 0.5;
    EXPECT_THROW(anisotropy::kernelShapes(index, classes, bad, ctx), ValueError);
    bad = shapeParams(p), bad.centreSmoothing = 1.5;
    EXPECT_THROW(anisotropy::kernelShapes(index, classes, bad, ctx), ValueError);
    bad = shapeParams(p), bad.pcaRadius = std::nan("");
    EXPECT_THROW(anisotropy::kernelShapes(index, classes, bad, ctx), ValueError);
}
