#!/usr/bin/env python3
"""Submits a gdvr job to OpenCue (pyoutline): a render layer whose frames are
chunked by Cuebot, each chunk running

    gdvr-farm render JOB --frames #FRAME_START#-#FRAME_END# --buffers FARM/buffers

(RQD replaces the tokens with the chunk's first and last frame), and a
finalize_tiles layer whose "frames" are the tiles of the T-GPT window solve
(gdvr-farm finalize --tiles #FRAME_START#-#FRAME_END#, docs/farm.md), and a
one-frame finalize layer that waits for it and assembles the frames.

    python3 gdvr_submit.py /shared/job.json --frames 0-47 --chunk 8 --farm-dir /shared/farm \\
        --show gdvr --shot demo

Chunks are idempotent: a retried frame of the render layer renders only the
frames of its chunk whose buffers are not complete yet.
"""
import argparse
import getpass

import outline
import outline.cuerun
from outline.modules.shell import Shell, ShellCommand


def build_outline(args):
    ol = outline.Outline(args.name, show=args.show, shot=args.shot, user=getpass.getuser())
    buffers = f"{args.farm_dir}/buffers"
    render_cmd = [args.gdvr_farm, "render", args.job_file, "--frames", "#FRAME_START#-#FRAME_END#",
                  "--buffers", buffers]
    if args.threads:
        render_cmd += ["--threads", str(args.threads)]
    render = Shell("render", command=render_cmd, range=args.frames, chunk=args.chunk,
                   threads=args.threads or 1, threadable=True)
    # The window solve by tiles: one task per chunk of tiles (the layer's
    # "frames" are tile indices here), each writing its tiles of every frame.
    tiles = Shell("finalize_tiles", command=[args.gdvr_farm, "finalize", args.job_file, "--tiles",
                                             "#FRAME_START#-#FRAME_END#", "--buffers", buffers,
                                             "--out", f"{args.farm_dir}/output"],
                  range=args.tiles, chunk=args.tiles_per_task, threads=args.threads or 1, threadable=True)
    finalize = ShellCommand("finalize", command=[args.gdvr_farm, "finalize", args.job_file, "--buffers", buffers,
                                                 "--out", f"{args.farm_dir}/output", "--video"])
    # Layer-on-layer: the tile tasks start once every chunk of render
    # succeeded, the assembling finalize once every tile task did.
    tiles.depend_all(render)
    finalize.depend_all(tiles)
    ol.add_layer(render)
    ol.add_layer(tiles)
    ol.add_layer(finalize)
    return ol


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("job_file", help="gdvr job file (JSON) on shared storage")
    p.add_argument("--frames", required=True, help="the job's frames, e.g. 0-47 (as in the job file)")
    p.add_argument("--chunk", type=int, default=8, help="frames per render task")
    p.add_argument("--tiles", default="0",
                   help="tile indices of the window solve, e.g. 0-11 (gdvr-farm tiles JOB --tiles-per-task 100000)")
    p.add_argument("--tiles-per-task", type=int, default=4, help="tiles per finalize_tiles task")
    p.add_argument("--farm-dir", required=True, help="shared folder for buffers/ and output/")
    p.add_argument("--threads", type=int, default=0, help="cores per task (0: all)")
    p.add_argument("--name", default="gdvr")
    p.add_argument("--show", required=True)
    p.add_argument("--shot", required=True)
    p.add_argument("--gdvr-farm", default="gdvr-farm", help="gdvr-farm on the render hosts")
    args = p.parse_args()
    # use_pycuerun=False: RQD runs our command as is, with #FRAME_START# and
    # #FRAME_END# substituted per chunk.
    outline.cuerun.launch(build_outline(args), use_pycuerun=False)


if __name__ == "__main__":
    main()
