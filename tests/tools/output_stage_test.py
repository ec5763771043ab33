#!/usr/bin/env python3
"""One output stage (ctest output_stage): the same job written by gdvr-render,
by gdvr-farm (chunks rendered apart, then finalize --video) and by gdvr-server
(fetched with the gdvr CLI) leaves the same folder: the same file names, EXR
frames and PNG previews equal byte for byte, and stats.json frame entries that
differ only in their timings; the frames carry the feature buffers. All three
go through core/job/job_outputs, so a difference here means a caller bypassed
it.

The video is compared by its frame count only: the H.264
encoder's bitstream may depend on thread timing."""
import argparse, filecmp, json, os, shutil, signal, subprocess, sys, tempfile, time

TIMING = {"render_seconds", "reconstruct_seconds", "feature_seconds", "sampling_seconds", "stage1_seconds",
          "samples_per_second", "rays_per_second"}


def fail(msg):
    sys.exit("FAIL: " + msg)


def run(cmd, **kw):
    p = subprocess.run([str(c) for c in cmd], capture_output=True, text=True, **kw)
    if p.returncode != 0:
        fail(f"{' '.join(map(str, cmd))}: exit {p.returncode}\n{p.stderr[-2000:]}")
    return p


def frames_without_timing(folder):
    stats = json.load(open(os.path.join(folder, "stats.json")))
    frames = [{k: v for k, v in f.items() if k not in TIMING} for f in stats["frames"]]
    return stats, frames


def exr_channels(path):
    """The channel names of a single-part EXR, from its header's chlist
    attribute (no OpenEXR module on the test machine)."""
    data = open(path, "rb").read()
    at = 8  # magic number and version
    def cstring(i):
        end = data.index(b"\0", i)
        return data[i:end].decode(), end + 1
    while data[at] != 0:
        name, at = cstring(at)
        kind, at = cstring(at)
        size = int.from_bytes(data[at:at + 4], "little")
        at += 4
        if name == "channels" and kind == "chlist":
            names, i = [], at
            while data[i] != 0:
                channel, i = cstring(i)
                names.append(channel)
                i += 16  # pixel type, pLinear and reserved, x and y sampling
            return names
        at += size
    return []


# The feature buffers every frame carries (core/render/feature_buffers.h),
# named as compositors expect.
FEATURE_CHANNELS = {"albedo.R", "albedo.G", "albedo.B", "N.X", "N.Y", "N.Z", "Z"}


def video_frames(path):
    """Sample count of the MP4's video track, from its 'stsz' box (no ffprobe on
    the test machine; the service tests decode with libavformat)."""
    data = open(path, "rb").read()
    at = data.find(b"stsz")
    if not data[4:8] == b"ftyp" or at < 0:
        return -1
    # box type, then version+flags (4), sample_size (4), sample_count (4)
    return int.from_bytes(data[at + 12:at + 16], "big")


def start_server(server, tmp, assets):
    port_file = os.path.join(tmp, "port")
    log = open(os.path.join(tmp, "server.log"), "wb")
    proc = subprocess.Popen([server, "--listen=127.0.0.1:0", f"--port-file={port_file}", f"--asset-root={assets}",
                             f"--output-root={tmp}/server-out", "--threads=2"],
                            stdout=log, stderr=log)
    for _ in range(600):
        if os.path.exists(port_file) and open(port_file).read().strip():
            return proc, "127.0.0.1:" + open(port_file).read().strip()
        if proc.poll() is not None:
            fail("server exited at start; log:\n" + open(log.name).read()[-2000:])
        time.sleep(0.05)
    proc.kill()
    fail("server did not start")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--render", required=True)
    ap.add_argument("--farm", required=True)
    ap.add_argument("--server", required=True)
    ap.add_argument("--cli", required=True)
    ap.add_argument("--source", required=True)
    a = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="gdvr-output-stage-") as tmp:
        # The bundled animated job, shrunk: T-GPT, so frames are final only
        # once the window has moved past them (the path that differs most).
        job = json.load(open(os.path.join(a.source, "scenes/demo/demo_job.json")))
        job.update({"frames": "0-3", "width": 24, "height": 18, "spp": 2, "seed": 3,
                    "reconstruction": {"method": "l2", "window": 3}})
        assets = os.path.join(tmp, "assets")
        for d in ["demo", "cbox"]:  # the demo scene includes ../cbox fragments
            shutil.copytree(os.path.join(a.source, "scenes", d), os.path.join(assets, d))
        job["scene"] = "demo/" + job["scene"]  # the job file's folder is the server's asset root
        job_file = os.path.join(assets, "job.json")
        json.dump(job, open(job_file, "w"))

        folders = {}
        folders["gdvr-render"] = os.path.join(tmp, "render")
        run([a.render, job_file, "--out", folders["gdvr-render"], "--threads", "2"])

        buffers = os.path.join(tmp, "buffers")
        for chunk in ["0-1", "2-3"]:
            run([a.farm, "render", job_file, "--frames", chunk, "--buffers", buffers, "--threads", "1"])
        folders["gdvr-farm"] = os.path.join(tmp, "farm")
        run([a.farm, "finalize", job_file, "--buffers", buffers, "--out", folders["gdvr-farm"], "--video"])

        proc, addr = start_server(a.server, tmp, assets)
        try:
            folders["gdvr (CLI from gdvr-server)"] = os.path.join(tmp, "cli")
            p = run([a.cli, "--server", addr, "submit", job_file, "--watch", "--out",
                     folders["gdvr (CLI from gdvr-server)"]])
            job_id = p.stdout.strip().splitlines()[0]
            folders["gdvr-server"] = os.path.join(tmp, "server-out", job_id)
        finally:
            proc.send_signal(signal.SIGTERM)
            proc.wait(timeout=60)

        expected = ["frame_0000.exr", "frame_0001.exr", "frame_0002.exr", "frame_0003.exr",
                    "preview_0000.png", "preview_0001.png", "preview_0002.png", "preview_0003.png",
                    "stats.json", "video.mp4"]
        base_name = "gdvr-render"
        base = folders[base_name]
        base_stats, base_frames = frames_without_timing(base)
        for f in expected[:4]:
            channels = set(exr_channels(os.path.join(base, f)))
            if not FEATURE_CHANNELS <= channels or not {"R", "G", "B"} <= channels:
                fail(f"{base_name}: {f} has channels {sorted(channels)}, lacking "
                     f"{sorted(FEATURE_CHANNELS - channels)} or R,G,B")
        if len(base_frames) != 4:
            fail(f"{base_name}: stats.json lists {len(base_frames)} frames, expected 4")
        for name, folder in folders.items():
            files = sorted(f for f in os.listdir(folder) if not f.startswith("."))
            if files != expected:
                fail(f"{name}: files {files}, expected {expected}")
            for f in expected:
                if f.endswith((".exr", ".png")) and not filecmp.cmp(os.path.join(base, f), os.path.join(folder, f),
                                                                     shallow=False):
                    fail(f"{name}: {f} differs from {base_name}'s")
            n = video_frames(os.path.join(folder, "video.mp4"))
            if n != 4:
                fail(f"{name}: video.mp4 holds {n} frames, expected 4")
            stats, frames = frames_without_timing(folder)
            if frames != base_frames:
                fail(f"{name}: stats.json frames differ from {base_name}'s:\n{frames}\n{base_frames}")
            for key in ["frames_total", "frames_final"]:
                if stats[key] != base_stats[key]:
                    fail(f"{name}: stats.json {key} {stats[key]} != {base_stats[key]}")
            print(f"ok: {name}: {len(files)} files, pixels and stats equal to {base_name}'s")


if __name__ == "__main__":
    main()
