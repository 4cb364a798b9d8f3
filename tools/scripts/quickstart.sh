#!/usr/bin/env bash
# quickstart.sh - install dependencies, build, and run the main job on the sample frame:
# describe it, and convert it to an OpenVDB points file in out/.
set -euo pipefail
cd "$(dirname "$0")/../.."
bash tools/scripts/install-deps.sh
bash tools/scripts/build.sh build
mkdir -p out
SAMPLE=data/drop_39849_particles.bgeo.gz
./build/fluidsurf info "$SAMPLE"
./build/fluidsurf convert "$SAMPLE" out/drop_points.vdb
./build/fluidsurf convert "$SAMPLE" out/drop_points.ply
echo "quickstart: wrote out/drop_points.vdb and out/drop_points.ply"
