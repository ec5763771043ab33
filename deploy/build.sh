#!/usr/bin/env bash
# Installs dependencies (idempotent) and builds gdvr into build/ (Release).
set -euo pipefail
cd "$(dirname "$0")/.."
bash deploy/install-deps.sh
BUILD_DIR=${GDVR_BUILD_DIR:-build}
# Options are set explicitly so that a build folder configured differently
# before (e.g. without the service) is brought back to the full build.
cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=Release -DGDVR_BUILD_SERVICE=ON -DGDVR_BUILD_TESTS=ON ${GDVR_CMAKE_ARGS:-}
cmake --build "$BUILD_DIR" -j "$(nproc)"
