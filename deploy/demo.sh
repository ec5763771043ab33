#!/usr/bin/env bash
# The main job on the bundled default: builds gdvr if needed and renders the
# bundled animation, leaving EXR frames and stats in the folder it prints.
set -euo pipefail
cd "$(dirname "$0")/.."
bash deploy/build.sh
OUT=${1:-out/demo}
mkdir -p "$OUT"
./build/core/gdvr-render scenes/demo/demo_job.json --out "$OUT"
echo "demo: frames and stats.json are in $(cd "$OUT" && pwd)"
