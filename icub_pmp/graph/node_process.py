"""NodeProcess: a node (or any project command) started as a subprocess, stopped by its PID."""

from __future__ import annotations

import os
import signal
import subprocess
import tempfile
import time
from pathlib import Path
from typing import Sequence

import yaml

from icub_pmp.config import repo_root

__all__ = ["NodeProcess", "param_text"]


class NodeProcess:
    """Run ``scripts/run_node.sh NODE ARGS`` (or any command) in its own process group.

    Output goes to a temporary log file (:meth:`output`), removed by :meth:`close_log` (and on
    leaving the context) unless ``ICUB_PMP_KEEP_NODE_LOGS`` is set (then its path is kept for
    reading after the run). :meth:`stop` sends SIGINT to the group this object started, then
    SIGKILL after ``timeout``; it never touches other processes. Usable as a context manager.
    """

    def __init__(
        self,
        node: str | None = None,
        args: Sequence[str] = (),
        *,
        command: Sequence[str] | None = None,
        env: dict[str, str] | None = None,
        params_file: str | Path | None = None,
        parameters: dict[str, object] | None = None,
    ):
        if command is None:
            if node is None:
                raise ValueError("NodeProcess needs a node name or a command")
            ros_args: list[str] = []
            if params_file is not None:
                ros_args += ["--params-file", str(params_file)]
            for k, v in (parameters or {}).items():
                ros_args += ["-p", f"{k}:={param_text(v)}"]
            command = [str(repo_root() / "scripts/run_node.sh"), node, *args]
            if ros_args:
                command += ["--ros-args", *ros_args]
        self.command = list(command)
        self.name = node or Path(self.command[0]).name
        self._log = tempfile.NamedTemporaryFile(
            prefix=f"{self.name}-", suffix=".log", delete=False
        )
        self._closed_output: str | None = None
        self.proc = subprocess.Popen(
            self.command,
            stdout=self._log,
            stderr=subprocess.STDOUT,
            stdin=subprocess.DEVNULL,
            env=env,
            start_new_session=True,
        )

    @property
    def pid(self) -> int:
        """PID of the started process (leader of its own process group)."""
        return self.proc.pid

    def alive(self) -> bool:
        """True while the process runs."""
        return self.proc.poll() is None

    def output(self) -> str:
        """Everything the process printed so far (after :meth:`close_log`: all it printed)."""
        if self._closed_output is not None:
            return self._closed_output
        self._log.flush()
        return Path(self._log.name).read_text(errors="replace")

    @property
    def log_path(self) -> str:
        """The log file's path."""
        return self._log.name

    def close_log(self) -> None:
        """Keep the output in memory and remove the log file (a stopped process's; kept when
        ``ICUB_PMP_KEEP_NODE_LOGS`` is set): benchmarks and tests start hundreds of nodes."""
        if self._closed_output is not None or self.alive():
            return
        self._closed_output = self.output()
        self._log.close()
        if not os.environ.get("ICUB_PMP_KEEP_NODE_LOGS"):
            try:
                os.unlink(self._log.name)
            except OSError:
                pass

    def signal(self, sig: int) -> None:
        """Send ``sig`` to the process group this object started (if still running)."""
        if self.alive():
            try:
                os.killpg(self.proc.pid, sig)
            except ProcessLookupError:
                pass

    def stop(self, timeout: float = 10.0) -> int | None:
        """SIGINT, wait up to ``timeout`` s, then SIGKILL. Returns the exit code."""
        if self.alive():
            self.signal(signal.SIGINT)
            try:
                self.proc.wait(timeout)
            except subprocess.TimeoutExpired:
                self.signal(signal.SIGKILL)
                self.proc.wait(5.0)
        return self.proc.returncode

    def kill(self) -> None:
        """SIGKILL the process group now (crash simulation)."""
        self.signal(signal.SIGKILL)
        try:
            self.proc.wait(5.0)
        except subprocess.TimeoutExpired:  # pragma: no cover
            pass

    def wait_for_output(self, text: str, timeout: float = 30.0) -> bool:
        """Wait until ``text`` appears in the output (False on timeout or exit)."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if text in self.output():
                return True
            if not self.alive():
                return text in self.output()
            time.sleep(0.05)
        return False

    def __enter__(self) -> "NodeProcess":
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()
        self.close_log()


def param_text(v: object) -> str:
    """A parameter value as ``-p NAME:=VALUE`` text (ROS YAML syntax)."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (list, tuple)):
        return "[" + ",".join(param_text(x) for x in v) + "]"
    if isinstance(v, str):
        # rcl reads the value as YAML: an empty string, or text YAML would read as another
        # type ("true", "1.5", "null", "[a]"), must be a quoted scalar
        try:
            plain = yaml.safe_load(v) == v and "'" not in v
        except yaml.YAMLError:
            plain = False
        return v if plain and v.strip() == v else "'" + v.replace("'", "''") + "'"
    return str(v)
