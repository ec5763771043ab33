#!/usr/bin/env python3
"""Render-farm deployment tests (docs/farm.md), one ctest per subcommand:

  localhost  3 gdvr-farm workers render 3 chunks concurrently, finalize joins
             them: the final EXRs equal gdvr-render's single-process frames
             byte for byte (pt and gpt); reruns change nothing; errors name
             the frame and path and exit non-zero.
  kill       a worker killed with SIGKILL mid-frame leaves no visible partial
             file; the rerun renders only what is missing and the result is
             unchanged.
  k8s        deploy/k8s/*.yaml validate offline against the Kubernetes
             schemas (kubernetes-validate from PyPI, installed into a venv);
             the Indexed Job's completions match its job's chunk count.
  systemd    deploy/systemd/gdvr-server.service passes systemd-analyze verify
             with no warning about it.

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
    for integrator in ("pt", "gpt"):
        work = fresh(args.work / integrator)
        job = write_job(args.source, work / "job.json", frames="0-5", width=24, height=24, spp=2,
                        integrator=integrator)
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
        check(not [p for p in buffers.iterdir() if p.name.startswith(".")],
              f"{integrator}: no staging files left behind")
        check(run([farm, "status", job, "--buffers", buffers]).returncode == 0,
              f"{integrator}: status exits 0 once every chunk is done")

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
    # A kill during a write leaves a hidden staging file; the timing above
    # rarely hits one, so plant what it would leave: this host's dead pid
    # (swept by the rerun) and another host's (left alone: it may be alive).
    dead = subprocess.Popen(["true"])
    dead.wait()
    host = socket.gethostname().replace(".", "_").replace("/", "_")
    ours = buffers / f".buffers_0001.exr.{host}.{dead.pid}.staging.tmp.{dead.pid}"
    theirs = buffers / f".buffers_0001.exr.other-host.{dead.pid}.staging"
    ours.write_bytes(b"half an EXR")
    theirs.write_bytes(b"half an EXR")

    rerun = run([farm, "render", job, "--buffers", buffers, "--threads", "1"])
    check(rerun.returncode == 0 and "frame 0: buffers already complete, skipped" in rerun.stderr
          and "2 of 3 frame(s)" in rerun.stderr, "the rerun renders only frames 1-2")
    check(snapshot(buffers)["buffers_0000.exr"] == frame0, "the rerun leaves frame 0 untouched")
    check(not ours.exists() and not [p for p in buffers.iterdir() if p.name.startswith(".") and p != theirs],
          "the rerun removed the killed worker's staging files")
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
job = next(d for d in docs if d["kind"] == "Job" and d["spec"].get("completionMode") == "Indexed")
cmd = job["spec"]["template"]["spec"]["containers"][0]["command"]
size = next(a.split("=", 1)[1] for a in cmd if a.startswith("--chunk-size="))
spec = json.loads(cm["data"]["job.json"])
spec["scene"] = spec["scene"].replace("/srv/gdvr/assets/", sys.argv[2] + "/scenes/")
json.dump(spec, open(sys.argv[3], "w"))
print(job["spec"]["completions"], size)
"""
    local_job = args.work / "configmap_job.json"
    r = run([python, "-c", check_completions, args.source / "deploy/k8s/farm-job.yaml", args.source, local_job])
    if check(r.returncode == 0, "farm-job.yaml: read completions, chunk size and job file"):
        completions, size = r.stdout.split()
        chunks = run([args.farm, "chunks", local_job, "--chunk-size", size])
        check(chunks.returncode == 0 and len(chunks.stdout.split()) == int(completions),
              f"Indexed Job completions ({completions}) = gdvr-farm chunks ({len(chunks.stdout.split())})")
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


def main():
    p = argparse.ArgumentParser()
    p.add_argument("test", choices=["localhost", "kill", "k8s", "systemd"])
    p.add_argument("--source", type=Path, required=True)
    p.add_argument("--work", type=Path, required=True)
    p.add_argument("--farm", type=Path)
    p.add_argument("--render", type=Path)
    p.add_argument("--server")
    args = p.parse_args()
    args.work.mkdir(parents=True, exist_ok=True)
    {"localhost": localhost, "kill": kill, "k8s": k8s, "systemd": systemd}[args.test](args)
    if FAILURES:
        print(f"{len(FAILURES)} check(s) failed", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
