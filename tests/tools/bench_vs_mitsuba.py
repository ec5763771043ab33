#!/usr/bin/env python3
"""gdvr's path tracer against Mitsuba 3 (scalar_rgb) at equal spp and resolution.

Renders cbox, veach-mis and matpreview with both renderers (same max_depth, box
filter, the same thread count), --runs times each, and prints the median render
times, their ratio, and both relMSE forms of each image against the committed
4096-spp Mitsuba reference. Render times exclude scene loading for both.

  pip install mitsuba==3.9.1 numpy
  python3 tests/tools/bench_vs_mitsuba.py --spp 64 --threads 2 --runs 3 [--json docs/bench_pt_vs_mitsuba.json]
"""
import argparse, json, os, re, subprocess, sys, tempfile, time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)
from mitsuba_baseline import SCENES, rel_mse  # noqa: E402


def render_gdvr(exe, xml, params, spp, threads, seed, out):
    cmd = [exe, os.path.join(ROOT, xml), "--out", out, "--spp", str(spp), "--threads", str(threads), "--seed", str(seed)]
    for k, v in params.items():
        cmd += ["--param", f"{k}={v}"]
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    stats = json.load(open(os.path.join(out, "stats.json")))
    return stats["frames"][0]["render_seconds"], os.path.join(out, "frame_0000.exr")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--scenes", default="cbox,veach-mis,matpreview")
    ap.add_argument("--gdvr", default=os.path.join(ROOT, "build/bin/gdvr-render"))
    ap.add_argument("--json", default="")
    args = ap.parse_args()

    import drjit as dr
    import mitsuba as mi
    mi.set_variant("scalar_rgb")
    dr.set_thread_count(args.threads)
    load = open("/proc/loadavg").read().split()[0]
    print(f"# spp {args.spp}, threads {args.threads}, runs {args.runs}, load average at start {load}")
    print(f"{'scene':12s} {'gdvr s':>8s} {'mitsuba s':>10s} {'speedup':>8s} {'gdvr relMSE (glob/pp)':>24s} {'mitsuba relMSE (glob/pp)':>26s}")
    results = {"spp": args.spp, "threads": args.threads, "runs": args.runs, "load_average_start": float(load), "scenes": {}}
    with tempfile.TemporaryDirectory() as tmpdir:
        for name in args.scenes.split(","):
            xml, ref_path, params = SCENES[name]
            ref = np.array(mi.Bitmap(os.path.join(ROOT, ref_path)), dtype=np.float64)
            src = open(os.path.join(ROOT, xml)).read()
            src = re.sub(r'<rfilter type="[^"]*"\s*/>', '<rfilter type="box"/>', src)
            fd, tmp = tempfile.mkstemp(suffix=".xml", dir=os.path.dirname(os.path.join(ROOT, xml)))
            with os.fdopen(fd, "w") as f:
                f.write(src)
            try:
                scene = mi.load_file(tmp, spp=args.spp, **params)
            finally:
                os.unlink(tmp)
            g_times, m_times, g_err, m_err = [], [], [], []
            for run in range(args.runs):
                # Interleave the two renderers so load changes affect both alike.
                out = os.path.join(tmpdir, f"{name}_{run}")
                t, exr = render_gdvr(args.gdvr, xml, params, args.spp, args.threads, run, out)
                g_times.append(t)
                img = np.array(mi.Bitmap(exr).split()[0][1], dtype=np.float64)
                g_err.append(rel_mse(img, ref))
                t0 = time.perf_counter()
                mimg = np.array(mi.render(scene, seed=run, spp=args.spp), dtype=np.float64)
                m_times.append(time.perf_counter() - t0)
                m_err.append(rel_mse(mimg, ref))
            gt, mt = float(np.median(g_times)), float(np.median(m_times))
            ge = [float(np.median([e[i] for e in g_err])) for i in range(2)]
            me = [float(np.median([e[i] for e in m_err])) for i in range(2)]
            print(f"{name:12s} {gt:8.3f} {mt:10.3f} {mt / gt:7.2f}x {ge[0]:11.5f} / {ge[1]:9.5f} {me[0]:12.5f} / {me[1]:9.5f}", flush=True)
            results["scenes"][name] = {"gdvr_seconds": gt, "mitsuba_seconds": mt, "speedup": mt / gt,
                                       "gdvr_run_seconds": g_times, "mitsuba_run_seconds": m_times,
                                       "gdvr_relmse_global": ge[0], "gdvr_relmse_per_pixel": ge[1],
                                       "mitsuba_relmse_global": me[0], "mitsuba_relmse_per_pixel": me[1]}
    results["load_average_end"] = float(open("/proc/loadavg").read().split()[0])
    if args.json:
        with open(args.json, "w") as f:
            json.dump(results, f, indent=2)
            f.write("\n")


if __name__ == "__main__":
    sys.exit(main())
