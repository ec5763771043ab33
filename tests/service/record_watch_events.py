#!/usr/bin/env python3
"""Records the event stream a watcher of a T-GPT job receives, for
ProgressViewTest (tests/service/progress_view_test.cpp): each event with
its arrival time, EXR bytes left out. Run by hand against a fresh server; the
output is committed (tests/service/data/tgpt_watch_events.tsv).

  PYTHONPATH=build/python /usr/bin/python3 tests/service/record_watch_events.py \
      --server-bin build/bin/gdvr-server --source-dir . --out tests/service/data/tgpt_watch_events.tsv

The job is the demo's animation (scenes/demo), small: 24 frames, a window of 8,
so final frames trail rendered ones as in the demo (3/48 final at 42%)."""

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time

from google.protobuf import json_format

from gdvr_client._proto.gdvr.v1 import render_service_pb2 as pb, render_service_pb2_grpc as pb_grpc
import grpc

JOB = {
    "scene": "demo/cbox_demo.xml", "frames": "0-23", "fps": 24, "spp": 4, "seed": 1, "integrator": "tgpt",
    "params": {"res": "64"}, "reconstruction": {"method": "l2", "window": 8},
    "tracks": [{"target": "smallbox", "interpolation": "linear",
                "keys": [{"frame": 0, "translate": [0, 0, 0]}, {"frame": 23, "translate": [-70, 0, -60]}]}],
}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--server-bin", required=True)
    ap.add_argument("--source-dir", required=True)
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    tmp = tempfile.mkdtemp(prefix="gdvr-record-")
    shutil.copytree(os.path.join(a.source_dir, "scenes/cbox"), os.path.join(tmp, "assets/cbox"))
    shutil.copytree(os.path.join(a.source_dir, "scenes/demo"), os.path.join(tmp, "assets/demo"))
    port_file = os.path.join(tmp, "port")
    proc = subprocess.Popen([a.server_bin, "--listen=127.0.0.1:0", f"--port-file={port_file}",
                             f"--asset-root={tmp}/assets", f"--output-root={tmp}/out", "--threads=2"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        while not os.path.exists(port_file):
            time.sleep(0.05)
        stub = pb_grpc.RenderServiceStub(grpc.insecure_channel("127.0.0.1:" + open(port_file).read().strip()))
        import json
        job_id = stub.SubmitJob(pb.SubmitJobRequest(idempotency_key="rec", job_json=json.dumps(JOB))).job_id
        t0 = time.monotonic()
        with open(a.out, "w") as out:
            for ev in stub.WatchJob(pb.WatchJobRequest(job_id=job_id)):
                t = time.monotonic() - t0
                if ev.HasField("frame_final"):
                    ev.frame_final.data = b""  # the EXR bytes are not what the test is about
                text = json_format.MessageToJson(ev, preserving_proto_field_name=True, indent=None)
                out.write(f"{t:.4f}\t{text}\n")
    finally:
        proc.terminate()
        proc.wait()
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
