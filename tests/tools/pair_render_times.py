#!/usr/bin/env python3
"""Paired A/B timing of two gdvr-render builds: the method behind the
"old/new, N pairs" figures in docs/benchmarks.md.

Each pair runs OLD and NEW at the same moment, one thread each, pinned to
cores 0 and 1 (swapped every pair, so neither build keeps the better core).
Load from outside then slows both alike, which a ratio of sequential runs
cannot promise. Prints the median of old/new render_seconds (stats.json,
frame 0): above 1 means NEW is faster.

  python3 tests/tools/pair_render_times.py OLD_gdvr-render NEW_gdvr-render 12 -- \\
      scenes/cbox/cbox-rgb.xml --param res=256 --spp 32

Needs two free cores (taskset). Everything after -- goes to both renders;
--threads and --out are added here.
"""
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile


def render_seconds(out_dir):
    with open(os.path.join(out_dir, "stats.json")) as f:
        return json.load(f)["frames"][0]["render_seconds"]


def main():
    if "--" not in sys.argv or sys.argv.index("--") != 4:
        sys.exit(__doc__)
    old, new, pairs = sys.argv[1], sys.argv[2], int(sys.argv[3])
    args = sys.argv[5:]
    ratios = []
    for p in range(pairs):
        work = tempfile.mkdtemp(prefix="gdvr-pair-")
        try:
            cores = (0, 1) if p % 2 == 0 else (1, 0)
            runs = []
            for exe, core, tag in ((old, cores[0], "old"), (new, cores[1], "new")):
                out = os.path.join(work, tag)
                cmd = ["taskset", "-c", str(core), exe] + args + ["--threads", "1", "--out", out]
                runs.append((subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE), out))
            for proc, _ in runs:
                _, err = proc.communicate()
                if proc.returncode != 0:
                    sys.exit(f"render failed (exit {proc.returncode}): {err.decode(errors='replace')[-2000:]}")
            ratios.append(render_seconds(runs[0][1]) / render_seconds(runs[1][1]))
        finally:
            shutil.rmtree(work, ignore_errors=True)
    print(f"old/new median {statistics.median(ratios):.3f}  "
          f"(min {min(ratios):.3f} max {max(ratios):.3f}, {len(ratios)} pairs)")


if __name__ == "__main__":
    main()
