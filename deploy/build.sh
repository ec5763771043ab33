#!/usr/bin/env bash
# Installs dependencies (idempotent) and builds gdvr into build/ (Release).
set -euo pipefail
cd "$(dirname "$0")/.."
bash deploy/install-deps.sh
BUILD_DIR=${GDVR_BUILD_DIR:-build}
cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=Release ${GDVR_CMAKE_ARGS:-}
cmake --build "$BUILD_DIR" -j "$(nproc)"
