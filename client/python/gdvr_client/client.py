"""gdvr-server client. Frames stream as EXR bytes plus raw float32 RGB
(requested with include_raw_rgb, since Python has no offline EXR decoder)."""

from __future__ import annotations

import dataclasses
import json
import os
import time
import uuid
from typing import Iterable, Iterator, Optional, Union

import grpc
import numpy as np
from google.protobuf import json_format

from gdvr_client._proto.gdvr.v1 import job_pb2, render_service_pb2 as pb, render_service_pb2_grpc as pb_grpc

JobSpec = job_pb2.JobSpec


class GdvrError(Exception):
    """A call failed; `code` is the grpc.StatusCode."""

    def __init__(self, code: grpc.StatusCode, message: str):
        super().__init__(f"{code.name}: {message}")
        self.code = code
        self.message = message


class JobFailed(GdvrError):
    """The job ended failed or cancelled."""


@dataclasses.dataclass
class Frame:
    frame: int
    rgb: Optional[np.ndarray]  # float32 (height, width, 3), linear
    exr: bytes                 # the frame_NNNN.exr file as written by the server
    file_name: str
    stats: pb.FrameStats
    progress: pb.Progress


_STATES = {
    "queued": pb.JOB_STATE_QUEUED, "running": pb.JOB_STATE_RUNNING, "completed": pb.JOB_STATE_COMPLETED,
    "failed": pb.JOB_STATE_FAILED, "cancelled": pb.JOB_STATE_CANCELLED,
    "cancelling": pb.JOB_STATE_CANCELLING,
}


def _wrap(call):
    try:
        return call()
    except grpc.RpcError as e:  # type: ignore[misc]
        raise GdvrError(e.code(), e.details()) from None


class Client:
    def __init__(self, server: str = None, token: str = None, root_certificates: bytes = None,
                 private_key: bytes = None, certificate_chain: bytes = None, timeout: float = 30.0):
        self.server = server or os.environ.get("GDVR_SERVER", "127.0.0.1:50051")
        self.token = token if token is not None else os.environ.get("GDVR_TOKEN")
        self.timeout = timeout
        options = [("grpc.keepalive_time_ms", 30000), ("grpc.keepalive_timeout_ms", 20000),
                   ("grpc.keepalive_permit_without_calls", 1), ("grpc.max_receive_message_length", 16 << 20)]
        if root_certificates:
            creds = grpc.ssl_channel_credentials(root_certificates, private_key, certificate_chain)
            self._channel = grpc.secure_channel(self.server, creds, options)
        else:
            self._channel = grpc.insecure_channel(self.server, options)
        self._stub = pb_grpc.RenderServiceStub(self._channel)

    def close(self):
        self._channel.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def _md(self):
        return [("authorization", f"Bearer {self.token}")] if self.token else None

    # ---- Verbs ----

    def submit(self, job: Union[dict, str, JobSpec], idempotency_key: str = None) -> str:
        """Submits a job (dict, job-file JSON text, or JobSpec); returns its id.
        The same idempotency_key returns the same job."""
        req = pb.SubmitJobRequest(idempotency_key=idempotency_key or f"py-{uuid.uuid4().hex}")
        if isinstance(job, JobSpec):
            req.job.CopyFrom(job)
        else:
            # Sent as text so the server names unknown fields in its error.
            req.job_json = job if isinstance(job, str) else json.dumps(job)
        resp = _wrap(lambda: self._stub.SubmitJob(req, timeout=self.timeout, metadata=self._md()))
        return resp.job_id

    def status(self, job_id: str) -> pb.Job:
        return _wrap(lambda: self._stub.GetJob(pb.GetJobRequest(job_id=job_id), timeout=self.timeout,
                                               metadata=self._md()))

    def list(self, states: Iterable[str] = (), page_size: int = 100) -> list:
        req = pb.ListJobsRequest(states=[_STATES[s] for s in states], page_size=page_size)
        jobs = []
        while True:
            resp = _wrap(lambda: self._stub.ListJobs(req, timeout=self.timeout, metadata=self._md()))
            jobs.extend(resp.jobs)
            if not resp.next_page_token:
                return jobs
            req.page_token = resp.next_page_token

    def cancel(self, job_id: str) -> pb.Job:
        return _wrap(lambda: self._stub.CancelJob(pb.CancelJobRequest(job_id=job_id), timeout=self.timeout,
                                                  metadata=self._md()))

    def upload(self, folder: str, scene_file: str) -> str:
        """Uploads `folder` as a scene bundle; returns the scene path to submit."""
        files = sorted(os.path.relpath(os.path.join(d, f), folder).replace(os.sep, "/")
                       for d, _, fs in os.walk(folder) for f in fs)

        def chunks():
            first = True
            for rel in files:
                with open(os.path.join(folder, rel), "rb") as fh:
                    while True:
                        data = fh.read(1 << 20)
                        yield pb.UploadSceneChunk(scene_file=scene_file if first else "", path=rel, data=data)
                        first = False
                        if not data or len(data) < (1 << 20):
                            break

        resp = _wrap(lambda: self._stub.UploadScene(chunks(), timeout=600, metadata=self._md()))
        return resp.scene

    def watch(self, job_id: str, from_frame: int = None, raw: bool = True) -> Iterator[pb.JobEvent]:
        """Raw event stream (one attempt; see frames() for auto-resume)."""
        req = pb.WatchJobRequest(job_id=job_id, include_raw_rgb=raw)
        if from_frame is not None:
            req.from_frame = from_frame
        try:
            yield from self._stub.WatchJob(req, metadata=self._md())
        except grpc.RpcError as e:  # type: ignore[misc]
            raise GdvrError(e.code(), e.details()) from None

    def frames(self, job_id: str, from_frame: int = None, retries: int = 30) -> Iterator[Frame]:
        """Yields each final frame in order, reconnecting and resuming after a
        dropped connection or a server restart. Raises JobFailed if the job
        fails or is cancelled."""
        next_frame = from_frame
        attempts = 0
        while True:
            exr, raw, current = bytearray(), bytearray(), None
            try:
                for ev in self.watch(job_id, next_frame, raw=True):
                    attempts = 0
                    kind = ev.WhichOneof("event")
                    if kind == "frame_final":
                        ff = ev.frame_final
                        if ff.offset == 0 and ff.payload == pb.FrameFinal.PAYLOAD_EXR:
                            exr, raw, current = bytearray(), bytearray(), ff.frame
                        (exr if ff.payload == pb.FrameFinal.PAYLOAD_EXR else raw).extend(ff.data)
                        if ff.last and ff.frame == current:
                            rgb = None
                            if raw and ff.width > 0:
                                rgb = np.frombuffer(bytes(raw), dtype="<f4").reshape(ff.height, ff.width, 3)
                            yield Frame(ff.frame, rgb, bytes(exr), ff.file_name, ff.stats, ff.progress)
                            next_frame = ff.frame + 1
                    elif kind == "completed":
                        return
                    elif kind == "failed":
                        raise JobFailed(grpc.StatusCode.ABORTED, f"{ev.failed.code}: {ev.failed.reason}")
                    elif kind == "cancelled":
                        raise JobFailed(grpc.StatusCode.CANCELLED, ev.cancelled.reason)
                return
            except GdvrError as e:
                if isinstance(e, JobFailed) or e.code != grpc.StatusCode.UNAVAILABLE or attempts >= retries:
                    raise
                attempts += 1
                time.sleep(min(2.0, 0.2 * attempts))

    ARTIFACT_KINDS = {"frames": 1, "previews": 2, "video": 3, "stats": 4}

    def fetch(self, job_id: str, out_dir: str, kinds: Iterable[str] = ("frames",)) -> list:
        """Saves the job's files as they are now (kinds: frames, previews,
        video, stats; empty: all) into out_dir; returns their paths."""
        req = pb.FetchArtifactsRequest(job_id=job_id, kinds=[self.ARTIFACT_KINDS[k] for k in kinds])
        os.makedirs(out_dir, exist_ok=True)
        paths, fh, name = [], None, None
        try:
            for c in self._stub.FetchArtifacts(req, metadata=self._md()):
                if c.offset == 0:
                    name = c.file_name
                    if not name or "/" in name or name in (".", ".."):
                        raise GdvrError(grpc.StatusCode.INTERNAL, f"refusing file name {name!r}")
                    fh = open(os.path.join(out_dir, name + ".part"), "wb")
                fh.write(c.data)
                if c.last:
                    fh.close()
                    path = os.path.join(out_dir, name)
                    os.replace(path + ".part", path)
                    paths.append(path)
                    fh = None
        except grpc.RpcError as e:  # type: ignore[misc]
            raise GdvrError(e.code(), e.details()) from None
        finally:
            if fh is not None:
                fh.close()
                os.remove(fh.name)
        return paths

    @staticmethod
    def job_from_json(text: str) -> JobSpec:
        return json_format.Parse(text, JobSpec())
