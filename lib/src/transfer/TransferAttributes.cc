// TransferAttributes.cc - the first-order (linear) moving-least-squares weights of each point,
// applied to every float attribute; integers from the nearest particle.
#include <fluidsurf/Error.h>
#include <fluidsurf/TransferAttributes.h>

#include "neighbors/CellIndex.h"
#include "util/Threads.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace fluidsurf {

namespace {

/// Below this spread (det / (trace / 3)^3 of the particles' weighted covariance) a fit over R
/// is retried over 2R: a single flat layer gives ~0, a half-space of lattice particles ~0.2.
constexpr double kMinSpread = 0.01;

struct Neighbour
{
    uint32_t index; ///< into the input particles
    double w;
    double d[3]; ///< x_j - x
};

/// The particles within R of p (and the nearest of them), in cell order.
void gather(const neighbors::CellIndex& cells, const Vec3f& p, double R,
            std::vector<Neighbour>& out)
{
    out.clear();
    const double lo[3] = {p.x - R, p.y - R, p.z - R}, hi[3] = {p.x + R, p.y + R, p.z + R};
    const double invR2 = 1.0 / (R * R);
    cells.forEachCellInBox(lo, hi, [&](uint32_t begin, uint32_t end) {
        for (uint32_t k = begin; k < end; ++k) {
            const Vec3f& x = cells.positions[k];
            const double d[3] = {double(x.x) - p.x, double(x.y) - p.y, double(x.z) - p.z};
            const double s2 = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) * invR2;
            if (s2 >= 1) continue;
            const double t = 1 - s2;
            out.push_back({cells.order[k], t * t * t, {d[0], d[1], d[2]}});
        }
    });
}

double distance2(const Vec3f& a, const Vec3f& b)
{
    const double d[3] = {double(a.x) - b.x, double(a.y) - b.y, double(a.z) - b.z};
    return d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
}

/// The nearest particle to p (ties: the lower input index), searching boxes of growing size;
/// once a box would hold more cells than there are particles, all particles.
uint32_t nearest(const neighbors::CellIndex& cells, const Vec3f& p, double R)
{
    uint32_t best = 0;
    double bestD2 = std::numeric_limits<double>::infinity();
    auto consider = [&](uint32_t k) {
        const double d2 = distance2(cells.positions[k], p);
        if (d2 < bestD2 || (d2 == bestD2 && cells.order[k] < best))
            best = cells.order[k], bestD2 = d2;
    };
    for (double rho = R;; rho *= 2) {
        const double cellsPerAxis = 2 * rho / cells.cellSize + 2;
        if (cellsPerAxis * cellsPerAxis * cellsPerAxis > double(cells.size())) {
            for (uint32_t k = 0; k < cells.size(); ++k)
                consider(k);
            return best;
        }
        const double lo[3] = {p.x - rho, p.y - rho, p.z - rho};
        const double hi[3] = {p.x + rho, p.y + rho, p.z + rho};
        cells.forEachCellInBox(lo, hi, [&](uint32_t begin, uint32_t end) {
            for (uint32_t k = begin; k < end; ++k)
                consider(k);
        });
        if (bestD2 <= rho * rho) return best; // every particle within rho was in the box
    }
}

/// det(M) / (trace(M) / 3)^3: 1 where the particles spread alike in every direction, 0 where
/// they form a sheet, a line or one point.
double spread(const double M[3][3])
{
    const double t = (M[0][0] + M[1][1] + M[2][2]) / 3;
    if (!(t > 0)) return 0;
    const double det = M[0][0] * (M[1][1] * M[2][2] - M[1][2] * M[2][1]) -
                       M[0][1] * (M[1][0] * M[2][2] - M[1][2] * M[2][0]) +
                       M[0][2] * (M[1][0] * M[2][1] - M[1][1] * M[2][0]);
    return det / (t * t * t);
}

/// The weights phi_j of the linear fit at the point (TransferAttributes.h); sum phi_j = 1.
/// Returns the spread of the particles (above).
double linearWeights(std::vector<Neighbour>& nb, double R, std::vector<double>& phi)
{
    double W = 0, m[3] = {0, 0, 0};
    for (const Neighbour& n : nb) {
        W += n.w;
        for (int a = 0; a < 3; ++a)
            m[a] += n.w * n.d[a];
    }
    const double dbar[3] = {m[0] / W, m[1] / W, m[2] / W};
    double M[3][3] = {};
    for (const Neighbour& n : nb) {
        const double e[3] = {n.d[0] - dbar[0], n.d[1] - dbar[1], n.d[2] - dbar[2]};
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b)
                M[a][b] += n.w * e[a] * e[b];
    }
    const double spreadOf = spread(M);
    // The ridge: a direction in which the particles do not spread gets no slope. Its floor
    // (relative to W R^2) covers one particle, or several in one place, where M is rounding
    // noise: the fit is then their average.
    const double ridge = 1e-4 * (M[0][0] + M[1][1] + M[2][2]) + 1e-9 * W * R * R;
    for (int a = 0; a < 3; ++a)
        M[a][a] += ridge;
    // u = M^-1 dbar by the adjugate (M is symmetric positive definite)
    const double c00 = M[1][1] * M[2][2] - M[1][2] * M[2][1];
    const double c01 = M[1][2] * M[2][0] - M[1][0] * M[2][2];
    const double c02 = M[1][0] * M[2][1] - M[1][1] * M[2][0];
    const double c11 = M[0][0] * M[2][2] - M[0][2] * M[2][0];
    const double c12 = M[0][2] * M[1][0] - M[0][0] * M[1][2];
    const double c22 = M[0][0] * M[1][1] - M[0][1] * M[1][0];
    const double det = M[0][0] * c00 + M[0][1] * c01 + M[0][2] * c02;
    const double u[3] = {(c00 * dbar[0] + c01 * dbar[1] + c02 * dbar[2]) / det,
                         (c01 * dbar[0] + c11 * dbar[1] + c12 * dbar[2]) / det,
                         (c02 * dbar[0] + c12 * dbar[1] + c22 * dbar[2]) / det};
    phi.resize(nb.size());
    for (size_t j = 0; j < nb.size(); ++j) {
        const Neighbour& n = nb[j];
        const double along =
            u[0] * (n.d[0] - dbar[0]) + u[1] * (n.d[1] - dbar[1]) + u[2] * (n.d[2] - dbar[2]);
        phi[j] = n.w * (1 / W - along);
    }
    return spreadOf;
}

std::string namesOf(const ParticleSet& ps)
{
    std::string s;
    for (const Attribute& a : ps.attributes)
        s += (s.empty() ? "" : ", ") + a.name;
    return s.empty() ? "none" : s;
}

} // namespace

const Attribute* findAttribute(const ParticleSet& ps, const std::string& name)
{
    if (const Attribute* a = ps.find(name)) return a;
    for (AttributeRole role : {AttributeRole::Radius, AttributeRole::Velocity,
                               AttributeRole::Density, AttributeRole::Id})
        if (isRoleAlias(role, name))
            if (const Attribute* a = ps.find(role)) return a;
    return nullptr;
}

void checkAttributeNames(const ParticleSet& ps, const std::vector<std::string>& names)
{
    std::vector<const Attribute*> found;
    for (const std::string& name : names) {
        const Attribute* a = findAttribute(ps, name);
        if (!a)
            throw ValueError("no attribute '" + name +
                             "' in the particles (they have: " + namesOf(ps) + ")");
        if (std::find(found.begin(), found.end(), a) != found.end())
            throw ValueError("attribute '" + name + "' is asked for twice");
        found.push_back(a);
    }
}

std::vector<Attribute> transferAttributes(const ParticleSet& ps,
                                          const std::vector<std::string>& names,
                                          const std::vector<Vec3f>& points, double R, Context& ctx)
{
    if (!std::isfinite(R) || !(R > 0))
        throw ValueError("transfer: the influence radius must be positive and finite");
    checkAttributeNames(ps, names);
    std::vector<const Attribute*> sources;
    for (const std::string& name : names)
        sources.push_back(findAttribute(ps, name));
    ps.validate();
    std::vector<Attribute> out;
    for (const Attribute* a : sources) {
        Attribute t;
        t.name = a->name, t.type = a->type, t.components = a->components;
        if (t.type == AttributeType::Float)
            t.floats.resize(points.size() * size_t(t.components));
        else
            t.ints.resize(points.size() * size_t(t.components));
        out.push_back(std::move(t));
    }
    if (out.empty() || points.empty() || ps.empty()) {
        if (!points.empty() && ps.empty() && !out.empty())
            throw ValueError("transfer: no particles to take attributes from");
        return out;
    }

    const auto timer = ctx.scope("transfer");
    util::withThreads(ctx, [&] {
        const neighbors::CellIndex cells =
            neighbors::buildCellIndex(ps.positions.data(), nullptr, ps.size(), R, ctx);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, points.size(), 256),
                          [&](const tbb::blocked_range<size_t>& range) {
                              ctx.checkpoint();
                              std::vector<Neighbour> nb, wide;
                              std::vector<double> phi, widePhi;
                              for (size_t i = range.begin(); i != range.end(); ++i) {
                                  gather(cells, points[i], R, nb);
                                  uint32_t near = 0;
                                  double nearD2 = std::numeric_limits<double>::infinity();
                                  for (const Neighbour& n : nb) {
                                      const double d2 =
                                          n.d[0] * n.d[0] + n.d[1] * n.d[1] + n.d[2] * n.d[2];
                                      if (d2 < nearD2 || (d2 == nearD2 && n.index < near))
                                          near = n.index, nearD2 = d2;
                                  }
                                  if (nb.empty()) near = nearest(cells, points[i], R);
                                  // Too flat a neighbourhood (the band's outer voxels see
                                  // only the outer layer of particles): a wider one, where
                                  // that spreads in every direction.
                                  if (!nb.empty() && linearWeights(nb, R, phi) < kMinSpread) {
                                      gather(cells, points[i], 2 * R, wide);
                                      if (linearWeights(wide, 2 * R, widePhi) >= kMinSpread)
                                          nb.swap(wide), phi.swap(widePhi);
                                  }
                                  for (size_t k = 0; k < out.size(); ++k) {
                                      const Attribute& src = *sources[k];
                                      Attribute& dst = out[k];
                                      const size_t c = size_t(src.components);
                                      for (size_t comp = 0; comp < c; ++comp) {
                                          if (src.type == AttributeType::Int) {
                                              dst.ints[i * c + comp] = src.ints[near * c + comp];
                                          } else if (nb.empty()) {
                                              dst.floats[i * c + comp] =
                                                  src.floats[near * c + comp];
                                          } else {
                                              double v = 0;
                                              for (size_t j = 0; j < nb.size(); ++j)
                                                  v += phi[j] * src.floats[nb[j].index * c + comp];
                                              dst.floats[i * c + comp] = float(v);
                                          }
                                      }
                                  }
                              }
                          });
    });
    return out;
}

} // namespace fluidsurf
