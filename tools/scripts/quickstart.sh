#!/usr/bin/env bash
# quickstart.sh - install dependencies, build, and run the main job on the sample frame:
# describe it, and reconstruct its surface as a narrow-band level set (out/drop_surface.vdb) and
# a triangle mesh (out/drop_surface.obj), with per-stage timings and a check of the mesh.
set -euo pipefail
cd "$(dirname "$0")/../.."
bash tools/scripts/install-deps.sh
bash tools/scripts/build.sh build
mkdir -p out
SAMPLE=data/drop_39849_particles.bgeo.gz
./build/fluidsurf info "$SAMPLE"
./build/fluidsurf reconstruct "$SAMPLE" -r 0.01 -o out/drop_surface.obj --vdb out/drop_surface.vdb -v --check
echo "quickstart: wrote out/drop_surface.vdb (level set 'surface') and out/drop_surface.obj (mesh with normals)"
