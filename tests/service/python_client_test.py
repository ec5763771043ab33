#!/usr/bin/env python3
"""The Python client (client/python) against a real gdvr-server; also drives
the C++ `gdvr` CLI for its exit codes. Plain script (no pytest on Debian by
default): exits non-zero on the first failure."""

import argparse
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time

import grpc
import numpy as np

from gdvr_client import Client, GdvrError

JOB = {"scene": "cbox/cbox-rgb.xml", "frames": "1-3", "width": 32, "height": 32, "spp": 2, "seed": 7}


def start_server(server_bin, tmp, extra_env=None):
    port_file = os.path.join(tmp, "port")
    if os.path.exists(port_file):
        os.remove(port_file)
    env = dict(os.environ, **(extra_env or {}))
    log = open(os.path.join(tmp, "server.log"), "ab")
    proc = subprocess.Popen([server_bin, "--listen=127.0.0.1:0", f"--port-file={port_file}",
                             f"--asset-root={tmp}/assets", f"--output-root={tmp}/out", "--threads=2"],
                            stdout=log, stderr=log, env=env)
    for _ in range(400):
        if os.path.exists(port_file):
            return proc, f"127.0.0.1:{open(port_file).read().strip()}"
        if proc.poll() is not None:
            raise RuntimeError("server exited; see " + log.name)
        time.sleep(0.05)
    raise RuntimeError("server did not start")


def check(cond, what):
    if not cond:
        raise AssertionError(what)
    print("ok:", what)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--server-bin", required=True)
    ap.add_argument("--cli-bin", required=True)
    ap.add_argument("--source-dir", required=True)
    a = ap.parse_args()
    tmp = tempfile.mkdtemp(prefix="gdvr-py-test-")
    shutil.copytree(os.path.join(a.source_dir, "scenes/cbox"), os.path.join(tmp, "assets/cbox"))
    proc, addr = start_server(a.server_bin, tmp, {"GDVR_TOKENS": "tok"})
    try:
        c = Client(addr, token="tok")
        job_id = c.submit(JOB, idempotency_key="py-1")
        check(c.submit(JOB, idempotency_key="py-1") == job_id, "idempotent submit returns the same job")
        frames = list(c.frames(job_id))
        check([f.frame for f in frames] == [1, 2, 3], "frames() yields 1,2,3 in order")
        for f in frames:
            check(f.rgb.shape == (32, 32, 3) and f.rgb.dtype == np.float32, f"frame {f.frame} is float32 32x32x3")
            check(np.isfinite(f.rgb).all() and f.rgb.mean() > 0, f"frame {f.frame} has finite, non-black pixels")
            disk = open(os.path.join(tmp, "out", job_id, f.file_name), "rb").read()
            check(disk == f.exr, f"frame {f.frame} EXR bytes equal the server's file")
        check(c.status(job_id).state == 3, "status: completed")
        check(any(j.id == job_id for j in c.list(["completed"])), "list filters by state")
        resumed = list(c.frames(job_id, from_frame=3))
        check([f.frame for f in resumed] == [3], "frames(from_frame=3) resumes at 3")
        paths = c.fetch(job_id, os.path.join(tmp, "fetched"))
        check(len(paths) == 3, "fetch saves 3 frames")
        paths = c.fetch(job_id, os.path.join(tmp, "fetched"), kinds=("previews", "video"))
        check(sorted(os.path.basename(p) for p in paths) ==
              ["preview_0001.png", "preview_0002.png", "preview_0003.png", "video.mp4"], "fetch previews and video")

        # Errors map to status codes with the field named.
        for job, code, word in [({"scene": "cbox/cbox-rgb.xml", "frames": "9-1"}, grpc.StatusCode.INVALID_ARGUMENT, "frames"),
                                ({"scene": "nope.xml"}, grpc.StatusCode.NOT_FOUND, "nope.xml"),
                                ({"scene": "cbox/cbox-rgb.xml", "bogus": 1}, grpc.StatusCode.INVALID_ARGUMENT, "bogus")]:
            try:
                c.submit(job)
                check(False, f"{job} rejected")
            except GdvrError as e:
                check(e.code == code and word in e.message, f"{code.name} naming '{word}': {e.message}")
        try:
            Client(addr, token="wrong").status(job_id)
            check(False, "wrong token rejected")
        except GdvrError as e:
            check(e.code == grpc.StatusCode.UNAUTHENTICATED, "wrong token: UNAUTHENTICATED")

        # Upload a bundle and render from it.
        scene = c.upload(os.path.join(tmp, "assets/cbox"), "cbox-rgb.xml")
        check(scene.startswith("uploads/") and scene.endswith("/cbox-rgb.xml"), f"upload returns {scene}")
        check(c.upload(os.path.join(tmp, "assets/cbox"), "cbox-rgb.xml") == scene, "upload is content-addressed")
        up_frames = list(c.frames(c.submit(dict(JOB, scene=scene, frames="1"))))
        check(np.array_equal(up_frames[0].rgb, frames[0].rgb), "uploaded scene renders the same pixels")

        # The C++ CLI: exit codes for success, auth, invalid job, unreachable.
        env = dict(os.environ, GDVR_SERVER=addr)
        cli = [a.cli_bin]
        out = os.path.join(tmp, "cli-frames")
        r = subprocess.run(cli + ["--token", "tok", "submit", "--scene", "cbox/cbox-rgb.xml", "--frames", "1-2",
                                  "--width", "32", "--height", "32", "--spp", "1", "--watch", "--out", out],
                           env=env, capture_output=True, text=True)
        check(r.returncode == 0 and sorted(os.listdir(out)) ==
              ["frame_0001.exr", "frame_0002.exr", "preview_0001.png", "preview_0002.png", "stats.json", "video.mp4"],
              f"gdvr submit --watch saves frames, previews, video (rc {r.returncode}) {r.stderr[-300:]}")
        r = subprocess.run(cli + ["--token", "tok", "watch", r.stdout.strip(), "--out", out], env=env,
                           capture_output=True, text=True)
        check(r.returncode == 0, "gdvr watch of a finished job resumes and exits 0")
        r = subprocess.run(cli + ["list"], env=env, capture_output=True, text=True)
        check(r.returncode == 4 and "authentication" in r.stderr, "gdvr without token: exit 4")
        r = subprocess.run(cli + ["--token", "tok", "submit", "--scene", "cbox/missing.xml"], env=env,
                           capture_output=True, text=True)
        check(r.returncode == 5 and "missing.xml" in r.stderr, "gdvr invalid job: exit 5 naming the scene")
        r = subprocess.run(cli + ["--server", "127.0.0.1:1", "list"], capture_output=True, text=True)
        check(r.returncode == 3 and "cannot reach" in r.stderr, "gdvr unreachable: exit 3")
    finally:
        proc.send_signal(signal.SIGTERM)
        rc = proc.wait(timeout=30)
        print("server exit", rc)
        if not os.environ.get("GDVR_KEEP_TEST_DIRS"):
            shutil.rmtree(tmp, ignore_errors=True)
    check(rc == 0, "server exits 0 on SIGTERM")


if __name__ == "__main__":
    main()
