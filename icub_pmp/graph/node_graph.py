"""NodeGraph: several nodes started through their scripts (scripts/<node>.sh), as a user does.

Used by the whole-graph integration tests and by the demo. Each node is a
:class:`NodeProcess` with its ``config/<node>.yaml``; extra parameters per node override it.
``restart(node)`` and ``kill(node)`` act on one node only.
"""

from __future__ import annotations

from typing import Iterable, Mapping, Sequence

from icub_pmp.config import repo_root
from icub_pmp.graph.node_process import NodeProcess, param_text

__all__ = ["NodeGraph"]


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
        if extra:
            cmd.append("--ros-args")
            for k, v in extra.items():
                cmd += ["-p", f"{k}:={param_text(v)}"]
        return cmd

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

    def __enter__(self) -> "NodeGraph":
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()
