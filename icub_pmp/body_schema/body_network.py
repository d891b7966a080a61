"""BodyNetwork: the learned body model of one arm, joint angles -> hand position (eqs 1-2).

The body-schema paper's internal model of the body (Bhat and Mohan, "Internal Body Model",
eq 1): a feed-forward network with two tanh hidden layers (32 and 41 units) and a linear
output maps the arm's joint angles q to the hand position s, trained on babbling data; the
Jacobian J(q) = ds/dq PMP relaxes on is read off the weights by the chain rule (eq 2). Here
the network is a :class:`TanhMlp` trained by Levenberg-Marquardt (:class:`LmTrainer`), the
inputs are the arm's 7 joints, or the 3 torso joints + the arm's 7 (10 inputs), and the output
is the hand marker's position [m] in the frame the data were measured in (``root_link``).

The model keeps what it was learned on: the arm, the input joints, their limits [rad], the
joints held fixed during babbling ({joint: angle}) and the training provenance.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping, NamedTuple, Sequence

import numpy as np

from icub_pmp.body_schema.lm_trainer import LmTrainer, TrainingReport, check_dataset
from icub_pmp.body_schema.model_file import load_model, save_model
from icub_pmp.body_schema.tanh_mlp import TanhMlp
from icub_pmp.errors import InvalidInput, ModelError, UnknownName
from icub_pmp.kinematics.robot_spec import HANDS

__all__ = ["BodyNetwork", "BodyPrediction", "DEFAULT_HIDDEN"]

#: the paper's hidden layer sizes (Fig. 2b: 32 and 41 tanh units)
DEFAULT_HIDDEN = (32, 41)
KIND = "body_network"


class BodyPrediction(NamedTuple):
    """Hand positions and Jacobians of a batch of postures."""

    positions: np.ndarray  # (n, 3) [m]
    jacobians: np.ndarray  # (n, 3, n_in) [m/rad], eq 2


class BodyNetwork:
    """Learned forward kinematics of one arm (module doc).

    Args:
        mlp: the trained network (n_in -> 3).
        arm: 'left' | 'right'.
        joint_names: the input joints, the columns of ``q`` (n_in,).
        lower, upper: their limits (n_in,) [rad] (the babbling range).
        frame: the end-effector frame the outputs stand for (e.g. ``r_hand_dh_frame``).
        fixed: joints held still while babbling, {joint: angle [rad]}.
        info: provenance (samples, training error, trainer), kept in the saved file.
    """

    def __init__(self, mlp: TanhMlp, arm: str, joint_names: Sequence[str], lower, upper,
                 frame: str, fixed: Mapping[str, float] | None = None,
                 info: Mapping[str, Any] | None = None):
        if arm not in HANDS:
            raise UnknownName("arm", arm, HANDS)
        self.joint_names = tuple(joint_names)
        if mlp.n_in != len(self.joint_names) or mlp.n_out != 3:
            raise InvalidInput(f"body network: expected {len(self.joint_names)} inputs -> 3 "
                               f"outputs, got {mlp.n_in} -> {mlp.n_out}")
        self.mlp = mlp
        self.arm = arm
        self.lower = np.array(lower, dtype=float).reshape(-1)
        self.upper = np.array(upper, dtype=float).reshape(-1)
        if self.lower.shape != (mlp.n_in,) or self.upper.shape != (mlp.n_in,) or np.any(
                self.upper < self.lower):
            raise InvalidInput(f"joint limits: expected {mlp.n_in} pairs lower <= upper")
        self.lower.setflags(write=False)
        self.upper.setflags(write=False)
        self.frame = str(frame)
        self.fixed = {str(k): float(v) for k, v in (fixed or {}).items()}
        self.info = dict(info or {})

    @property
    def hidden(self) -> tuple[int, ...]:
        """Hidden layer sizes."""
        return self.mlp.hidden

    # ------------------------------------------------------------------ training
    @classmethod
    def train(cls, arm: str, joint_names: Sequence[str], q: np.ndarray, hand: np.ndarray,
              lower, upper, frame: str, hidden: Sequence[int] = DEFAULT_HIDDEN,
              trainer: LmTrainer | None = None, fixed: Mapping[str, float] | None = None,
              initial: "BodyNetwork | None" = None) -> tuple["BodyNetwork", TrainingReport]:
        """Fit a body network to babbled postures ``q`` (n, n_in) [rad] and observed hand
        positions ``hand`` (n, 3) [m] (eq 1); ``initial`` continues from a trained model
        (online adaptation: its weights and normalisation are the starting point)."""
        q, hand = check_dataset(q, hand, len(tuple(joint_names)), 3)
        trainer = trainer or LmTrainer()
        if initial is not None and tuple(initial.joint_names) != tuple(joint_names):
            raise InvalidInput(f"initial model has joints {initial.joint_names}, data "
                               f"{tuple(joint_names)}")
        mlp, report = trainer.fit(tuple(hidden), q, hand,
                                  initial=initial.mlp if initial is not None else None)
        info = {"samples": len(q), "train_rmse_m": report.rmse, "train_s": report.seconds,
                "method": trainer.config.method, "evaluations": report.evaluations}
        return cls(mlp, arm, joint_names, lower, upper, frame, fixed, info), report

    # ------------------------------------------------------------------ evaluation
    def _q(self, q: np.ndarray) -> tuple[np.ndarray, bool]:
        q = np.asarray(q, dtype=float)
        single = q.ndim == 1
        q2 = q[None] if single else q
        if q2.ndim != 2 or q2.shape[1] != len(self.joint_names):
            raise InvalidInput(f"q: expected (n, {len(self.joint_names)}) joint angles "
                               f"{self.joint_names}, got {q.shape}")
        if not np.all(np.isfinite(q2)):
            raise InvalidInput("q: contains NaN or infinite joint angles")
        return q2, single

    def position(self, q: np.ndarray) -> np.ndarray:
        """Hand position(s) [m]: (3,) for one posture (n_in,), (n, 3) for (n, n_in) (eq 1)."""
        q2, single = self._q(q)
        s = self.mlp.predict(q2)
        return s[0] if single else s

    def jacobian(self, q: np.ndarray) -> BodyPrediction:
        """Positions and J(q) = ds/dq by the chain rule through the weights (eq 2), for a batch
        (n, n_in) (a single posture gives n = 1)."""
        q2, _ = self._q(q)
        s, jac = self.mlp.input_jacobian(q2)
        return BodyPrediction(s, jac)

    # ------------------------------------------------------------------ files
    def save(self, path: str | Path) -> Path:
        """Write the model (weights, normalisation, metadata) to ``path`` (.npz)."""
        meta = {"arm": self.arm, "joint_names": list(self.joint_names),
                "lower": self.lower.tolist(), "upper": self.upper.tolist(),
                "frame": self.frame, "fixed": self.fixed, "hidden": list(self.hidden),
                "info": self.info}
        return save_model(path, self.mlp, KIND, meta)

    @classmethod
    def load(cls, path: str | Path, arm: str | None = None) -> "BodyNetwork":
        """Read a model saved by :meth:`save`; with ``arm``, a model of another arm is a
        :class:`ModelError` naming both."""
        mlp, meta = load_model(path, KIND)
        if arm is not None and meta.get("arm") != arm:
            raise ModelError(f"{path} is a body model of the {meta.get('arm')} arm, "
                             f"not of the {arm} arm")
        try:
            return cls(mlp, meta["arm"], meta["joint_names"], meta["lower"], meta["upper"],
                       meta["frame"], meta.get("fixed"), meta.get("info"))
        except KeyError as exc:
            raise ModelError(f"{path}: body model metadata lacks {exc}") from exc
