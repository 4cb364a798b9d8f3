// SmoothSteps.h - the numbers of post/Smooth's steps, as plain constants that the CPU smoothing
// (post/Smooth.cc, which says why each is what it is) and the GPU's (cuda/src/Smooth.cu) both
// compile, so that the two take the same steps.
#pragma once

namespace fluidsurf {
namespace post {
namespace steps {

constexpr double kLambda = 0.5, kMu = -0.5; ///< Taubin's pair
constexpr int kFlatSteps = 34;              ///< plain Laplacian steps on the flat regions
constexpr double kFlatLambda = 0.9;         ///< their factor
constexpr int kSlowSteps = 80;              ///< averaging steps: the slow part of their moves
constexpr int kNormalSteps = 4;             ///< flat steps per new set of normals
constexpr int kShapeSteps = 20;  ///< plain Laplacian steps on the copy the curvature is taken on
constexpr int kFeatureRings = 2; ///< rings over which a curved point keeps its neighbours still
constexpr double kThinReach = 3; ///< voxels: the surface facing a point this near: thin
constexpr double kFlatCurvature = 1 / 33.0;   ///< per voxel: full weight below
constexpr double kCurvedCurvature = 1 / 12.5; ///< per voxel: no weight above
constexpr double kFacing = -0.5; ///< unit normals' dot below this: the surfaces face each other
constexpr double kTurned = 0.5;  ///< a triangle's normal turned past 60 degrees (cos below this)

} // namespace steps
} // namespace post
} // namespace fluidsurf
