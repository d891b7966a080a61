"""NodeGraph: several nodes started through their scripts (scripts/<node>.sh), as a user does.

Used by the whole-graph integration tests and by the demo. Each node is a
:class:`NodeProcess` with its ``config/<node>.yaml``; extra parameters per node override it.
``restart(node)`` and ``kill(node)`` act on one node only.

A composed process counts as one node of the list: ``torque_loop`` hosts the
``wrench_estimator`` and ``impedance_controller`` nodes, ``robot_loop`` the ``sim_bridge``
and those two (:data:`COMPOSED`); the per-node
parameters given under their own names go to them in a parameter file with one section per
node (a ``-p`` on the command line would set both), and :meth:`host` names the process that
runs a node.
"""

from __future__ import annotations

import tempfile
from pathlib import Path
from typing import Iterable, Mapping, Sequence

import yaml

from icub_pmp.config import repo_root
from icub_pmp.graph.node_process import NodeProcess, param_text

__all__ = ["NodeGraph", "COMPOSED"]

#: processes that host several nodes: process name -> the nodes it runs
COMPOSED: dict[str, tuple[str, ...]] = {
    "torque_loop": ("wrench_estimator", "impedance_controller"),
    "robot_loop": ("sim_bridge", "wrench_estimator", "impedance_controller"),
}


class NodeGraph:
    """Start ``nodes`` (names of scripts/<node>.sh) with optional per-node parameters;
    ``prefix`` runs them through a command (a network namespace: :class:`VethLink`)."""

    def __init__(
        self,
        nodes: Iterable[str],
        parameters: Mapping[str, Mapping[str, object]] | None = None,
        env: dict[str, str] | None = None,
        prefix: Sequence[str] = (),
    ):
        self.prefix = list(prefix)  # e.g. ["ip", "netns", "exec", NS]: where the nodes run
        self.parameters = {k: dict(v) for k, v in (parameters or {}).items()}
        self.env = env
        self.procs: dict[str, NodeProcess] = {}
        self._files: list[str] = []  # parameter files written for composed processes
        try:
            for n in nodes:
                self.start(n)
        except Exception:
            self.stop()
            raise

    def command(self, node: str) -> list[str]:
        """The command line that starts ``node`` (its script plus parameter overrides)."""
        cmd = [*self.prefix, str(repo_root() / "scripts" / f"{node}.sh")]
        extra = self.parameters.get(node, {})
        hosted = {n: self.parameters[n] for n in COMPOSED.get(node, ())
                  if self.parameters.get(n)}
        if extra or hosted:
            cmd.append("--ros-args")
        if hosted:  # one section per hosted node (node.sh reads their config files first)
            f = tempfile.NamedTemporaryFile("w", prefix=f"{node}-", suffix=".yaml",
                                            delete=False)
            with f:
                yaml.safe_dump({f"/**/{n}": {"ros__parameters": dict(v)}
                                for n, v in hosted.items()}, f)
            self._files.append(f.name)
            cmd += ["--params-file", f.name]
        for k, v in extra.items():
            cmd += ["-p", f"{k}:={param_text(v)}"]
        return cmd

    def host(self, node: str) -> str:
        """The name of the process of this graph that runs ``node`` (itself, or the composed
        process hosting it); KeyError naming the processes when none does."""
        if node in self.procs:
            return node
        for proc in self.procs:
            if node in COMPOSED.get(proc, ()):
                return proc
        raise KeyError(f"no process of this graph runs {node!r}; processes: "
                       f"{sorted(self.procs)}")

    def start(self, node: str) -> NodeProcess:
        """Start (or restart) ``node``."""
        if node in self.procs and self.procs[node].alive():
            raise RuntimeError(f"{node} is already running (pid {self.procs[node].pid})")
        proc = NodeProcess(command=self.command(node), env=self.env)
        proc.name = node
        self.procs[node] = proc
        return proc

    def kill(self, node: str) -> None:
        """SIGKILL one node (crash simulation); the others keep running."""
        self.procs[node].kill()

    def restart(self, node: str) -> NodeProcess:
        """Stop ``node`` if alive, then start it again."""
        self.procs[node].stop()
        self.procs[node].close_log()
        return self.start(node)

    def alive(self) -> dict[str, bool]:
        """{node: running?}"""
        return {n: p.alive() for n, p in self.procs.items()}

    def outputs(self) -> str:
        """All nodes' output, for failure messages."""
        return "\n".join(f"===== {n}\n{p.output()[-4000:]}" for n, p in self.procs.items())

    def stop(self) -> None:
        """Stop every node this graph started (reverse order)."""
        for p in reversed(list(self.procs.values())):
            p.stop()
            p.close_log()
        for name in self._files:
            Path(name).unlink(missing_ok=True)
        self._files.clear()

    def __enter__(self) -> "NodeGraph":
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()
