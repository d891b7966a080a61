"""run_icub: the ``icub`` command line run as a user runs it (``scripts/env.sh icub ...``), in
the caller's environment (the test session's ROS domain)."""

from __future__ import annotations

import subprocess

from icub_pmp.config import repo_root

__all__ = ["run_icub"]


def run_icub(*args: str, timeout: float = 120.0) -> subprocess.CompletedProcess:
    """Run ``scripts/env.sh icub ARGS``; returns the finished process (text stdout/stderr)."""
    return subprocess.run([str(repo_root() / "scripts/env.sh"), "icub", *args],
                          capture_output=True, text=True, timeout=timeout,
                          stdin=subprocess.DEVNULL)
