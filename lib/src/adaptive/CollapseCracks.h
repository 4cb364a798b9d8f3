// CollapseCracks.h - closing a crack that has one level-2 edge without adding triangles
// (MeshLevels.cc, after the cells are meshed and before the cracks are cut or fanned).
//
// Such a crack is a level-2 edge a -> b on a face between levels and, across the gap, the
// level-3 path from b to a through one or two points inside the level-2 face square (where the
// path crosses the square's middle lines). Cutting the level-2 triangle at those points closes
// it with one triangle more per point (a sliver); merging each point into an end of the edge
// closes it with one triangle less (the level-3 cell's sliver at that point flattens away), and
// moves the level-3 surface only along itself by at most the point's distance to that end. The
// points lie on values sub-sampled from level 2 (LevelFields.h), so they carry no level-3
// detail that the merge could lose.
#pragma once

#include <fluidsurf/Mesh.h>

#include <cstdint>
#include <vector>

namespace fluidsurf {
namespace adaptive {

/// One crack: its level-2 edge a -> b (as the level-2 triangle walks it) and the level-3 points
/// across the gap, in order from a to b.
struct CrackPath
{
    uint32_t a = 0, b = 0;
    std::vector<uint32_t> between;
};

/// Merges each path's points into its ends: the first half into a, the second into b (working
/// inwards from each end, so each point merges into a vertex it shares a triangle with), a
/// middle one into b only if clearly nearer (0.1%), else a. A merge is done only where afterwards
/// no edge at the end has two triangles walking it the same way (so none has three), the end's
/// triangles still form one fan if they close around it, and no triangle that changes turns over or
/// loses its area; otherwise that point and those further in stay. The triangles that flatten are
/// marked in `removed` (resized to the triangles); `between` keeps the points left, for cutting the
/// level-2 triangle. Serial and in the paths' order, so the result does not depend on threads
/// (cracks touch about 1% of the triangles). Returns how many points were merged.
size_t collapseCracks(TriangleMesh& mesh, std::vector<CrackPath>& paths,
                      std::vector<char>& removed);

} // namespace adaptive
} // namespace fluidsurf
