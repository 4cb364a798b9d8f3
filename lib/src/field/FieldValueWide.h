// FieldValueWide.h - FieldMath's fieldValue for four voxels at once, on AVX2 (4 doubles a
// register): the same operations in the same order, with the branches as selects, so every
// value is bit-identical to fieldValue's (no fused multiply-adds: the target is AVX2 alone).
// Why: the value's chain of roots and divisions (the eigenvalue) waits on each step, and one
// voxel after another it was a quarter of the field stage's time on the 1.7M-particle frame.
// Host only; the CUDA field calls fieldValue itself.
#pragma once

#include "field/FieldMath.h"

namespace fluidsurf {
namespace field {

/// out[i] = fieldValue(sums[i], c) for i < n. Only where the CPU has AVX2 (fieldLanes() == 8
/// in GatherField.h implies it); elsewhere it faults.
void fieldValuesWide(const FieldSums* sums, int n, const FieldConstants& c, float* out);

} // namespace field
} // namespace fluidsurf
