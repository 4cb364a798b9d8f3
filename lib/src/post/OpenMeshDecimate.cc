// OpenMeshDecimate.cc - OpenMesh's quadric decimater on our mesh arrays (see OpenMeshDecimate.h).
#include "post/OpenMeshDecimate.h"

#include <fluidsurf/Error.h>

// OpenMesh 9's property containers trip GCC 12's -Wmaybe-uninitialized inside their own
// templates (a default-constructed property value); nothing of ours is involved
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Tools/Decimater/DecimaterT.hh>
#include <OpenMesh/Tools/Decimater/ModNormalFlippingT.hh>
#include <OpenMesh/Tools/Decimater/ModQuadricT.hh>
#include <OpenMesh/Tools/Decimater/Observer.hh>
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif

#include <string>
#include <vector>

namespace fluidsurf {
namespace post {

namespace {
using OmMesh = OpenMesh::TriMesh_ArrayKernelT<>;

/// The context's checkpoint after every collapse (a relaxed load and a try-lock: nothing beside
/// one collapse's heap updates); a cancel there stops the decimater. Every 1000 collapses was
/// seconds where OpenMesh's collapse checks grow with the square of a vertex's valence.
class CancelObserver : public OpenMesh::Decimater::Observer
{
public:
    explicit CancelObserver(Context& ctx) : Observer(1), mCtx(ctx) {}
    void notify(size_t) override
    {
        try {
            mCtx.checkpoint();
        } catch (const Cancelled&) {
            mStop = true;
        }
    }
    bool abort() const override { return mStop || mCtx.cancelled(); }

private:
    Context& mCtx;
    bool mStop = false;
};

/// OpenMesh says what it refuses on its own stream (`PolyMeshT::add_face: complex edge`): a
/// second message beside ours. Quiet while it lives.
struct QuietOpenMesh
{
    QuietOpenMesh() { omerr().disable(); }
    ~QuietOpenMesh() { omerr().enable(); }
};
} // namespace

TriangleMesh decimateOpenMesh(const TriangleMesh& in, size_t targetTriangles, Context& ctx)
{
    const QuietOpenMesh quiet;
    OmMesh m;
    std::vector<OmMesh::VertexHandle> handles;
    handles.reserve(in.points.size());
    for (const Vec3f& p : in.points)
        handles.push_back(m.add_vertex(OmMesh::Point(p.x, p.y, p.z)));
    for (size_t t = 0; t < in.triangles.size(); ++t) {
        const auto& [a, b, c] = in.triangles[t];
        if (!m.add_face(handles[a], handles[b], handles[c]).is_valid())
            throw ValueError("OpenMesh cannot take triangle " + std::to_string(t) +
                             " (a non-manifold edge or vertex); decimate a manifold mesh");
    }
    m.request_face_normals();
    m.update_face_normals();
    OpenMesh::Decimater::DecimaterT<OmMesh> decimater(m);
    OpenMesh::Decimater::ModQuadricT<OmMesh>::Handle quadric;
    OpenMesh::Decimater::ModNormalFlippingT<OmMesh>::Handle flipping;
    decimater.add(quadric);
    decimater.add(flipping);
    decimater.module(quadric).unset_max_err();
    decimater.initialize();
    CancelObserver observer(ctx);
    decimater.set_observer(&observer);
    decimater.decimate_to_faces(0, targetTriangles);
    decimater.set_observer(nullptr);
    if (observer.abort()) throw Cancelled("cancelled");
    m.garbage_collection();

    TriangleMesh out;
    out.points.reserve(m.n_vertices());
    for (const auto& v : m.vertices()) {
        const OmMesh::Point& p = m.point(v);
        out.points.emplace_back(p[0], p[1], p[2]);
    }
    out.triangles.reserve(m.n_faces());
    for (const auto& f : m.faces()) {
        std::array<uint32_t, 3> t{};
        int k = 0;
        for (const auto& v : m.fv_range(f))
            t[k++] = uint32_t(v.idx());
        out.triangles.push_back(t);
    }
    return out; // without normals: see Normals.h
}

} // namespace post
} // namespace fluidsurf
