"""VethLink: two network namespaces joined by a veth pair, standing in for two machines on one
Ethernet link (the robot's PC and a laptop, as iCub setups run).

Each namespace has its own loopback and one interface on the link (``10.77.N.1`` and
``10.77.N.2``); nothing is routed beyond the pair, so traffic between the two "hosts" never
leaves this machine. An optional ``netem`` delay emulates the link's latency. Processes are
started in a namespace with :meth:`VethLink.prefix` (``ip netns exec NS``). Needs the
``CAP_SYS_ADMIN``/``CAP_NET_ADMIN`` capabilities (root); without them :class:`VethLinkError`
carries the system's error. No ROS import.
"""

from __future__ import annotations

import os
import random
import subprocess
from dataclasses import dataclass

__all__ = ["VethLink", "VethLinkError", "Host"]


class VethLinkError(RuntimeError):
    """The namespaces or the link could not be created (the command and its error)."""


@dataclass(frozen=True)
class Host:
    """One end of the link: its namespace, interface and address."""

    namespace: str
    interface: str
    address: str


def _run(*cmd: str) -> str:
    try:
        done = subprocess.run(cmd, capture_output=True, text=True, timeout=30)
    except FileNotFoundError as exc:
        raise VethLinkError(f"{cmd[0]} is not installed: {exc}") from None
    if done.returncode != 0:
        raise VethLinkError(f"`{' '.join(cmd)}` failed: {done.stderr.strip() or done.stdout}")
    return done.stdout


class VethLink:
    """Create ``robot`` and ``laptop`` namespaces joined by a veth pair (context manager).

    ``delay_ms``: one-way delay added on each side with ``tc netem`` (0 = none).
    ``tag``: a name part that keeps parallel links apart (default: the PID).
    """

    def __init__(self, delay_ms: float = 0.0, tag: str | None = None):
        self.tag = tag or str(os.getpid())
        subnet = random.randrange(1, 250)
        self.robot = Host(f"icub_{self.tag}_robot", f"icr{self.tag}"[:15], f"10.77.{subnet}.1")
        self.laptop = Host(f"icub_{self.tag}_laptop", f"icl{self.tag}"[:15],
                           f"10.77.{subnet}.2")
        self.delay_ms = float(delay_ms)
        self._created: list[str] = []

    def up(self) -> "VethLink":
        """Create the namespaces, the pair, the addresses (raises VethLinkError)."""
        try:
            for h in (self.robot, self.laptop):
                _run("ip", "netns", "add", h.namespace)
                self._created.append(h.namespace)
                _run("ip", "-n", h.namespace, "link", "set", "lo", "up")
            _run("ip", "link", "add", self.robot.interface, "type", "veth", "peer", "name",
                 self.laptop.interface)
            for h in (self.robot, self.laptop):
                _run("ip", "link", "set", h.interface, "netns", h.namespace)
                _run("ip", "-n", h.namespace, "addr", "add", f"{h.address}/24", "dev",
                     h.interface)
                # IPv4 only on the link: no IPv6 router solicitations in the counters
                _run("ip", "netns", "exec", h.namespace, "sysctl", "-qw",
                     f"net.ipv6.conf.{h.interface}.disable_ipv6=1")
                _run("ip", "-n", h.namespace, "link", "set", h.interface, "up")
                if self.delay_ms > 0:
                    _run("ip", "netns", "exec", h.namespace, "tc", "qdisc", "add", "dev",
                         h.interface, "root", "netem", "delay", f"{self.delay_ms}ms")
        except VethLinkError:
            self.down()
            raise
        return self

    def down(self) -> None:
        """Delete the namespaces this object created (the veth pair goes with them)."""
        for ns in reversed(self._created):
            subprocess.run(["ip", "netns", "del", ns], capture_output=True, timeout=30)
        self._created.clear()

    @staticmethod
    def prefix(host: Host) -> list[str]:
        """The command prefix that runs a process on ``host``."""
        return ["ip", "netns", "exec", host.namespace]

    def peer_of(self, host: Host) -> Host:
        """The other end of the link."""
        return self.laptop if host == self.robot else self.robot

    def tx_packets(self, host: Host) -> int:
        """Packets sent so far by ``host`` on the link (its interface's counter)."""
        out = _run("ip", "netns", "exec", host.namespace, "cat",
                   f"/sys/class/net/{host.interface}/statistics/tx_packets")
        return int(out.strip())

    def __enter__(self) -> "VethLink":
        return self.up()

    def __exit__(self, *exc: object) -> None:
        self.down()
