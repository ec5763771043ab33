"""Python client of gdvr-server: the same verbs as the `gdvr` CLI, plus an
iterator of final frames as numpy arrays."""

from gdvr_client.client import Client, Frame, GdvrError, JobFailed

__all__ = ["Client", "Frame", "GdvrError", "JobFailed"]
