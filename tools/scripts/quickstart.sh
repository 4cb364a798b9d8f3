#!/usr/bin/env bash
# quickstart.sh - install dependencies, build, and run the main job on the sample frame:
# describe it, rasterize it to a narrow-band level set (out/drop_surface.vdb, with the per-stage
# timings) and convert it to OpenVDB points.
set -euo pipefail
cd "$(dirname "$0")/../.."
bash tools/scripts/install-deps.sh
bash tools/scripts/build.sh build
mkdir -p out
SAMPLE=data/drop_39849_particles.bgeo.gz
./build/fluidsurf info "$SAMPLE"
./build/fluidsurf convert "$SAMPLE" out/drop_points.vdb
./build/fluidsurf rasterize "$SAMPLE" -r 0.01 -o out/drop_surface.vdb -v
echo "quickstart: wrote out/drop_surface.vdb (level set 'surface') and out/drop_points.vdb"
