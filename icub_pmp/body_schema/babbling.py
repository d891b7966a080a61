"""MotorBabbling: random joint targets within the limits, and the samples they produced.

The body-schema paper acquires its models from "random motor babbling movements of a robotic
arm in its peripersonal space while the end-effector location is tracked through visual
perception" ("Acquisition of the Internal Body Model"). This core draws the targets (uniform
within the URDF limits, shrunk by ``limit_margin`` so the controller can reach them) for one
arm (7 joints) or torso + arm (10), collects what the robot perceived at each reached posture
(:class:`BabblingSample`), counts the postures whose marker was not seen, and writes the
dataset (:meth:`MotorBabbling.save`, ``.npz`` with a JSON metadata string).

What a learner may read: ``q`` (the babbled joints as measured), ``head`` (neck and eye joints),
``pixels`` (u_l, v_l, u_r, v_r) and ``hand_seen`` (the triangulated marker). ``ground_truth``
is the simulator's marker position, kept for evaluation only (:data:`LEARNER_FIELDS` lists the
others; :func:`load_dataset` returns them apart).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Mapping, NamedTuple, Sequence

import numpy as np

from icub_pmp.errors import InvalidInput

__all__ = ["MotorBabbling", "BabblingSample", "BabblingDataset", "load_dataset",
           "LEARNER_FIELDS", "HEAD_JOINTS", "min_jerk_move"]

#: the dataset fields a learner may use (everything but the ground truth)
LEARNER_FIELDS = ("q", "head", "pixels", "hand_seen", "t")
#: the head joints recorded with each sample (neck, then the eyes of eq 12)
HEAD_JOINTS = ("neck_pitch", "neck_roll", "neck_yaw", "eyes_tilt", "eyes_version",
               "eyes_vergence")


class BabblingSample(NamedTuple):
    """What the robot perceived at one babbled posture."""

    t: float  # stamp of the images [s] (simulated time)
    q: np.ndarray  # (n,) babbled joints, measured [rad]
    head: np.ndarray  # (6,) HEAD_JOINTS [rad]
    pixels: np.ndarray  # (4,) u_l, v_l, u_r, v_r [px]
    hand_seen: np.ndarray  # (3,) triangulated marker in root_link [m]
    ground_truth: np.ndarray  # (3,) the simulator's marker in root_link [m] (evaluation only)


class BabblingDataset(NamedTuple):
    """A dataset as loaded: the learner's arrays, the ground truth apart, the metadata."""

    learner: dict[str, np.ndarray]  # LEARNER_FIELDS -> arrays
    ground_truth: np.ndarray  # (n, 3) [m], evaluation only
    meta: dict[str, Any]


class MotorBabbling:
    """Targets and samples of one babbling run (module doc).

    Args:
        joint_names: the babbled joints (7 arm joints, or 3 torso + 7 arm).
        lower, upper: their limits [rad] (the URDF's).
        arm: 'left' | 'right' (kept in the metadata).
        seed: seed of the targets.
        limit_margin: fraction of each range kept clear at both ends.
    """

    def __init__(self, joint_names: Sequence[str], lower, upper, arm: str, seed: int = 0,
                 limit_margin: float = 0.05):
        self.joint_names = tuple(joint_names)
        n = len(self.joint_names)
        self.lower = np.array(lower, dtype=float).reshape(-1)
        self.upper = np.array(upper, dtype=float).reshape(-1)
        if n == 0 or self.lower.shape != (n,) or self.upper.shape != (n,) or np.any(
                self.upper <= self.lower):
            raise InvalidInput(f"babbling: expected {n} joint limits with lower < upper")
        if not 0.0 <= limit_margin < 0.5:
            raise InvalidInput(f"limit_margin: expected in [0, 0.5), got {limit_margin}")
        self.arm = arm
        self.margin = float(limit_margin)
        self._rng = np.random.default_rng(seed)
        self.samples: list[BabblingSample] = []
        self.attempts = 0
        self.dropped = 0
        self.drop_reasons: dict[str, int] = {}

    def next_target(self) -> np.ndarray:
        """A uniform random target (n,) [rad] within the limits (less the margin)."""
        span = self.upper - self.lower
        return self._rng.uniform(self.lower + self.margin * span, self.upper - self.margin * span)

    def record(self, sample: BabblingSample) -> None:
        """Keep a sample (its arrays are checked: finite, the right sizes)."""
        n = len(self.joint_names)
        shapes = {"q": n, "head": len(HEAD_JOINTS), "pixels": 4, "hand_seen": 3,
                  "ground_truth": 3}
        for name, size in shapes.items():
            v = np.asarray(getattr(sample, name), dtype=float)
            if v.shape != (size,) or not np.all(np.isfinite(v)):
                raise InvalidInput(f"babbling sample {name}: expected {size} finite values, "
                                   f"got {v.tolist()}")
        self.attempts += 1
        self.samples.append(BabblingSample(
            float(sample.t), *(np.asarray(getattr(sample, f), dtype=float).copy()
                               for f in BabblingSample._fields[1:])))

    def drop(self, reason: str) -> None:
        """Count a posture whose sample was not kept, by ``reason`` (e.g. 'marker not seen')."""
        self.attempts += 1
        self.dropped += 1
        self.drop_reasons[reason] = self.drop_reasons.get(reason, 0) + 1

    @property
    def visible_fraction(self) -> float:
        """Kept samples / attempts (0 before the first attempt)."""
        return len(self.samples) / self.attempts if self.attempts else 0.0

    def arrays(self) -> dict[str, np.ndarray]:
        """The samples as arrays: LEARNER_FIELDS and ``ground_truth``."""
        n = len(self.joint_names)
        out = {"t": np.array([s.t for s in self.samples], dtype=float)}
        for name, size in (("q", n), ("head", len(HEAD_JOINTS)), ("pixels", 4),
                           ("hand_seen", 3), ("ground_truth", 3)):
            out[name] = np.array([getattr(s, name) for s in self.samples],
                                 dtype=float).reshape(-1, size)
        return out

    def save(self, path: str | Path, meta: Mapping[str, Any] | None = None) -> Path:
        """Write the dataset (``.npz``: the arrays + JSON metadata); parent folders made."""
        path = Path(path)
        if path.suffix != ".npz":
            path = path.with_suffix(path.suffix + ".npz")
        path.parent.mkdir(parents=True, exist_ok=True)
        info = dict(meta or {})
        info.update(kind="babbling_dataset", arm=self.arm, joint_names=list(self.joint_names),
                    lower=self.lower.tolist(), upper=self.upper.tolist(),
                    head_joints=list(HEAD_JOINTS), samples=len(self.samples),
                    attempts=self.attempts, dropped=self.dropped,
                    drop_reasons=self.drop_reasons, learner_fields=list(LEARNER_FIELDS),
                    evaluation_only=["ground_truth"])
        np.savez(path, meta=np.array(json.dumps(info)), **self.arrays())
        return path


def load_dataset(path: str | Path) -> BabblingDataset:
    """Read a dataset written by :meth:`MotorBabbling.save`: the learner's arrays and the
    ground truth apart (:class:`ModelError` for a missing or foreign file)."""
    from icub_pmp.body_schema.model_file import read_npz

    arrays, meta = read_npz(path, "babbling_dataset", "no babbling dataset")
    learner = {k: arrays[k] for k in LEARNER_FIELDS}
    return BabblingDataset(learner, arrays["ground_truth"], meta)


def min_jerk_move(q0: np.ndarray, q1: np.ndarray, velocity_limit: np.ndarray,
                  acceleration_limit: np.ndarray, min_time: float, points: int = 21,
                  usage: float = 0.7) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A minimum-jerk joint move q0 -> q1 sampled at ``points`` times: ``(t (k,), q (k, n),
    qd (k, n))``. Its duration is ``min_time`` [s] or longer, so the peak velocity (1.875 d/T)
    and acceleration (5.774 d/T^2) stay within ``usage`` of the limits [rad/s, rad/s^2]."""
    q0 = np.asarray(q0, dtype=float)
    d = np.asarray(q1, dtype=float) - q0
    a = np.abs(d)
    t_vel = float(np.max(1.875 * a / (usage * np.asarray(velocity_limit, dtype=float))))
    t_acc = float(np.sqrt(np.max(5.774 * a / (usage * np.asarray(acceleration_limit,
                                                                   dtype=float)))))
    T = max(float(min_time), t_vel, t_acc)
    t = np.linspace(0.0, T, max(int(points), 2))
    s = t / T
    shape = 10 * s ** 3 - 15 * s ** 4 + 6 * s ** 5
    rate = (30 * s ** 2 - 60 * s ** 3 + 30 * s ** 4) / T
    return t, q0 + shape[:, None] * d, rate[:, None] * d
