#!/usr/bin/env bash
# check_cuda_includes.sh SOURCE_DIR - cuda/ sees plain arrays and its own headers: from the
# library it may include only the public Vec3.h and Error.h and the plain math that both backends
# compile (util/HostDevice.h, util/Floor.h, field/FieldMath.h, field/AnisotropicSums.h, field/GatherLayout.h,
# classify/ClassRule.h, neighbors/CellSlot.h, mesh/CellPolygons.h, mesh/GradientMath.h,
# post/SmoothSteps.h, post/RayPlanes.h).
# No OpenVDB, ever.
set -euo pipefail
cd "$1"
allowed='^(facade/|fluidsurf/Vec3\.h|fluidsurf/Error\.h|util/HostDevice\.h|util/Floor\.h|field/FieldMath\.h|field/AnisotropicSums\.h|field/GatherLayout\.h|classify/ClassRule\.h|neighbors/CellSlot\.h|mesh/CellPolygons\.h|mesh/GradientMath\.h|post/SmoothSteps\.h|post/RayPlanes\.h|cub/|cuda_runtime|[a-z_]+(\.h)?$|[A-Z][A-Za-z]*\.cuh$)'
bad=0
while IFS= read -r line; do
    file=${line%%:*}
    inc=$(sed -E 's/.*#include [<"]([^>"]+)[>"].*/\1/' <<<"$line")
    if ! grep -Eq "$allowed" <<<"$inc"; then
        echo "cuda/ includes '$inc' ($file): not one of its own headers or the shared math"
        bad=1
    fi
done < <(grep -rn '#include' cuda/src cuda/facade)
# The shared math includes nothing of the library beyond the macro.
if grep -n '#include "' lib/src/field/FieldMath.h lib/src/field/AnisotropicSums.h lib/src/field/GatherLayout.h \
    lib/src/util/Floor.h lib/src/classify/ClassRule.h lib/src/neighbors/CellSlot.h \
    lib/src/mesh/CellPolygons.h lib/src/mesh/GradientMath.h lib/src/post/SmoothSteps.h lib/src/post/RayPlanes.h |
    grep -v 'util/HostDevice.h' | grep -v 'GatherLayout.h:.*util/Floor.h' |
    grep -v 'AnisotropicSums.h:.*field/FieldMath.h'; then
    echo "the shared math headers include library headers"; bad=1
fi
[ "$bad" = 0 ] && echo "cuda includes: 1 passed, 0 failed" || { echo "cuda includes: 0 passed, 1 failed"; exit 1; }
