"""Motor babbling on a body model: random arm postures and the hand positions they give.

The paper's robots babble to random locations and observe the end effector ("Acquisition of
the peripersonal representation", step b). Here a posture is drawn uniformly within the
arm's joint limits (the other joints at the rest posture) and the hand position comes from
the body model's forward kinematics (the iCub URDF through pinocchio by default, or any
:class:`~icub_pmp.pmp.JacobianProvider`). A learned body schema's babbling dataset can be
used instead: the maps only need the hand positions (n, 3).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from icub_pmp.errors import InvalidInput, UnknownName
from icub_pmp.kinematics.robot_spec import HANDS, RobotSpec
from icub_pmp.pmp.jacobian_provider import JacobianProvider

__all__ = ["Babbling", "analytic_babbling"]


class Babbling(NamedTuple):
    """Babbled postures of one arm and the resulting hand positions."""

    arm: str
    joint_names: tuple[str, ...]  # the arm's joints, the columns of ``q``
    q: np.ndarray  # (n, 7) [rad]
    hand: np.ndarray  # (n, 3) [m] hand frame origin in root_link


def analytic_babbling(arm: str, n: int, seed: int, provider: JacobianProvider | None = None,
                      spec: RobotSpec | None = None) -> Babbling:
    """``n`` uniform random postures of ``arm`` ('left' | 'right') within the body model's
    joint limits, trunk and other arm at the rest posture, and their hand positions."""
    if arm not in HANDS:
        raise UnknownName("arm", arm, HANDS)
    if int(n) < 1:
        raise InvalidInput(f"n: expected at least 1 babble, got {n}")
    spec = spec or RobotSpec.load()
    if provider is None:
        from icub_pmp.pmp.pinocchio_provider import PinocchioJacobianProvider

        provider = PinocchioJacobianProvider()
    names = provider.joint_names
    joints = spec.arm_joints(arm)
    for j in joints:
        if j not in names:
            raise UnknownName("joint of the body model", j, names)
    idx = [names.index(j) for j in joints]
    rest = spec.posture("rest")
    q0 = np.array([rest.get(j, 0.0) for j in names])
    rng = np.random.default_rng(seed)
    q = rng.uniform(provider.lower[idx], provider.upper[idx], size=(int(n), len(idx)))
    frame = [spec.hand_frame(arm)]
    full = q0.copy()
    hand = np.empty((int(n), 3))
    for k in range(int(n)):
        full[idx] = q[k]
        hand[k] = provider.positions(full, frame)[0]
    return Babbling(arm, tuple(joints), q, hand)
