// LevelSetIO.h - level sets in .vdb files: reading the grid to mesh, writing grids atomically and
// deterministically, and describing what a .vdb holds (`fluidsurf info`).
#pragma once

#include <fluidsurf/AdaptiveGrid.h>

#include <openvdb/openvdb.h>

#include <string>
#include <utility>
#include <vector>

namespace fluidsurf {
namespace io {

/// Read a level set from a .vdb file: the float grid named gridName, or (empty name) the first
/// grid of class level set, else the first float grid. InputError naming the file otherwise,
/// also for a grid no mesher can use (voxel size or background not positive and finite).
openvdb::FloatGrid::Ptr readLevelSet(const std::string& path, const std::string& gridName = "");

/// The same from the bytes of a .vdb in memory; source names them in errors.
openvdb::FloatGrid::Ptr readLevelSetFromMemory(const uint8_t* data, size_t size,
                                               const std::string& source,
                                               const std::string& gridName = "");

/// What `fluidsurf mesh` meshes in a .vdb: an adaptive grid (AdaptiveGrid.h) when the file holds
/// one and no grid name is given (grid is then its level 2), else readLevelSet's grid.
struct LevelSetFile
{
    openvdb::FloatGrid::Ptr grid;
    AdaptiveGrid adaptive;
};
LevelSetFile readLevelSetFile(const std::string& path, const std::string& gridName = "");

/// Write grids to a .vdb (Blosc), atomically (temporary file + rename). The file's UUID is
/// derived from its content, so equal grids give byte-identical files. OutputError on failure.
void writeLevelSet(const openvdb::GridPtrVec& grids, const std::string& path);

/// One grid of a .vdb file, as `fluidsurf info` shows it.
struct GridDescription
{
    std::string name, gridClass, valueType;
    double voxelSize[3] = {0, 0, 0};
    bool linear = true; ///< a linear (affine) transform, not a frustum
    uint64_t activeVoxels = 0, leaves = 0;
    int64_t bboxMin[3] = {0, 0, 0}, bboxMax[3] = {0, 0, 0};    ///< active voxels, index space
    bool empty = true;                                         ///< no active voxel
    std::string background;                                    ///< as text
    std::vector<std::pair<std::string, std::string>> metadata; ///< name, value as text
};

/// Every grid of a .vdb file (read whole, validated like every reader). InputError otherwise.
/// Grids of types fluidsurf does not check (bool, mask, string trees; frustum transforms) are
/// not read; each is listed in skipped as "name (type): why".
std::vector<GridDescription> describeVdb(const std::string& path,
                                         std::vector<std::string>* skipped = nullptr);

} // namespace io
} // namespace fluidsurf
