"""Builds gdvr_client with its gRPC stubs generated from proto/ at build time
(generate_stubs.sh: the system protoc and grpc_python_plugin), so nothing
generated is committed. The rest of the metadata is in pyproject.toml."""
import os
import subprocess

from setuptools import setup
from setuptools.command.build_py import build_py

HERE = os.path.dirname(os.path.abspath(__file__))


class BuildPyWithStubs(build_py):
    def run(self):
        super().run()
        out = os.path.join(self.build_lib, "gdvr_client", "_proto")
        subprocess.check_call([os.path.join(HERE, "generate_stubs.sh"), out])


setup(cmdclass={"build_py": BuildPyWithStubs})
