#!/usr/bin/env bash
# The main job: installs dependencies and builds gdvr (deploy/build.sh), starts
# gdvr-server on localhost, submits the bundled animation with the gdvr CLI,
# streams the frames back into the folder it names (default out/demo), fetches
# the previews, the video and stats.json next to them, stops the server with
# SIGTERM and prints where everything is.
#
#   bash deploy/demo.sh [OUT_DIR]
#
# Environment:
#   GDVR_BUILD_DIR        build folder (default build)
#   GDVR_DEMO_SKIP_BUILD  1: use the binaries already in GDVR_BUILD_DIR
#   GDVR_DEMO_JOB         job file (default scenes/demo/demo_job.json)
#   GDVR_DEMO_STATE       where the server keeps its job database, job folders
#                         and log (default out/.demo-server)
#   GDVR_DEMO_THREADS     render threads (default: all cores)
#
# Idempotent: the job is submitted with a key derived from the job file and the
# server binary, and the server's state persists in GDVR_DEMO_STATE/<key>, so
# running again with nothing changed streams the finished job back without
# rendering it again, and a run that was interrupted resumes where it stopped.
# State of other keys (an older job file or build) is deleted, so a stale
# unfinished job never resumes ahead of this one.
set -euo pipefail
cd "$(dirname "$0")/.."

OUT=${1:-out/demo}
BUILD_DIR=${GDVR_BUILD_DIR:-build}
JOB=${GDVR_DEMO_JOB:-scenes/demo/demo_job.json}
STATE_ROOT=${GDVR_DEMO_STATE:-out/.demo-server}
ASSET_ROOT=scenes

if [ "${GDVR_DEMO_SKIP_BUILD:-0}" != 1 ]; then
  bash deploy/build.sh
fi
SERVER_BIN=$BUILD_DIR/bin/gdvr-server
CLI=$BUILD_DIR/bin/gdvr
for b in "$SERVER_BIN" "$CLI"; do
  [ -x "$b" ] || { echo "demo: $b is missing; run deploy/build.sh" >&2; exit 1; }
done

mkdir -p "$OUT"
# The folder holds exactly this run's results.
rm -f "$OUT"/frame_*.exr "$OUT"/preview_*.png "$OUT"/video.mp4 "$OUT"/video.mov "$OUT"/video.mkv "$OUT"/stats.json

# Jobs name scenes relative to the asset root; the job file names its scene
# relative to itself.
JOB_SCENE=$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["scene"])' "$JOB")
SCENE=$(realpath --relative-to="$ASSET_ROOT" "$(dirname "$JOB")/$JOB_SCENE")
KEY=demo-$(cat "$JOB" "$SERVER_BIN" | sha256sum | cut -c1-24)
STATE=$STATE_ROOT/$KEY
mkdir -p "$STATE"
find "$STATE_ROOT" -mindepth 1 -maxdepth 1 -type d -name 'demo-*' ! -name "$KEY" -exec rm -rf {} +

# ---- Start gdvr-server on an ephemeral localhost port ----
rm -f "$STATE/port"
SERVER_ARGS=(--listen=127.0.0.1:0 --port-file="$STATE/port" --asset-root="$ASSET_ROOT"
             --output-root="$STATE/jobs" --db="$STATE/gdvr.db")
[ -n "${GDVR_DEMO_THREADS:-}" ] && SERVER_ARGS+=(--threads="$GDVR_DEMO_THREADS")
"$SERVER_BIN" "${SERVER_ARGS[@]}" >>"$STATE/server.log" 2>&1 &
SERVER_PID=$!

stop_server() {
  if kill -0 "$SERVER_PID" 2>/dev/null; then
    kill -TERM "$SERVER_PID"  # graceful: in-flight state saved, exits within its grace period
    local rc=0
    wait "$SERVER_PID" || rc=$?
    return $rc
  fi
}
trap 'stop_server || true' EXIT
trap 'echo "demo: interrupted; run again to resume" >&2; exit 130' INT TERM

for _ in $(seq 1 300); do
  [ -s "$STATE/port" ] && break
  kill -0 "$SERVER_PID" 2>/dev/null || { echo "demo: gdvr-server did not start:" >&2; tail -20 "$STATE/server.log" >&2; exit 1; }
  sleep 0.1
done
[ -s "$STATE/port" ] || { echo "demo: gdvr-server did not report its port" >&2; exit 1; }
export GDVR_SERVER=127.0.0.1:$(cat "$STATE/port")
"$CLI" health --wait 30 >/dev/null
echo "demo: gdvr-server (pid $SERVER_PID) is SERVING on $GDVR_SERVER; log: $STATE/server.log"

# ---- Submit the bundled animation and stream it back ----
START=$(date +%s)
"$CLI" submit "$JOB" --scene "$SCENE" --key "$KEY" --watch --out "$OUT"
END=$(date +%s)

# ---- Stop the server cleanly ----
trap - EXIT
stop_server
echo "demo: gdvr-server stopped (SIGTERM)"

# ---- Error-vs-time report (gdvr-report; docs/report.md) ----
# BEGIN gdvr-report step. PT (plain and with the stratified direct-light
# pass), G-PT (L1, L2, weighted) and T-GPT (L1, L2) on the first 24 frames of
# the same job at 64x64, at 0.1 and 0.3 s per frame, against a 512-spp PT
# reference cached in $OUT/report/reference/ (reused on the next run): about
# two minutes on 2 cores. GDVR_DEMO_REPORT=0 skips it.
REPORT=""
if [ "${GDVR_DEMO_REPORT:-1}" != 0 ]; then
  REPORT_ARGS=(--out "$OUT/report" --frames 0-23 --width 64 --height 64 --budgets 0.1,0.3 --reference-spp 512)
  [ -n "${GDVR_DEMO_THREADS:-}" ] && REPORT_ARGS+=(--threads "$GDVR_DEMO_THREADS")
  if "$BUILD_DIR/bin/gdvr-report" "$JOB" "${REPORT_ARGS[@]}"; then
    REPORT=$(cd "$OUT/report" && pwd)/report.html
  else
    echo "demo: gdvr-report failed (the rendered frames in $OUT are complete)" >&2
    exit 1
  fi
fi
# END gdvr-report step.

# ---- Where everything is ----
OUT_ABS=$(cd "$OUT" && pwd)
VIDEO=$(ls "$OUT_ABS"/video.* 2>/dev/null | head -1 || true)
echo
echo "demo: done in $((END - START)) s; results in $OUT_ABS"
echo "  frames:   $(ls "$OUT_ABS"/frame_*.exr 2>/dev/null | wc -l) multi-layer EXR (frame_NNNN.exr)"
echo "  previews: $(ls "$OUT_ABS"/preview_*.png 2>/dev/null | wc -l) PNG (preview_NNNN.png, OCIO ACES 1.0 - SDR Video / sRGB)"
echo "  video:    ${VIDEO:-none}"
echo "  stats:    $OUT_ABS/stats.json"
[ -n "$REPORT" ] && echo "  report:   $REPORT"
echo "  server state (jobs, database, log): $(cd "$STATE" && pwd)"
# The Python client runs from the build tree, where the build generated its gRPC stubs.
if [ -d "$BUILD_DIR/python/gdvr_client/_proto" ]; then
  echo "  Python client: PYTHONPATH=$(cd "$BUILD_DIR/python" && pwd) python3 -m gdvr_client --help"
fi
