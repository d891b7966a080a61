"""Saving and loading a :class:`TanhMlp` with its metadata as one ``.npz`` file.

The file holds the layer sizes, the flat weights, the normalisation and a JSON metadata
string (``kind``: ``body_network`` | ``eye_hand_map``, plus what the owner needs: arm, joint
names, frames, limits, provenance). Nothing is pickled (``allow_pickle=False``).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from icub_pmp.body_schema.tanh_mlp import TanhMlp
from icub_pmp.errors import ModelError

__all__ = ["save_model", "load_model", "read_npz"]

_FORMAT = 1


def save_model(path: str | Path, mlp: TanhMlp, kind: str, meta: Mapping[str, Any]) -> Path:
    """Write ``mlp`` and ``meta`` (JSON-serialisable) to ``path`` (``.npz`` added if missing;
    parent folders created). Returns the path written."""
    path = Path(path)
    if path.suffix != ".npz":
        path = path.with_suffix(path.suffix + ".npz")
    path.parent.mkdir(parents=True, exist_ok=True)
    info = dict(meta, kind=kind, format=_FORMAT)
    np.savez(path, sizes=np.array(mlp.sizes), theta=mlp.params(), x_mean=mlp.x_mean,
             x_scale=mlp.x_scale, y_mean=mlp.y_mean, y_scale=mlp.y_scale,
             meta=np.array(json.dumps(info)))
    return path


def read_npz(path: str | Path, kind: str, missing: str) -> tuple[dict[str, np.ndarray],
                                                                 dict[str, Any]]:
    """The arrays and JSON metadata of an ``.npz`` written with a ``kind``: :class:`ModelError`
    ``missing`` (+ the path) when there is no file, or naming what is wrong (unreadable,
    another kind)."""
    path = Path(path)
    if not path.is_file():
        raise ModelError(f"{missing} at {path}")
    try:
        with np.load(path, allow_pickle=False) as z:
            arrays = {k: z[k] for k in z.files}
        meta = json.loads(str(arrays.pop("meta")))
    except (OSError, ValueError, KeyError) as exc:
        raise ModelError(f"{path} is not a readable {kind} file: {exc}") from exc
    if meta.get("kind") != kind:
        raise ModelError(f"{path} holds a {meta.get('kind')!r}, expected {kind!r}")
    return arrays, meta


def load_model(path: str | Path, kind: str) -> tuple[TanhMlp, dict[str, Any]]:
    """The network and metadata saved at ``path``; :class:`ModelError` if the file is missing,
    unreadable, or holds another kind of model."""
    arrays, meta = read_npz(path, kind, f"no {kind} model file (train one first, or check "
                                        f"the path)")
    try:
        mlp = TanhMlp(arrays["sizes"], arrays["theta"], arrays["x_mean"], arrays["x_scale"],
                      arrays["y_mean"], arrays["y_scale"])
    except (ValueError, KeyError) as exc:
        raise ModelError(f"{path} is not a readable model file: {exc}") from exc
    return mlp, meta
