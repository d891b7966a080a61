"""GazeSolution: the head posture that fixates a point, with its predicted fixation error."""

from __future__ import annotations

import dataclasses

import numpy as np

__all__ = ["GazeSolution", "GAZE_JOINTS"]

#: the six head joints the gaze controller moves, in the order of its vectors.
GAZE_JOINTS = ("neck_pitch", "neck_roll", "neck_yaw", "eyes_tilt", "eyes_version",
               "eyes_vergence")


@dataclasses.dataclass(frozen=True)
class GazeSolution:
    """Attributes:
        target: fixation point (3,) in root_link [m].
        neck: neck pitch, roll, yaw (3,) [rad].
        eyes: eye tilt, version, vergence (3,) [rad] (within the limits).
        fixation_errors: predicted angle between each optical axis and the direction to the
            target at this posture (2,) left, right [rad].
        neck_pointing_error: angle between the head-centre z axis and the target [rad].
        exact: both fixation errors are within the controller's ``fixation_tolerance``.
        clipped: joints whose exact value lies beyond their limit (the solution is clipped).
        neck_solved: False when a tracking update kept the previous neck target (the target
            moved less than ``neck_activation_angle``).
    """

    target: np.ndarray
    neck: np.ndarray
    eyes: np.ndarray
    fixation_errors: np.ndarray
    neck_pointing_error: float
    exact: bool
    clipped: tuple[str, ...]
    neck_solved: bool = True

    def __post_init__(self) -> None:
        for name in ("target", "neck", "eyes", "fixation_errors"):
            a = np.array(getattr(self, name), dtype=float)
            a.setflags(write=False)
            object.__setattr__(self, name, a)

    @property
    def positions(self) -> np.ndarray:
        """Joint targets (6,) [rad] in :data:`GAZE_JOINTS` order."""
        return np.concatenate((self.neck, self.eyes))

    @property
    def joints(self) -> dict[str, float]:
        """{joint: target [rad]} of the six head joints."""
        return dict(zip(GAZE_JOINTS, (float(v) for v in self.positions)))

    @property
    def fixation_error(self) -> float:
        """The larger of the two eyes' fixation errors [rad]."""
        return float(self.fixation_errors.max())
