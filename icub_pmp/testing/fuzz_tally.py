"""FuzzTally: what the fuzzer saw per interface (cases, crashes, hangs, unclear rejections)."""

from __future__ import annotations

import collections
import dataclasses

__all__ = ["FuzzTally", "InterfaceTally"]


@dataclasses.dataclass
class InterfaceTally:
    """Counts for one interface ``name`` (a service, an action or a subscribed topic).

    ``cases``: inputs sent; ``crashes``: cases after which the serving node's process was gone;
    ``hangs``: requests or goals not answered within the interface's time budget; ``unclear``:
    rejections (success false, an error code) with an empty message; ``rejected``: clear
    rejections; ``burst_hz``: the rate a topic burst reached [msg/s]; ``examples``: a few of
    the problems, for the failure message; ``reasons``: how often each rejection message
    (its first 60 characters, numbers dropped) came back: how deep the cases got.
    """

    kind: str
    node: str
    name: str = ""
    cases: int = 0
    crashes: int = 0
    hangs: int = 0
    unclear: int = 0
    rejected: int = 0
    burst_hz: float = 0.0
    examples: list[str] = dataclasses.field(default_factory=list)
    reasons: collections.Counter = dataclasses.field(default_factory=collections.Counter)

    def reject(self, message: str) -> None:
        """Count a clear rejection with its ``message``."""
        self.rejected += 1
        self.reasons["".join(c for c in message[:60] if not c.isdigit())] += 1

    def note(self, what: str) -> None:
        """Keep an example of a problem (the first five)."""
        if len(self.examples) < 5:
            self.examples.append(what)


class FuzzTally:
    """Per-interface tallies, with totals and a printable table."""

    def __init__(self) -> None:
        self.interfaces: dict[str, InterfaceTally] = {}

    def get(self, name: str, kind: str, node: str) -> InterfaceTally:
        """The tally of interface ``name`` (created on first use)."""
        if name not in self.interfaces:
            self.interfaces[name] = InterfaceTally(kind, node, name)
        return self.interfaces[name]

    def total(self, field: str) -> int:
        """The sum of ``field`` (cases | crashes | hangs | unclear | rejected) over all
        interfaces."""
        return sum(getattr(t, field) for t in self.interfaces.values())

    def problems(self) -> list[str]:
        """One line per interface with a crash, a hang or an unclear rejection."""
        return [f"{name} ({t.node}): {t.crashes} crashes, {t.hangs} hangs, {t.unclear} unclear; "
                f"e.g. {t.examples}"
                for name, t in self.interfaces.items() if t.crashes or t.hangs or t.unclear]

    def reasons(self, top: int = 3) -> str:
        """The most frequent rejection messages per interface, one line each."""
        return "\n".join(f"{name}: " + "; ".join(f"{n}x {r!r}" for r, n in
                                                  t.reasons.most_common(top))
                         for name, t in self.interfaces.items() if t.reasons)

    def table(self) -> str:
        """A fixed-width table: interface, kind, node, cases, rejected, crashes, hangs,
        unclear, and a totals row."""
        head = f"{'interface':44s} {'kind':8s} {'node':22s} cases rejected crash hang unclear"
        rows = [head]
        for name, t in self.interfaces.items():
            rows.append(f"{name:44s} {t.kind:8s} {t.node:22s} {t.cases:5d} {t.rejected:8d} "
                        f"{t.crashes:5d} {t.hangs:4d} {t.unclear:7d}")
        rows.append(f"{'total':76s} {self.total('cases'):5d} {self.total('rejected'):8d} "
                    f"{self.total('crashes'):5d} {self.total('hangs'):4d} "
                    f"{self.total('unclear'):7d}")
        return "\n".join(rows)
