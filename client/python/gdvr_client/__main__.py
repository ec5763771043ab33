"""python -m gdvr_client submit|watch|status|list|cancel|fetch (a thin twin of the C++ CLI)."""

import argparse
import sys

import grpc

from gdvr_client import Client, GdvrError, JobFailed

EXIT = {grpc.StatusCode.UNAVAILABLE: 3, grpc.StatusCode.DEADLINE_EXCEEDED: 3, grpc.StatusCode.UNAUTHENTICATED: 4,
        grpc.StatusCode.INVALID_ARGUMENT: 5, grpc.StatusCode.NOT_FOUND: 5, grpc.StatusCode.FAILED_PRECONDITION: 5,
        grpc.StatusCode.RESOURCE_EXHAUSTED: 5}


def main(argv=None):
    ap = argparse.ArgumentParser(prog="gdvr-py")
    ap.add_argument("--server")
    ap.add_argument("--token")
    sub = ap.add_subparsers(dest="cmd", required=True)
    s = sub.add_parser("submit"); s.add_argument("job_file"); s.add_argument("--key"); s.add_argument("--out")
    s.add_argument("--watch", action="store_true")
    w = sub.add_parser("watch"); w.add_argument("job_id"); w.add_argument("--out")
    for name in ("status", "cancel"):
        sub.add_parser(name).add_argument("job_id")
    sub.add_parser("list").add_argument("--state", action="append", default=[])
    f = sub.add_parser("fetch"); f.add_argument("job_id"); f.add_argument("--out", required=True)
    f.add_argument("--what", default="frames,previews,video,stats")
    a = ap.parse_args(argv)
    c = Client(a.server, a.token)
    try:
        if a.cmd == "submit":
            job_id = c.submit(open(a.job_file).read(), a.key)
            print(job_id)
            if a.watch:
                for fr in c.frames(job_id):
                    print(f"frame {fr.frame} {fr.progress.frames_done}/{fr.progress.frames_total}", file=sys.stderr)
                    if a.out:
                        import os
                        os.makedirs(a.out, exist_ok=True)
                        with open(os.path.join(a.out, fr.file_name), "wb") as fh:
                            fh.write(fr.exr)
        elif a.cmd == "watch":
            for fr in c.frames(a.job_id):
                print(f"frame {fr.frame} {fr.progress.frames_done}/{fr.progress.frames_total}")
        elif a.cmd == "status":
            print(c.status(a.job_id))
        elif a.cmd == "list":
            for j in c.list(a.state):
                print(j.id, pb_state(j.state), f"{len(j.final_frames)}/{len(j.frames)}")
        elif a.cmd == "cancel":
            c.cancel(a.job_id)
        elif a.cmd == "fetch":
            for p in c.fetch(a.job_id, a.out, [k for k in a.what.split(",") if k]):
                print(p)
    except JobFailed as e:
        print(f"gdvr-py: {e}", file=sys.stderr)
        return 1
    except GdvrError as e:
        print(f"gdvr-py: {e}", file=sys.stderr)
        return EXIT.get(e.code, 6)
    return 0


def pb_state(s):
    from gdvr_client._proto.gdvr.v1 import render_service_pb2 as pb
    return pb.JobState.Name(s).replace("JOB_STATE_", "").lower()


if __name__ == "__main__":
    sys.exit(main())
