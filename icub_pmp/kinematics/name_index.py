"""name_indices: positions of named joints in a joint vector (one helper for every core)."""

from __future__ import annotations

from typing import Iterable, Mapping, Sequence

import numpy as np

from icub_pmp.errors import UnknownName

__all__ = ["name_indices"]


def name_indices(
    names: Iterable[str], index: Mapping[str, int], valid: Sequence[str], kind: str = "joint"
) -> np.ndarray:
    """Positions (int array) of ``names`` through ``index`` ({name: position}); an unknown name
    raises :class:`UnknownName` listing ``valid``."""
    out = []
    for n in names:
        i = index.get(n)
        if i is None:
            raise UnknownName(kind, n, valid)
        out.append(i)
    return np.array(out, dtype=int)
