#!/usr/bin/env bash
# install-deps.sh - install exactly the Debian 12 packages fluidsurf needs (see DESIGN.md).
# Idempotent: packages already present are skipped, so a second run costs a few seconds.
# CUDA 13 is expected at /usr/local/cuda (not a Debian package); without it the build drops CUDA.
set -euo pipefail

PACKAGES=(
    libopenvdb-dev libopenvdb-tools libnanovdb-dev libtbb-dev libblosc-dev
    libboost-iostreams-dev libopenmesh-dev libgtest-dev libgmock-dev libbenchmark-dev
    libcli11-dev zlib1g-dev cmake ninja-build g++
    # The CLI end-to-end tests: /usr/bin/python3 checks OBJ files and memory figures
    # independently, numpy re-reads the .npy round trip, pyopenvdb opens the written level set.
    python3 python3-numpy python3-openvdb
    # The Python package (tools/python, pybind11) and its tests (tests/python, pytest).
    python3-dev python3-pybind11 python3-pytest
    # CI's format check (tools/scripts/check-format.sh) against .clang-format.
    clang-format
    # The farm test (tests/integration/slurm_test.sh) starts a single-node Slurm of its own.
    slurm-wlm munge
)

missing=()
for p in "${PACKAGES[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if [ ${#missing[@]} -eq 0 ]; then
    echo "install-deps: all ${#PACKAGES[@]} packages present"
    exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "install-deps: done"
