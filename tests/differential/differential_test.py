#!/usr/bin/env python3
"""Differential test: gdvr against Mitsuba 3 on generated scenes.

For each seed, scene_generator.generate() writes a random scene; gdvr-render
and Mitsuba 3 (scalar_rgb) each render it `--runs` times at `--spp` with
independent seeds. The image is cut into blocks; for each block (and for the
whole image) the two renderers' means are compared against the noise measured
from the runs themselves:

    z = (mean_gdvr - mean_mitsuba) / sqrt(se_gdvr^2 + se_mitsuba^2)

with se the standard error of the run means. A scene fails where some |z|
exceeds --z (default 6: with 17 comparisons a scene and 15 degrees of
freedom, about one false alarm in 2,500 scenes) and the difference is also
above --floor of the block mean (default 1e-3: the float precision to which
the two renderers can agree at all, see docs/correctness.md). Noise is also
compared: each renderer's per-pixel variance over its runs, relative to the
squared mean (relMSE's form) and averaged over the image without its noisiest
1 % of pixels; gdvr fails where its figure exceeds Mitsuba's by more than
--variance-ratio.

With --integrators N, every N-th scene also goes through gdvr's gradient-domain
integrators (G-PT with each spatial shift and L2 reconstruction, T-GPT on a
static three-frame shot) and their block means are compared with gdvr PT's
the same way: every integrator must converge to the same image.

Mitsuba is imported from the running interpreter; with --venv DIR, an
interpreter without it makes DIR a venv, installs Mitsuba 3 from PyPI there
(once) and runs this script under it (tests/CMakeLists.txt does so under the
build folder). No Mitsuba and no PyPI is a failure, not a skip. Prints one line per scene and the
worst cases with their seeds; writes a JSON report with --report. Exit code 1
if any scene failed.

  python3 tests/differential/differential_test.py --render build/bin/gdvr-render --seeds 0-499 \\
      --integrators 5 --venv build/mitsuba-venv --report differential.json
  python3 tests/differential/differential_test.py --render build/bin/gdvr-render --seeds 17 --keep /tmp/s17
  python3 tests/differential/differential_test.py --render build/bin/gdvr-render --scene my/scene.xml --runs 8
"""
import argparse
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time

try:  # numpy may come only with the venv (main() re-runs this script there)
    import numpy as np
except ImportError:
    np = None

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))


def parse_seeds(text):
    seeds = []
    for part in text.split(","):
        if "-" in part:
            a, b = part.split("-")
            seeds += range(int(a), int(b) + 1)
        else:
            seeds.append(int(part))
    return seeds


def read_exr(path):
    import mitsuba as mi
    return np.array(mi.Bitmap(path), dtype=np.float64)[..., :3]


def render_gdvr(render, xml, out, spp, seed, extra=()):
    cmd = [render, xml, "--out", out, "--spp", str(spp), "--seed", str(seed), "--threads", str(os.cpu_count() or 1)]
    cmd += list(extra)
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        raise RuntimeError("gdvr-render failed (%d): %s" % (r.returncode, r.stderr.strip()[-2000:]))
    frames = sorted(f for f in os.listdir(out) if f.startswith("frame_") and f.endswith(".exr"))
    return [read_exr(os.path.join(out, f)) for f in frames]


def block_means(img, blocks):
    """Means over a blocks x blocks grid and over the whole image (last)."""
    h, w = img.shape[:2]
    lum = img.mean(axis=2)
    bh, bw = h // blocks, w // blocks
    cut = lum[: bh * blocks, : bw * blocks].reshape(blocks, bh, blocks, bw).mean(axis=(1, 3)).ravel()
    return np.append(cut, lum.mean())


def compare_means(a_runs, b_runs, blocks, floor):
    """Worst |z| over blocks (and the image) between two sets of runs, among
    the blocks whose difference is above `floor` of their mean."""
    a = np.array([block_means(x, blocks) for x in a_runs])
    b = np.array([block_means(x, blocks) for x in b_runs])
    ma, mb = a.mean(0), b.mean(0)
    se = np.sqrt(a.var(0, ddof=1) / len(a) + b.var(0, ddof=1) / len(b))
    diff = ma - mb
    scale = np.maximum(np.abs(ma), np.abs(mb))
    with np.errstate(divide="ignore", invalid="ignore"):
        z = np.where(se > 0, diff / se, np.where(diff == 0, 0.0, np.inf))
        rel = np.where(scale > 0, diff / scale, 0.0)
    z = np.where(np.abs(rel) > floor, z, 0.0)
    i = int(np.argmax(np.abs(z)))
    return {"z": float(z[i]), "rel": float(rel[i]), "block": i, "image_ratio": float(ma[-1] / mb[-1]) if mb[-1] else 1.0}


def variance_ratio(g_runs, m_runs, trim=0.01):
    """gdvr's noise over Mitsuba's: per pixel, each renderer's variance over
    its runs relative to the squared mean of all runs (relMSE's form), averaged
    over the image without its noisiest `trim` of pixels (a single firefly in
    16 runs otherwise decides the ratio), gdvr's over Mitsuba's. The same
    pixels are left out of both (the noisiest by the two renderers' noise
    together): trimmed apart, each loses its own worst pixels, which in an
    image whose noise sits in a few dozen pixels (lights seen at max_depth 1)
    compares different pixels."""
    g = np.array([x.mean(axis=2) for x in g_runs])
    m = np.array([x.mean(axis=2) for x in m_runs])
    denom = 0.5 * (g.mean(0) + m.mean(0)) ** 2 + 1e-2
    vg, vm = (g.var(0, ddof=1) / denom).ravel(), (m.var(0, ddof=1) / denom).ravel()
    keep = np.argsort(vg + vm)[: max(1, int(len(vg) * (1 - trim)))]
    rg, rm = float(vg[keep].mean()), float(vm[keep].mean())
    return (rg / rm if rm > 0 else (1.0 if rg == 0 else float("inf"))), rg, rm


MITSUBA_PACKAGES = ["mitsuba==3.9.1", "numpy"]


def reexec_in_venv(venv):
    """Runs this script under `venv`'s python, making the venv first."""
    python = os.path.join(venv, "bin", "python")
    if not os.path.exists(python):
        r = subprocess.run([sys.executable, "-m", "venv", venv])
        if r.returncode != 0:
            sys.exit("cannot make a venv at %s (package python3-venv)" % venv)
    check = subprocess.run([python, "-c", "import mitsuba, numpy"], capture_output=True)
    if check.returncode != 0:
        r = subprocess.run([python, "-m", "pip", "install", "--quiet", *MITSUBA_PACKAGES])
        if r.returncode != 0:
            sys.exit("pip install %s into %s failed (no PyPI?)" % (" ".join(MITSUBA_PACKAGES), venv))
    argv = [python, os.path.abspath(__file__)]
    skip = False
    for a in sys.argv[1:]:  # drop --venv DIR: the child must not loop
        if skip:
            skip = False
        elif a == "--venv":
            skip = True
        elif not a.startswith("--venv="):
            argv.append(a)
    os.execv(python, argv)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--venv", help="where to make a venv with Mitsuba 3 if this interpreter lacks it")
    ap.add_argument("--render", required=True, help="the gdvr-render executable")
    ap.add_argument("--seeds", default="0-9")
    ap.add_argument("--scene", action="append", default=[],
                    help="compare this scene file instead of generated ones (repeatable; its own folder, "
                         "its <default> values; use the same pixel filter in both renderers: gdvr's is box)")
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--runs", type=int, default=16)
    ap.add_argument("--size", type=int, default=48)
    ap.add_argument("--blocks", type=int, default=4)
    ap.add_argument("--z", type=float, default=6.0)
    ap.add_argument("--floor", type=float, default=1e-3)
    ap.add_argument("--variance-ratio", type=float, default=1.5)
    ap.add_argument("--integrators", type=int, default=0, metavar="N",
                    help="every N-th scene (by seed) also goes through G-PT (every shift) and T-GPT against PT")
    ap.add_argument("--report", help="write a JSON report here")
    ap.add_argument("--keep", help="keep the generated scenes under this folder")
    ap.add_argument("--time-limit", type=float, default=0, help="stop starting new scenes after this many seconds")
    args = ap.parse_args()

    try:
        import mitsuba as mi
        if np is None:
            raise ImportError("numpy")
    except ImportError:
        if not args.venv:
            sys.exit("Mitsuba 3 and numpy are not importable here; pass --venv DIR to install them from PyPI")
        reexec_in_venv(args.venv)
    import scene_generator  # needs numpy and Mitsuba, so only after the venv check
    mi.set_variant("scalar_rgb")
    mi.set_log_level(mi.LogLevel.Error)

    work = args.keep or tempfile.mkdtemp(prefix="gdvr-differential-")
    results, failures = [], []
    start = time.time()
    cases = list(enumerate(args.scene)) if args.scene else [(seed, None) for seed in parse_seeds(args.seeds)]
    for seed, given in cases:
        if args.time_limit and time.time() - start > args.time_limit:
            print("time limit reached; stopping before seed %d" % seed)
            break
        folder = os.path.join(work, "seed%05d" % seed)
        shutil.rmtree(folder, ignore_errors=True)
        t0 = time.time()
        if given:
            os.makedirs(folder)
            desc, xml = given, os.path.abspath(given)
        else:
            desc = scene_generator.generate(seed, folder, args.size, args.size)
            xml = os.path.join(folder, "scene.xml")
        entry = {"seed": seed, "scene": desc}
        try:
            scene = mi.load_file(xml)
            m_runs = [np.array(mi.render(scene, spp=args.spp, seed=1000 + k), dtype=np.float64)[..., :3]
                      for k in range(args.runs)]
            out = os.path.join(folder, "gdvr")
            g_runs = []
            for k in range(args.runs):
                shutil.rmtree(out, ignore_errors=True)
                g_runs += render_gdvr(args.render, xml, out, args.spp, 5000 + k)
            entry["mitsuba"] = compare_means(g_runs, m_runs, args.blocks, args.floor)
            ratio, g_rel, m_rel = variance_ratio(g_runs, m_runs)
            entry["variance"] = {"ratio": ratio, "gdvr": g_rel, "mitsuba": m_rel}
            ok = abs(entry["mitsuba"]["z"]) <= args.z and ratio <= args.variance_ratio
            if args.integrators and seed % args.integrators == 0:
                entry["integrators"] = {}
                # --keep-negative: the default clamp at 0 lowers one frame's
                # error but lifts the mean of dark blocks (consistent, not unbiased).
                # --data-term sampled: T-GPT's default denoised data term is
                # consistent, not unbiased, for the same reason.
                variants = [("gpt_replay", ["--integrator", "gpt", "--shift", "replay", "--recon", "l2"]),
                            ("gpt_reconnect", ["--integrator", "gpt", "--shift", "reconnect", "--recon", "l2"]),
                            ("gpt_hybrid", ["--integrator", "gpt", "--shift", "hybrid", "--recon", "l2"]),
                            ("tgpt_static", ["--integrator", "tgpt", "--recon", "l2", "--frames", "0-2",
                                             "--data-term", "sampled"])]
                for name, extra in variants:
                    extra = extra + ["--keep-negative"]
                    runs = []
                    for k in range(max(4, args.runs // 2)):
                        shutil.rmtree(out, ignore_errors=True)
                        frames = render_gdvr(args.render, xml, out, args.spp, 9000 + k, extra)
                        runs.append(frames[len(frames) // 2])
                    c = compare_means(runs, g_runs, args.blocks, args.floor)
                    entry["integrators"][name] = c
                    ok = ok and abs(c["z"]) <= args.z
        except Exception as e:  # a scene either renderer refuses is a failure to look at
            entry["error"] = str(e)[-600:]
            ok = False
        entry["ok"] = bool(ok)
        entry["seconds"] = round(time.time() - t0, 2)
        results.append(entry)
        if not ok:
            failures.append(entry)
        line = "seed %5d %s  %5.1fs  " % (seed, "ok  " if ok else "FAIL", entry["seconds"])
        if "mitsuba" in entry:
            line += "z %+6.2f rel %+.4f image %.4f var %.2f" % (entry["mitsuba"]["z"], entry["mitsuba"]["rel"],
                                                               entry["mitsuba"]["image_ratio"], entry["variance"]["ratio"])
        if "integrators" in entry:
            line += "  " + " ".join("%s %+.1f" % (k, v["z"]) for k, v in entry["integrators"].items())
        if "error" in entry:
            line += "error: " + entry["error"].splitlines()[-1][:200]
        print(line + "  | " + desc, flush=True)
        if not args.keep:
            shutil.rmtree(folder, ignore_errors=True)

    worst = sorted((r for r in results if "mitsuba" in r), key=lambda r: -abs(r["mitsuba"]["z"]))[:5]
    print("\n%d scenes, %d failed, %.0f s" % (len(results), len(failures), time.time() - start))
    print("worst agreement (reproduce with --seeds N --keep DIR):")
    for r in worst:
        print("  seed %d: z %+.2f rel %+.4f | %s" % (r["seed"], r["mitsuba"]["z"], r["mitsuba"]["rel"], r["scene"]))
    noisiest = sorted((r for r in results if "variance" in r), key=lambda r: -r["variance"]["ratio"])[:3]
    print("highest relMSE ratio gdvr / Mitsuba:")
    for r in noisiest:
        print("  seed %d: %.2f | %s" % (r["seed"], r["variance"]["ratio"], r["scene"]))
    if args.report:
        with open(args.report, "w") as f:
            json.dump({"args": vars(args), "mitsuba": mi.__version__, "scenes": len(results),
                       "failed": len(failures), "results": results}, f, indent=1)
    if not args.keep:
        shutil.rmtree(work, ignore_errors=True)
    if not results:
        print("no scene was tried")
        return 1
    print("%d passed, %d failed" % (len(results) - len(failures), len(failures)))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
