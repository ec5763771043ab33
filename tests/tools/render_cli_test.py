#!/usr/bin/env python3
"""gdvr-render's command line (ctest render_cli): the integrator, shift and
reconstruction flags reach the job (stats.json says what ran), bad values are
rejected with exit 2 and a message naming the flag, and a T-GPT job with the
path-space temporal shift counts its temporal rays. gdvr-report (--report)
takes the flags it shares with gdvr-render (core/job/job_flags.h) alike. The
benchmark tools (--bench TOOL, repeatable) reject malformed numbers the same
way."""
import argparse, json, os, subprocess, sys, tempfile


def run(exe, args, expect_rc):
    p = subprocess.run([exe] + args, capture_output=True, text=True)
    if p.returncode != expect_rc:
        sys.exit(f"FAIL: {' '.join(args)}: exit {p.returncode}, expected {expect_rc}\n{p.stderr}")
    return p


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--render", required=True)
    ap.add_argument("--source", required=True)
    ap.add_argument("--report", help="gdvr-report")
    ap.add_argument("--bench", action="append", default=[], help="a gdvr-bench* executable")
    a = ap.parse_args()
    demo = os.path.join(a.source, "scenes", "demo", "demo_job.json")
    cbox = os.path.join(a.source, "scenes", "cbox", "cbox-rgb.xml")
    with tempfile.TemporaryDirectory() as tmp:
        # ---- Flags reach the job ----
        out = os.path.join(tmp, "tgpt")
        run(a.render, [demo, "--out", out, "--frames", "0-2", "--width", "16", "--height", "16", "--spp", "2",
                       "--integrator", "tgpt", "--temporal-shift", "reconnect", "--recon", "l1", "--alpha", "0.3",
                       "--window", "3", "--threads", "2"], 0)
        stats = json.load(open(os.path.join(out, "stats.json")))
        assert stats["integrator"] == "tgpt", stats["integrator"]
        frames = stats["frames"]
        assert [f["frame"] for f in frames] == [0, 1, 2], frames
        assert all(f["temporal_rays"] > 0 for f in frames), [f["temporal_rays"] for f in frames]
        assert stats["total"]["temporal_rays"] == sum(f["temporal_rays"] for f in frames)
        for f in range(3):
            assert os.path.getsize(os.path.join(out, f"frame_{f:04d}.exr")) > 0

        out = os.path.join(tmp, "gpt")
        run(a.render, [cbox, "--out", out, "-D", "res=16", "--spp", "2", "--integrator", "gpt", "--shift", "hybrid",
                       "--recon", "weighted"], 0)
        stats = json.load(open(os.path.join(out, "stats.json")))
        assert stats["integrator"] == "gpt" and stats["frames"][0]["temporal_rays"] == 0, stats

        # ---- Bad values: exit 2, the message names what is wrong ----
        for args, needle in [(["--recon", "l3"], "l3"), (["--shift", "sideways"], "sideways"),
                             (["--temporal-shift", "warp"], "warp"), (["--alpha", "-1"], "--alpha"),
                             (["--alpha", "nan"], "--alpha"), (["--window", "0"], "--window"),
                             (["--integrator"], "--integrator needs a value"), (["--bogus"], "unknown option --bogus"),
                             (["--time-budget", "1abc"], "--time-budget"), (["--time-budget", "inf"], "--time-budget"),
                             (["--param", "res"], "--param"), (["--param", "=16"], "--param")]:
            p = run(a.render, [cbox, "--out", os.path.join(tmp, "bad")] + args, 2)
            if needle not in p.stderr:
                sys.exit(f"FAIL: {args}: message does not name '{needle}':\n{p.stderr}")
        # An unknown integrator is the job's error (exit 1), naming the field.
        p = run(a.render, [cbox, "--out", os.path.join(tmp, "bad"), "--integrator", "bdpt"], 1)
        assert "bdpt" in p.stderr and "job.integrator" in p.stderr, p.stderr
        # So is a value the job refuses, whether from a flag or the file.
        p = run(a.render, [cbox, "--out", os.path.join(tmp, "bad"), "--frames", "5-1"], 1)
        assert "job.frames" in p.stderr, p.stderr

        # ---- gdvr-report: the shared flags, parsed alike; its own too ----
        if a.report:
            for args, needle in [(["--width", "0"], "--width"), (["--seed", "x"], "--seed"),
                                 (["--param", "res"], "--param"), (["--frames"], "--frames needs a value"),
                                 (["--threads", "0"], "--threads"), (["--budgets", "x"], "--budgets"),
                                 (["--spp", "4"], "unknown option --spp"), (["--bogus"], "unknown option --bogus")]:
                p = run(a.report, [cbox, "--out", os.path.join(tmp, "report")] + args, 2)
                if needle not in p.stderr:
                    sys.exit(f"FAIL: gdvr-report {args}: message does not name '{needle}':\n{p.stderr}")
            p = run(a.report, [cbox, "--out", os.path.join(tmp, "report"), "--frames", "5-1"], 1)
            assert "job.frames" in p.stderr, p.stderr

    # ---- Benchmark tools: a malformed number is exit 2 naming the option ----
    # (std::stoi threw and std::atoi read 0 before cli_args.h's int_option.)
    bench_args = {"gdvr-bench": [cbox], "gdvr-bench-gpt": [], "gdvr-bench-recon": [], "gdvr-bench-tgpt": [],
                  "gdvr-bench-stream": []}
    for exe in a.bench:
        name = os.path.basename(exe)
        for bad in (["--runs", "x"], ["--runs", "0"], ["--threads", "2x"]):
            p = run(exe, bench_args[name] + bad, 2)
            if bad[0] not in p.stderr or repr(bad[1])[1:-1] not in p.stderr:
                sys.exit(f"FAIL: {name} {bad}: message does not name the option and value:\n{p.stderr}")
    print("render_cli: ok")


if __name__ == "__main__":
    main()
