"""EyeHandMap: the learned map from what the eyes see to where the hand is (force paper eq 12).

``(x, y, z)_H = M(u_l, v_l, u_r, v_r, T, V_s, V_g)``: the hand's pixel coordinates in the left
and right images [px] and the eyes' tilt, pan (version) and vergence [rad] to the hand position
[m] in the head-centred frame. As in the paper (Sect. 4): 7 linear inputs, 50 tanh hidden
units, 3 linear outputs, trained on babbling data (:class:`TanhMlp` + :class:`LmTrainer`).
A learned map absorbs whatever the camera calibration gets wrong; geometric triangulation
with a nominal camera model does not.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from icub_pmp.body_schema.lm_trainer import LmTrainer, TrainingReport, check_dataset
from icub_pmp.body_schema.model_file import load_model, save_model
from icub_pmp.body_schema.tanh_mlp import TanhMlp
from icub_pmp.errors import InvalidInput

__all__ = ["EyeHandMap", "EYE_HAND_INPUTS", "DEFAULT_EYE_HAND_HIDDEN"]

#: eq 12's inputs, in order
EYE_HAND_INPUTS = ("u_l", "v_l", "u_r", "v_r", "eyes_tilt", "eyes_version", "eyes_vergence")
#: the paper's hidden layer (50 tanh units)
DEFAULT_EYE_HAND_HIDDEN = (50,)
KIND = "eye_hand_map"


class EyeHandMap:
    """Eq 12 of the force paper as a trained network (module doc).

    Args:
        mlp: the trained network (7 -> 3).
        frame: the head-centred frame of the outputs.
        info: provenance kept in the saved file.
        camera: the camera setup the pixels come from ({width, height [px], fx, fy [px]};
            empty: unknown). A map only holds for the cameras it was learned with.
    """

    def __init__(self, mlp: TanhMlp, frame: str, info: Mapping[str, Any] | None = None,
                 camera: Mapping[str, float] | None = None):
        if mlp.n_in != len(EYE_HAND_INPUTS) or mlp.n_out != 3:
            raise InvalidInput(f"eye-hand map: expected 7 inputs -> 3 outputs, got "
                               f"{mlp.n_in} -> {mlp.n_out}")
        self.mlp = mlp
        self.frame = str(frame)
        self.info = dict(info or {})
        self.camera = {str(k): float(v) for k, v in (camera or {}).items()}

    @classmethod
    def train(cls, inputs: np.ndarray, hand: np.ndarray, frame: str,
              hidden: Sequence[int] = DEFAULT_EYE_HAND_HIDDEN,
              trainer: LmTrainer | None = None, camera: Mapping[str, float] | None = None
              ) -> tuple["EyeHandMap", TrainingReport]:
        """Fit eq 12 on ``inputs`` (n, 7) in :data:`EYE_HAND_INPUTS` order and hand positions
        (n, 3) [m] in ``frame``; ``camera`` names the camera setup (class doc)."""
        inputs, hand = check_dataset(inputs, hand, len(EYE_HAND_INPUTS), 3)
        trainer = trainer or LmTrainer()
        mlp, report = trainer.fit(tuple(hidden), inputs, hand)
        info = {"samples": len(inputs), "train_rmse_m": report.rmse, "train_s": report.seconds,
                "method": trainer.config.method}
        return cls(mlp, frame, info, camera), report

    def locate(self, inputs: np.ndarray) -> np.ndarray:
        """Hand position(s) [m] in :attr:`frame`: (3,) for one input (7,), (n, 3) for (n, 7)."""
        x = np.asarray(inputs, dtype=float)
        if x.shape[-1:] != (len(EYE_HAND_INPUTS),) or x.ndim > 2:
            raise InvalidInput(f"eye-hand inputs: expected (n, 7) or (7,) as "
                               f"{EYE_HAND_INPUTS}, got {x.shape}")
        if not np.all(np.isfinite(x)):
            raise InvalidInput("eye-hand inputs: contain NaN or infinite values")
        return self.mlp.predict(x)

    def save(self, path: str | Path) -> Path:
        """Write the map to ``path`` (.npz)."""
        meta = {"frame": self.frame, "inputs": list(EYE_HAND_INPUTS),
                "hidden": list(self.mlp.hidden), "info": self.info, "camera": self.camera}
        return save_model(path, self.mlp, KIND, meta)

    @classmethod
    def load(cls, path: str | Path) -> "EyeHandMap":
        """Read a map saved by :meth:`save` (:class:`ModelError` if missing or not a map)."""
        mlp, meta = load_model(path, KIND)
        return cls(mlp, meta.get("frame", "head"), meta.get("info"), meta.get("camera"))
