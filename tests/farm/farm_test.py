#!/usr/bin/env python3
"""Render-farm deployment tests (docs/farm.md), one ctest per subcommand:

  localhost  3 gdvr-farm workers render 3 chunks concurrently, finalize joins
             them: the final EXRs equal gdvr-render's single-process frames
             byte for byte (pt and gpt); reruns change nothing; errors name
             the frame and path and exit non-zero. tgpt's temporal window
             reads neighbouring chunks' buffers.
  tiles      tgpt's stage 2 by tiles: tile ranges finalized by different
             worker processes, then one finalize assembling them, give the
             frames of one worker and of gdvr-render byte for byte; a missing
             tile part is named (exit 3); integrators without a window solve
             are one tile whose task does nothing.
  kill       a worker killed with SIGKILL mid-frame leaves no visible partial
             file; the rerun renders only what is missing and the result is
             unchanged.
  k8s        deploy/k8s/*.yaml validate offline against the Kubernetes
             schemas (kubernetes-validate from PyPI, installed into a venv);
             the Indexed Job's completions match its job's chunk count.
  systemd    deploy/systemd/gdvr-server.service passes systemd-analyze verify
             with no warning about it.
  openjd, opencue, flamenco
             deploy/farm's templates, run by stand-ins for each manager
             (OpenJD's own reference runtime; pyoutline/RQD and the Flamenco
             job compiler emulated), give the single-process frames.

A check that cannot run fails: nothing here skips.
"""
import argparse
import filecmp
import json
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

FAILURES = []


def check(cond, what):
    print(("ok    " if cond else "FAIL  ") + what, flush=True)
    if not cond:
        FAILURES.append(what)
    return cond


def run(cmd, **kw):
    kw.setdefault("capture_output", True)
    kw.setdefault("text", True)
    return subprocess.run([str(c) for c in cmd], **kw)


def fresh(path):
    shutil.rmtree(path, ignore_errors=True)
    path.mkdir(parents=True)
    return path


def write_job(source, path, **fields):
    """The bundled demo job (animated box and camera), shrunk for a fast test."""
    job = json.loads((source / "scenes/demo/demo_job.json").read_text())
    job["scene"] = str(source / "scenes/demo/cbox_demo.xml")
    job.update(fields)
    path.write_text(json.dumps(job, indent=2))
    return path


def frame_files(folder, prefix):
    return sorted(p.name for p in folder.iterdir() if p.name.startswith(prefix))


def same_bytes(a, b):
    return a.exists() and b.exists() and filecmp.cmp(a, b, shallow=False)


def snapshot(folder):
    return {p.name: (p.stat().st_mtime_ns, p.read_bytes()) for p in folder.iterdir()}


# ---- localhost farm ----

def localhost(args):
    farm, render = args.farm, args.render
    for integrator in ("pt", "gpt", "tgpt"):
        work = fresh(args.work / integrator)
        extra = {"reconstruction": {"window": 4}} if integrator == "tgpt" else {}
        job = write_job(args.source, work / "job.json", frames="0-5", width=24, height=24, spp=2,
                        integrator=integrator, **extra)
        ref = run([render, job, "--out", work / "ref", "--threads", "1"])
        if not check(ref.returncode == 0, f"{integrator}: gdvr-render single-process run"):
            print(ref.stderr)
            continue

        buffers, out = work / "buffers", work / "out"
        status = run([farm, "status", job, "--buffers", buffers])
        check(status.returncode == 3 and "missing: 0-5" in status.stdout,
              f"{integrator}: status before rendering exits 3 and lists 0-5 ({status.stdout.strip()})")

        # Three workers at once on one folder, as on a farm with shared storage.
        workers = [subprocess.Popen([str(farm), "render", str(job), "--frames", chunk, "--buffers", str(buffers),
                                     "--threads", "1"], stderr=subprocess.PIPE, text=True)
                   for chunk in ("0-1", "2-3", "4-5")]
        results = [(w.wait(), w.stderr.read()) for w in workers]
        check(all(rc == 0 for rc, _ in results),
              f"{integrator}: 3 concurrent workers succeed " + str([rc for rc, _ in results]))
        for rc, err in results:
            if rc:
                print(err)
        check(frame_files(buffers, "buffers_") == [f"buffers_{f:04d}.{e}" for f in range(6) for e in ("exr", "json")],
              f"{integrator}: one buffers EXR + marker per frame, nothing else visible")
        check(not [p for p in buffers.iterdir() if ".tmp." in p.name],
              f"{integrator}: no temporaries left behind")
        check(run([farm, "status", job, "--buffers", buffers]).returncode == 0,
              f"{integrator}: status exits 0 once every chunk is done")

        if integrator == "tgpt":
            # The temporal window reaches past a chunk: finalizing 0-2 alone
            # reads frames 3.. too and must still match the whole-shot solve.
            part = run([farm, "finalize", job, "--frames", "0-2", "--buffers", buffers, "--out", out])
            check(part.returncode == 0, "tgpt: finalize of chunk 0-2 on its own")
        fin = run([farm, "finalize", job, "--buffers", buffers, "--out", out, "--video"])
        if not check(fin.returncode == 0, f"{integrator}: finalize"):
            print(fin.stderr)
            continue
        for f in range(6):
            name = f"frame_{f:04d}.exr"
            check(same_bytes(out / name, work / "ref" / name),
                  f"{integrator}: {name} from 3 chunks + finalize equals the single-process frame byte for byte")
            check((out / f"preview_{f:04d}.png").stat().st_size > 0, f"{integrator}: preview_{f:04d}.png written")
        video = out / "video.mp4"
        check(video.exists() and video.stat().st_size > 0, f"{integrator}: video.mp4 written")
        stats = json.loads((out / "stats.json").read_text())
        check(stats["state"] == "completed" and [f["frame"] for f in stats["frames"]] == list(range(6))
              and all(f["render_seconds"] > 0 and f["file"] == f"frame_{f['frame']:04d}.exr" for f in stats["frames"]),
              f"{integrator}: stats.json lists all 6 frames with their render times")

        # ---- idempotence: a rerun of any stage changes nothing ----
        before_buffers, before_out = snapshot(buffers), snapshot(out)
        again = run([farm, "render", job, "--frames", "2-3", "--buffers", buffers])
        check(again.returncode == 0 and again.stderr.count("already complete, skipped") == 2,
              f"{integrator}: rerunning a finished chunk skips its frames")
        check(snapshot(buffers) == before_buffers, f"{integrator}: rerun leaves the buffers untouched")
        again = run([farm, "finalize", job, "--buffers", buffers, "--out", out])
        check(again.returncode == 0 and "6 already final" in again.stderr,
              f"{integrator}: rerunning finalize skips final frames")
        check({k: v for k, v in snapshot(out).items()} == before_out, f"{integrator}: rerun leaves the output untouched")

        # A lost output frame (or a finalize killed midway) is redone from the buffers.
        (out / "frame_0003.exr").unlink()
        (out / "preview_0003.png").unlink()
        again = run([farm, "finalize", job, "--frames", "2-4", "--buffers", buffers, "--out", out])
        check(again.returncode == 0 and same_bytes(out / "frame_0003.exr", work / "ref/frame_0003.exr")
              and before_out["preview_0003.png"][1] == (out / "preview_0003.png").read_bytes(),
              f"{integrator}: a deleted frame is finalized again, identical")

    # ---- errors name the frame and the path; exit codes differ ----
    work = args.work / "pt"
    job = work / "job.json"
    missing = run([farm, "finalize", job, "--frames", "2-3", "--buffers", work / "nothing", "--out", work / "o2"])
    check(missing.returncode == 3 and "frame 2" in missing.stderr and str(work / "nothing/buffers_0002.exr")
          in missing.stderr, "finalize without buffers exits 3 naming frame and path")
    check(not (work / "o2/frame_0002.exr").exists(), "finalize without buffers writes no frame")
    other = write_job(args.source, work / "other.json", frames="0-5", width=24, height=24, spp=3)
    foreign = run([farm, "render", other, "--frames", "0", "--buffers", work / "buffers"])
    check(foreign.returncode == 1 and "different job" in foreign.stderr,
          "buffers of another job are refused, not mixed in")
    check(run([farm, "render", job, "--frames", "40-50", "--buffers", work / "b3"]).returncode == 2,
          "frames outside the job exit 2")
    chunks = run([farm, "chunks", job, "--chunk-size", "4"])
    check(chunks.returncode == 0 and chunks.stdout.split() == ["0-3", "4-5"], "chunks prints the chunk ranges")
    by_index = run([farm, "render", job, "--chunk-size", "4", "--chunk-index", "1", "--buffers", work / "b4"])
    check(by_index.returncode == 0 and frame_files(work / "b4", "buffers_") ==
          ["buffers_0004.exr", "buffers_0004.json", "buffers_0005.exr", "buffers_0005.json"],
          "--chunk-index 1 --chunk-size 4 renders frames 4-5")
    check(run([farm, "render", job, "--chunk-size", "4", "--chunk-index", "2", "--buffers", work / "b4"])
          .returncode == 2, "a chunk index past the end exits 2")


# ---- tgpt's finalize by tiles ----

def tiles(args):
    farm, render = args.farm, args.render
    work = fresh(args.work)
    # 48x40 with 16-pixel tiles: a 3x3 grid whose halos cross every border.
    job = write_job(args.source, work / "job.json", frames="0-5", width=48, height=40, spp=2,
                    reconstruction={"method": "l2", "window": 4, "tile_size": 16})
    ref = run([render, job, "--out", work / "ref", "--threads", "1"])
    check(ref.returncode == 0, "tiles: gdvr-render single-process reference")
    buffers, out, one = work / "buffers", work / "out", work / "one_worker"
    rendered = [run([farm, "render", job, "--frames", chunk, "--buffers", buffers, "--threads", "1"])
                for chunk in ("0-2", "3-5")]
    check(all(r.returncode == 0 for r in rendered), "tiles: render stage")
    listing = run([farm, "tiles", job, "--tiles-per-task=4"])  # --name=value, as the k8s manifests write flags
    check(listing.returncode == 0 and listing.stdout.split() == ["0-3", "4-7", "8"],
          "tiles: gdvr-farm tiles lists the 3x3 grid in tasks of 4 " + repr(listing.stdout.split()))
    # One worker process per tile range, all at once; none writes a frame.
    if not run_concurrently([[farm, "finalize", job, "--tiles", r, "--buffers", buffers, "--out", out]
                             for r in listing.stdout.split()], "tiles: tiled finalize"):
        return
    check(not list(out.glob("frame_*.exr")) and len(list((out / "tiles").glob("solved_*.exr"))) == 6 * 9,
          "tiles: tile tasks write one part per frame and tile, no frame")
    again = run([farm, "finalize", job, "--tiles", "0-3", "--buffers", buffers, "--out", out])
    check(again.returncode == 0 and "of 0 frame(s)" in again.stderr, "tiles: a rerun of a tile task skips its parts")
    # A missing part is named; the assemble writes nothing for that frame.
    part = out / "tiles/solved_0002_t0005.exr"
    saved = part.read_bytes()
    part.unlink()
    gap = run([farm, "finalize", job, "--frames", "2", "--buffers", buffers, "--out", out])
    check(gap.returncode == 3 and "tile(s) 5" in gap.stderr and not (out / "frame_0002.exr").exists(),
          "tiles: assembling with a tile part missing exits 3 naming the tile")
    part.write_bytes(saved)
    fin = run([farm, "finalize", job, "--buffers", buffers, "--out", out, "--video"])
    if not check(fin.returncode == 0 and fin.stderr.count("assembled from its tiles") == 6,
                 "tiles: the last finalize assembles every frame from its tiles"):
        print(fin.stderr)
    single = run([farm, "finalize", job, "--buffers", buffers, "--out", one])
    check(single.returncode == 0, "tiles: one-worker finalize")
    for f in range(6):
        name = f"frame_{f:04d}.exr"
        check(same_bytes(out / name, one / name) and same_bytes(out / name, work / "ref" / name),
              f"tiles: {name} assembled from tile tasks equals the one-worker finalize and gdvr-render byte for byte")
    check(not list((out / "tiles").glob("*")), "tiles: the parts are removed once their frame is written")
    check((out / "video.mp4").exists(), "tiles: video.mp4 written by the assembling finalize")
    # Integrators without a window solve have one tile, whose task does nothing.
    pt = write_job(args.source, work / "pt.json", frames="0-1", width=24, height=24, spp=1, integrator="pt")
    listing = run([farm, "tiles", pt])
    check(listing.returncode == 0 and listing.stdout.split() == ["0"], "tiles: a pt job is one tile")
    noop = run([farm, "finalize", pt, "--tiles", "0", "--buffers", work / "pt_buffers", "--out", work / "pt_out"])
    check(noop.returncode == 0 and "nothing to do" in noop.stderr and not (work / "pt_out/tiles").exists(),
          "tiles: a pt job's tile task does nothing")


# ---- a worker killed mid-frame ----

def kill(args):
    farm, render = args.farm, args.render
    work = fresh(args.work)
    # Frames large enough (about a second each on one thread) to kill one mid-render.
    job = write_job(args.source, work / "job.json", frames="0-2", width=160, height=120, spp=32)
    buffers = work / "buffers"
    proc = subprocess.Popen([str(farm), "render", str(job), "--buffers", str(buffers), "--threads", "1"],
                            stderr=subprocess.PIPE, text=True)
    deadline = time.time() + 120
    while not (buffers / "buffers_0000.json").exists() and proc.poll() is None and time.time() < deadline:
        time.sleep(0.01)
    time.sleep(0.3)  # well into frame 1
    alive = proc.poll() is None
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    if not check(alive and not (buffers / "buffers_0001.json").exists(),
                 "worker was killed with SIGKILL while rendering frame 1"):
        print(proc.stderr.read())
        return

    # Whatever is visible is complete: a buffers file is there only with its
    # marker (or, killed between the two renames, alone but whole).
    visible = frame_files(buffers, "buffers_")
    check(visible[:2] == ["buffers_0000.exr", "buffers_0000.json"] and "buffers_0002.exr" not in visible,
          f"after kill -9 only frame 0 is visible ({visible})")
    status = run([farm, "status", job, "--buffers", buffers])
    check(status.returncode == 3 and "missing: 1-2" in status.stdout, "status reports frames 1-2 missing")
    frame0 = snapshot(buffers)["buffers_0000.exr"]
    # A kill during a write leaves a temporary "<file>.tmp.<host>.<pid>"; the
    # timing above rarely hits one, so plant what it would leave: this host's
    # dead pid (swept by the rerun) and another host's (left alone: it may be
    # alive).
    dead = subprocess.Popen(["true"])
    dead.wait()
    host = socket.gethostname().replace(".", "_").replace("/", "_")
    ours = buffers / f"buffers_0001.exr.tmp.{host}.{dead.pid}"
    theirs = buffers / f"buffers_0001.exr.tmp.other-host.{dead.pid}"
    ours.write_bytes(b"half an EXR")
    theirs.write_bytes(b"half an EXR")

    rerun = run([farm, "render", job, "--buffers", buffers, "--threads", "1"])
    check(rerun.returncode == 0 and "frame 0: buffers already complete, skipped" in rerun.stderr
          and "2 of 3 frame(s)" in rerun.stderr, "the rerun renders only frames 1-2")
    check(snapshot(buffers)["buffers_0000.exr"] == frame0, "the rerun leaves frame 0 untouched")
    check(not ours.exists() and not [p for p in buffers.iterdir() if ".tmp." in p.name and p != theirs],
          "the rerun removed the killed worker's temporaries")
    check(theirs.exists(), "the rerun left another host's staging file alone")
    theirs.unlink()

    ref = run([render, job, "--out", work / "ref", "--threads", "1"])
    fin = run([farm, "finalize", job, "--buffers", buffers, "--out", work / "out"])
    if check(ref.returncode == 0 and fin.returncode == 0, "reference render and finalize"):
        for f in range(3):
            name = f"frame_{f:04d}.exr"
            check(same_bytes(work / "out" / name, work / "ref" / name),
                  f"{name} after kill -9 and rerun equals the single-process frame")
    else:
        print(ref.stderr, fin.stderr)


# ---- Kubernetes manifests ----

KUBERNETES_VALIDATE = "kubernetes-validate==1.37.0"
# backoffLimitPerIndex (the Indexed Job) is beta and on by default from 1.29.
KUBERNETES_VERSIONS = ("1.29.0", "1.37.0")


def k8s(args):
    venv = args.work / "venv"
    python = venv / "bin/python"
    if not python.exists():
        made = run([sys.executable, "-m", "venv", venv])
        if not check(made.returncode == 0, "python3 -m venv (package python3-venv)"):
            print(made.stderr)
            return
    have = run([python, "-c", "import kubernetes_validate"]).returncode == 0
    if not have:
        pip = run([python, "-m", "pip", "install", "--quiet", "--disable-pip-version-check", KUBERNETES_VALIDATE])
        if not check(pip.returncode == 0, f"pip install {KUBERNETES_VALIDATE}"):
            print(pip.stdout, pip.stderr)
            return
    validate = [venv / "bin/kubernetes-validate", "--strict", "--quiet"]
    manifests = sorted((args.source / "deploy/k8s").glob("*.yaml"))
    check(len(manifests) >= 2, f"manifests found: {[m.name for m in manifests]}")
    for version in KUBERNETES_VERSIONS:
        for m in manifests:
            r = run(validate + ["-k", version, m])
            check(r.returncode == 0, f"{m.name} validates against Kubernetes {version} (strict)")
            if r.returncode:
                print(r.stdout, r.stderr)

    # The validator must be able to fail: a misspelt field is rejected.
    bad = args.work / "bad.yaml"
    bad.write_text((args.source / "deploy/k8s/farm-job.yaml").read_text()
                   .replace("backoffLimitPerIndex:", "backoffLimitPerIndexx:"))
    check(run(validate + ["-k", KUBERNETES_VERSIONS[0], bad]).returncode != 0,
          "a manifest with a misspelt field fails validation")

    # The Indexed Job's completions must cover its job's chunks exactly.
    check_completions = r"""
import json, sys, yaml
docs = [d for d in yaml.safe_load_all(open(sys.argv[1])) if d]
cm = next(d for d in docs if d["kind"] == "ConfigMap")
job = next(d for d in docs if d["kind"] == "Job" and d["metadata"]["name"] == "gdvr-render-demo")
tiles = next(d for d in docs if d["kind"] == "Job" and d["metadata"]["name"] == "gdvr-finalize-tiles-demo")
cmd = job["spec"]["template"]["spec"]["containers"][0]["command"]
size = next(a.split("=", 1)[1] for a in cmd if a.startswith("--chunk-size="))
spec = json.loads(cm["data"]["job.json"])
spec["scene"] = spec["scene"].replace("/srv/gdvr/assets/", sys.argv[2] + "/scenes/")
json.dump(spec, open(sys.argv[3], "w"))
assert tiles["spec"]["completionMode"] == "Indexed"
assert "--tiles=$(JOB_COMPLETION_INDEX)" in tiles["spec"]["template"]["spec"]["containers"][0]["command"]
print(job["spec"]["completions"], size, tiles["spec"]["completions"])
"""
    local_job = args.work / "configmap_job.json"
    r = run([python, "-c", check_completions, args.source / "deploy/k8s/farm-job.yaml", args.source, local_job])
    if check(r.returncode == 0, "farm-job.yaml: read completions, chunk size and job file"):
        completions, size, tile_completions = r.stdout.split()
        chunks = run([args.farm, "chunks", local_job, "--chunk-size", size])
        check(chunks.returncode == 0 and len(chunks.stdout.split()) == int(completions),
              f"Indexed Job completions ({completions}) = gdvr-farm chunks ({len(chunks.stdout.split())})")
        tiles = run([args.farm, "tiles", local_job])
        check(tiles.returncode == 0 and len(tiles.stdout.split()) == int(tile_completions),
              f"tiles Job completions ({tile_completions}) = gdvr-farm tiles ({len(tiles.stdout.split())})")
    else:
        print(r.stderr)


# ---- systemd unit ----

def systemd(args):
    tool = shutil.which("systemd-analyze")
    if not check(tool is not None, "systemd-analyze is installed"):
        return
    unit_dir = fresh(args.work)
    unit = (args.source / "deploy/systemd/gdvr-server.service").read_text()
    conf = (args.source / "deploy/systemd/gdvr-server.conf").read_text()
    # verify insists that ExecStart= exists: point it at the built server (or
    # any executable when the service is not built) without touching the rest.
    server = args.server if args.server and Path(args.server).exists() else shutil.which("true")
    path = unit_dir / "gdvr-server.service"
    path.write_text(unit.replace("/usr/local/bin/gdvr-server", str(server)))
    r = run([tool, "verify", path])
    # verify exits 0 on unknown keys or bad values, only warning: any line
    # about our unit is a failure.
    complaints = [l for l in (r.stdout + r.stderr).splitlines() if "gdvr-server" in l]
    check(r.returncode == 0 and not complaints, "systemd-analyze verify gdvr-server.service")
    for l in complaints:
        print("      " + l)

    # The stop timeout must outlast the server's drain (grace + render stop).
    grace = int(re.search(r"^GDVR_SHUTDOWN_GRACE_S=(\d+)", conf, re.M).group(1))
    stop = int(re.search(r"^TimeoutStopSec=(\d+)", unit, re.M).group(1))
    check(stop >= grace + 5, f"TimeoutStopSec={stop} outlasts --shutdown-grace-s={grace}")
    # Every ${VAR} ExecStart uses is set in the configuration file.
    used = set(re.findall(r"\$\{?(GDVR_[A-Z_]+)", unit))
    defined = set(re.findall(r"^(GDVR_[A-Z_]+)=", conf, re.M))
    check(used <= defined, f"gdvr-server.conf defines every variable the unit uses (missing: {used - defined})")


# ---- farm-manager templates, run by stand-ins for the managers ----

def template_job(args, work):
    """A 6-frame job, its single-process reference frames, and the folders.
    16-pixel tiles make its window solve 2x2 tiles (TEMPLATE_TILES), which
    the templates' tile steps split between tasks."""
    work = fresh(work)
    job = write_job(args.source, work / "job.json", frames="0-5", width=24, height=24, spp=2,
                    reconstruction={"method": "l2", "window": 20, "tile_size": 16})
    ref = run([args.render, job, "--out", work / "ref", "--threads", "1"])
    check(ref.returncode == 0, "gdvr-render single-process reference")
    return work, job


TEMPLATE_TILES = "0-3"  # gdvr-farm tiles of template_job's job


def compare_to_reference(work, out, who):
    for f in range(6):
        name = f"frame_{f:04d}.exr"
        check(same_bytes(out / name, work / "ref" / name), f"{who}: {name} equals the single-process frame")
    check((out / "video.mp4").exists(), f"{who}: video.mp4 written")
    check(not list((out / "tiles").glob("*")), f"{who}: frames assembled from their tiles (no part left)")


def run_concurrently(commands, who):
    procs = [subprocess.Popen([str(c) for c in cmd], stderr=subprocess.PIPE, text=True) for cmd in commands]
    results = [(p.wait(), p.stderr.read()) for p in procs]
    for rc, err in results:
        if rc:
            print(err)
    return check(all(rc == 0 for rc, _ in results), f"{who}: {len(commands)} task(s) succeed")


def openjd(args):
    """deploy/farm/openjd: `openjd check`, then the OpenJD reference runtime
    (openjd run) executes every Render chunk and Finalize locally."""
    work, job = template_job(args, args.work)
    venv = args.work.parent / (args.work.name + "-venv")
    openjd_cli = venv / "bin/openjd"
    if not openjd_cli.exists():
        made = run([sys.executable, "-m", "venv", venv])
        pip = made.returncode == 0 and run([venv / "bin/python", "-m", "pip", "install", "--quiet",
                                            "--disable-pip-version-check", "openjd-cli==0.8.0"])
        if not check(made.returncode == 0 and pip.returncode == 0, "pip install openjd-cli into a venv"):
            print(made.stderr, pip and pip.stderr)
            return
    template = args.source / "deploy/farm/openjd/gdvr-job.template.yaml"
    r = run([openjd_cli, "check", template])
    check(r.returncode == 0, "openjd check gdvr-job.template.yaml")
    r = run([openjd_cli, "run", template, "--step", "Finalize", "--run-dependencies",
             "-p", f"JobFile={job}", "-p", "Frames=0-5", "-p", "ChunkSize=2", "-p", f"FarmDir={work / 'farm'}",
             "-p", f"GdvrFarm={args.farm}", "-p", "Threads=1", "-p", f"Tiles={TEMPLATE_TILES}", "-p", "TilesPerTask=2"])
    chunks = re.findall(r"Frame\(CHUNK\[INT\]\) = (\S+)", r.stdout + r.stderr)
    check(r.returncode == 0 and chunks == ["0-1", "2-3", "4-5"], f"openjd run: Render chunks {chunks} + Finalize")
    tile_chunks = re.findall(r"Tile\(CHUNK\[INT\]\) = (\S+)", r.stdout + r.stderr)
    check(tile_chunks == ["0-1", "2-3"], f"openjd run: FinalizeTiles chunks {tile_chunks}")
    if r.returncode:
        print(r.stdout[-3000:], r.stderr[-3000:])
    compare_to_reference(work, work / "farm/output", "OpenJD")


OUTLINE_STUB = {
    "outline/__init__.py": """
import json, os
class Outline:
    def __init__(self, name, **kw):
        self.name, self.kw, self.layers = name, kw, []
    def add_layer(self, layer):
        self.layers.append(layer)
""",
    "outline/cuerun.py": """
import json, os
def launch(ol, use_pycuerun=True, **kw):
    json.dump({"use_pycuerun": use_pycuerun, "layers": [l.spec() for l in ol.layers]},
              open(os.environ["GDVR_OUTLINE_DUMP"], "w"))
""",
    "outline/modules/__init__.py": "",
    "outline/modules/shell.py": """
class _Layer:
    def __init__(self, name, **args):
        self.name, self.args, self.depends = name, args, []
    def depend_all(self, other):
        self.depends.append(other.name)
    def spec(self):
        return {"name": self.name, "kind": type(self).__name__, "args": self.args, "depends": self.depends}
class Shell(_Layer): pass
class ShellCommand(_Layer): pass
""",
}


def opencue(args):
    """deploy/farm/opencue: the submit script runs against a stand-in for
    pyoutline that records the layers; the test then does what Cuebot and RQD
    do: chunk the render layer's range, substitute #FRAME_START#/#FRAME_END#,
    run the chunks at once, then the dependent finalize layer."""
    work, job = template_job(args, args.work)
    stub = work / "stub"
    for rel, text in OUTLINE_STUB.items():
        (stub / rel).parent.mkdir(parents=True, exist_ok=True)
        (stub / rel).write_text(text)
    dump = work / "outline.json"
    env = dict(os.environ, PYTHONPATH=str(stub), GDVR_OUTLINE_DUMP=str(dump))
    r = run([sys.executable, args.source / "deploy/farm/opencue/gdvr_submit.py", job, "--frames", "0-5",
             "--chunk", "2", "--farm-dir", work / "farm", "--show", "test", "--shot", "farm", "--gdvr-farm",
             args.farm, "--threads", "1", "--tiles", TEMPLATE_TILES, "--tiles-per-task", "2"], env=env)
    if not check(r.returncode == 0 and dump.exists(), "gdvr_submit.py builds the outline"):
        print(r.stderr)
        return
    spec = json.loads(dump.read_text())
    layers = {l["name"]: l for l in spec["layers"]}
    check(spec["use_pycuerun"] is False, "launched without pycuerun (RQD substitutes the frame tokens)")
    check(set(layers) == {"render", "finalize_tiles", "finalize"} and layers["finalize_tiles"]["depends"] == ["render"]
          and layers["finalize"]["depends"] == ["finalize_tiles"],
          "layers: render, finalize_tiles depending on all of render, finalize depending on all tiles")
    render, tiles = layers["render"]["args"], layers["finalize_tiles"]["args"]
    check(render["range"] == "0-5" and render["chunk"] == 2, "render layer: range 0-5, chunk 2")
    check(tiles["range"] == TEMPLATE_TILES and tiles["chunk"] == 2, "finalize_tiles layer: the tiles, chunk 2")

    def chunked(layer, indices):  # what Cuebot and RQD make of a layer's range
        return [[str(a).replace("#FRAME_START#", str(indices[i])).replace(
            "#FRAME_END#", str(indices[min(len(indices), i + layer["chunk"]) - 1])) for a in layer["command"]]
            for i in range(0, len(indices), layer["chunk"])]
    if run_concurrently(chunked(render, list(range(0, 6))), "OpenCue render chunks") and \
            run_concurrently(chunked(tiles, list(range(0, 4))), "OpenCue finalize_tiles chunks"):
        run_concurrently([layers["finalize"]["args"]["command"]], "OpenCue finalize")
    compare_to_reference(work, work / "farm/output", "OpenCue")


FLAMENCO_HARNESS = r"""
// Stand-in for the Flamenco Manager's job compiler: the globals a job type
// script sees (author, frameChunker), then compileJob on one job.
const fs = require("fs");
const [script, settingsJson] = process.argv.slice(2);
function parseFrames(text) {
  const out = [];
  for (const part of text.split(",")) {
    const [a, b] = part.split("-").map(Number);
    for (let f = a; f <= (b === undefined ? a : b); f++) out.push(f);
  }
  return out;
}
function formatFrames(frames) {
  const runs = [];
  for (let i = 0; i < frames.length;) {
    let j = i;
    while (j + 1 < frames.length && frames[j + 1] === frames[j] + 1) j++;
    runs.push(j > i ? `${frames[i]}-${frames[j]}` : `${frames[i]}`);
    i = j + 1;
  }
  return runs.join(",");
}
globalThis.frameChunker = (text, size) => {
  const frames = parseFrames(text), chunks = [];
  for (let i = 0; i < frames.length; i += size) chunks.push(formatFrames(frames.slice(i, i + size)));
  return chunks;
};
globalThis.author = {
  Task: (name, type) => ({ name, type, commands: [], deps: [],
    addCommand(c) { this.commands.push(c); }, addDependency(t) { this.deps.push(t.name); } }),
  Command: (name, params) => ({ name, params }),
};
const tasks = [];
const fn = new Function(fs.readFileSync(script, "utf8") + "\nreturn [JOB_TYPE, compileJob];");
const [jobType, compileJob] = fn();
const settings = JSON.parse(settingsJson);
for (const s of jobType.settings) if (!(s.key in settings) && "default" in s) settings[s.key] = s.default;
compileJob({ settings, addTask: (t) => tasks.push(t) });
console.log(JSON.stringify(tasks.map(t => ({ name: t.name, type: t.type, commands: t.commands, deps: t.deps }))));
"""


def flamenco(args):
    """deploy/farm/flamenco/gdvr.js compiled by a stand-in for the Flamenco
    Manager (node with author/frameChunker), its tasks then run in
    dependency order the way Workers would."""
    work, job = template_job(args, args.work)
    node = shutil.which("node") or shutil.which("nodejs")
    if not check(node is not None, "node is installed"):
        return
    harness = work / "harness.js"
    harness.write_text(FLAMENCO_HARNESS)
    settings = {"job_file": str(job), "frames": "0-5", "chunk_size": 2, "farm_dir": str(work / "farm"),
                "gdvr_farm": str(args.farm), "threads": 1, "tiles": TEMPLATE_TILES, "tiles_per_task": 2}
    r = run([node, harness, args.source / "deploy/farm/flamenco/gdvr.js", json.dumps(settings)])
    if not check(r.returncode == 0, "gdvr.js compiles a job"):
        print(r.stderr)
        return
    tasks = json.loads(r.stdout)
    names = [t["name"] for t in tasks]
    check(names == ["render-0-1", "render-2-3", "render-4-5", "finalize-tiles-0-1", "finalize-tiles-2-3", "finalize"],
          f"tasks {names}")
    check(all(t["deps"] == names[:3] for t in tasks[3:5]), "each finalize-tiles task depends on every render task")
    check(tasks[-1]["deps"] == names[3:5], "finalize depends on every finalize-tiles task")
    check(all(c["name"] == "exec" for t in tasks for c in t["commands"]), "every command is an exec command")
    exe = lambda c: [c["params"]["exe"]] + c["params"]["args"]
    if run_concurrently([exe(c) for t in tasks[:3] for c in t["commands"]], "Flamenco render tasks") and \
            run_concurrently([exe(c) for t in tasks[3:5] for c in t["commands"]], "Flamenco finalize-tiles tasks"):
        run_concurrently([exe(c) for c in tasks[-1]["commands"]], "Flamenco finalize")
    compare_to_reference(work, work / "farm/output", "Flamenco")


def main():
    p = argparse.ArgumentParser()
    p.add_argument("test", choices=["localhost", "tiles", "kill", "k8s", "systemd", "openjd", "opencue", "flamenco"])
    p.add_argument("--source", type=Path, required=True)
    p.add_argument("--work", type=Path, required=True)
    p.add_argument("--farm", type=Path)
    p.add_argument("--render", type=Path)
    p.add_argument("--server")
    args = p.parse_args()
    args.work.mkdir(parents=True, exist_ok=True)
    {"localhost": localhost, "tiles": tiles, "kill": kill, "k8s": k8s, "systemd": systemd, "openjd": openjd, "opencue": opencue,
     "flamenco": flamenco}[args.test](args)
    if FAILURES:
        print(f"{len(FAILURES)} check(s) failed", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
