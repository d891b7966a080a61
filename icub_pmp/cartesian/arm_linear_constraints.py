"""ArmLinearConstraints: the iCub shoulder tendon and forearm limits as ``lb <= C q <= ub``.

The reaching paper (Sect. 4, item 5) adds "a set of constraints that avoid reaching the limits
of the tendons that actuate the three joints of the shoulder". These are the seven linear
inequalities iKin adds to every iCub arm chain (``iCubAdditionalArmConstraints``; numbers from
icub-main iKinFwd.cpp iCubAdditionalArmConstraints and the icub-tech page "Range of Motion of
the iCub Shoulders"), in
the URDF joint angles q0 shoulder_pitch, q1 shoulder_roll, q2 shoulder_yaw, q3 elbow,
q4 wrist_prosup (same signs on both arms):

1. ``1.71 (q0 - q1) >= -347 deg``                       (tendon length)
2. ``-366.57 deg <= 1.71 (q0 - q1 - q2) <= 112.42 deg``  (tendon length)
3. ``-66.6 deg <= q1 + q2 <= 213.3 deg``                 (tendon length)
4. ``q1 + 0.0427 q2 >= 26.4 deg``                        (upper arm vs torso collision)
5. ``q1 <= 100 deg``                                     (maximum abduction)
6. ``2.5 q3 + q4 <= 302.5 deg``                          (forearm vs upper arm)
7. ``q4 - 2.5 q3 >= -302.5 deg``                         (forearm vs upper arm)
"""

from __future__ import annotations

import math
from typing import NamedTuple, Sequence

import numpy as np

from icub_pmp.errors import InvalidInput, UnknownName

__all__ = ["ArmLinearConstraints", "LinearConstraints"]

_D = math.pi / 180.0
_INF = math.inf
# rows over (q0 .. q4) of one arm; bounds in deg
_ROWS = (
    ((1.71, -1.71, 0.0, 0.0, 0.0), -347.0, _INF),
    ((1.71, -1.71, -1.71, 0.0, 0.0), -366.57, 112.42),
    ((0.0, 1.0, 1.0, 0.0, 0.0), -66.6, 213.3),
    ((0.0, 1.0, 0.0427, 0.0, 0.0), 26.4, _INF),
    ((0.0, 1.0, 0.0, 0.0, 0.0), -_INF, 100.0),
    ((0.0, 0.0, 0.0, 2.5, 1.0), -_INF, 302.5),
    ((0.0, 0.0, 0.0, -2.5, 1.0), -302.5, _INF),
)
_SUFFIXES = ("shoulder_pitch", "shoulder_roll", "shoulder_yaw", "elbow", "wrist_prosup")


class LinearConstraints(NamedTuple):
    """``lb <= C q <= ub`` over a given joint list; C (m, n), lb/ub (m,) [rad] (+-inf = none)."""

    C: np.ndarray
    lb: np.ndarray
    ub: np.ndarray


class ArmLinearConstraints:
    """The seven iKin arm constraints of one hand ('left' or 'right')."""

    def __init__(self, hand: str):
        if hand not in ("left", "right"):
            raise UnknownName("hand", hand, ("left", "right"))
        self.hand = hand
        prefix = "l_" if hand == "left" else "r_"
        self.arm_joints = tuple(prefix + s for s in _SUFFIXES)

    def over(self, joints: Sequence[str]) -> LinearConstraints:
        """The constraints with columns in the order of ``joints`` (must contain q0..q4)."""
        joints = list(joints)
        missing = [j for j in self.arm_joints if j not in joints]
        if missing:
            raise InvalidInput(f"ArmLinearConstraints({self.hand}): joints lack {missing}")
        C = np.zeros((len(_ROWS), len(joints)))
        lb = np.empty(len(_ROWS))
        ub = np.empty(len(_ROWS))
        for i, (row, lo, hi) in enumerate(_ROWS):
            for coef, name in zip(row, self.arm_joints):
                C[i, joints.index(name)] = coef
            lb[i] = lo * _D
            ub[i] = hi * _D
        for a in (C, lb, ub):
            a.setflags(write=False)
        return LinearConstraints(C, lb, ub)

    def violation(self, joints: Sequence[str], q: np.ndarray) -> float:
        """Largest violation [rad] of the constraints at ``q`` (ordered as ``joints``); 0 if met."""
        c = self.over(joints)
        v = c.C @ np.asarray(q, dtype=float)
        return float(max(0.0, np.max(c.lb - v), np.max(v - c.ub)))
