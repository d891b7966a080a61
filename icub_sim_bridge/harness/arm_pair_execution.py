"""Two imagined reaches executed in parallel in the physics, to judge the imagined collision
check (Bhat and Mohan 2018, "collision detection follows": the distal joints of both arms
compared along the anticipated trajectories; on the iCub also the arms' link hulls).

:func:`shared_target_pairs` draws target pairs from the two arms' shared workspace (above the
table); :func:`execute_pair` runs both arms' PMP joint trajectories together on the in-process
simulator harness (:class:`SimLoop`: MuJoCo with the arms colliding, the impedance controller
core at 1 kHz; the table's objects moved away) and reports whether an arm-arm contact
appeared; :func:`recall_precision` scores predictions against it. Used by
``bench/peripersonal.py`` and the paper report (``body_schema_imagined_collisions``).
"""

from __future__ import annotations

from typing import Any, Mapping

import numpy as np

from icub_pmp.control.joint_trajectory import JointTrajectory
from icub_pmp.control.trajectory_limits import JointRateLimits, scale_trajectory_time
from icub_pmp.kinematics.robot_spec import HANDS
from icub_sim_bridge.harness.sim_loop import SimLoop

__all__ = ["shared_target_pairs", "execute_pair", "send_plans", "recall_precision", "PAIR_Z_MIN"]

#: lowest target [m, root_link]: 6 cm above the table top (z = -0.09)
PAIR_Z_MIN = -0.03


def shared_target_pairs(space: Any, n: int, seed: int, z_min: float = PAIR_Z_MIN
                        ) -> np.ndarray:
    """(n, 2, 3) targets [m]: left from the left map's shared neurons, right from the right
    map's (``space``: a :class:`~icub_pmp.peripersonal.PeripersonalSpace`), above ``z_min``."""
    rng = np.random.default_rng(seed)
    pts = {}
    for arm in HANDS:
        p = space.shared.points(arm)
        pts[arm] = p[p[:, 2] >= z_min]
    i = rng.integers(0, len(pts["left"]), n)
    j = rng.integers(0, len(pts["right"]), n)
    return np.stack([pts["left"][i], pts["right"][j]], axis=1)


def send_plans(loop: SimLoop, plans: Mapping[str, Any]) -> tuple[float, float]:
    """Hand the arms' imagined reaches (``plans``: arm -> ReachPlan) to the controller core
    now, all slowed down by one factor to the joints' rate limits where needed (as the
    planner does before execution: the same paths, in step with each other as imagined).
    Returns (the longest scaled duration [s], the factor)."""
    ctl = loop.controller
    limits = JointRateLimits.from_spec(loop.sim.spec)
    scale = max(limits.report(JointTrajectory(p.joint_names, np.asarray(p.t), p.positions,
                                              np.asarray(p.velocities))).time_scale
                for p in plans.values())
    scale = scale * 1.01 if scale > 1.0 + 1e-3 else 1.0
    t0 = loop.t
    for p in plans.values():
        times, vel, _ = scale_trajectory_time(np.asarray(p.t), np.asarray(p.velocities), None,
                                              scale)
        ctl.set_trajectory(ctl.make_trajectory(p.joint_names, times, p.positions, vel,
                                               start=t0), t0)
    return max(p.tau for p in plans.values()) * scale, scale


def execute_pair(loop: SimLoop, plans: Mapping[str, Any], settle: float) -> dict:
    """Run both imagined reaches (``plans``: arm -> ReachPlan with joint_names, t, positions,
    velocities, tau) in parallel through the controller from the rest posture, both slowed
    down by one factor to the joints' rate limits where needed, for the longer tau +
    ``settle`` [s]: {collided, first_contact_s, bodies (arm-arm), arm_torso, time_scale}."""
    sim, ctl = loop.sim, loop.controller
    sim.reset("rest")
    for name, pos in (("box", (0.6, 0.4, -0.55)), ("cylinder", (0.6, -0.4, -0.55))):
        sim.set_object_pose(name, pos)  # off the table, on the floor behind the robot
    js = sim.joint_state()
    ctl.step(js.time, js.position, js.velocity)  # the controller sees the reset posture ...
    ctl.hold()  # ... and holds it (no set-point left from the previous pair)
    t0 = loop.t
    duration, scale = send_plans(loop, plans)
    duration += settle
    first, bodies, other = None, set(), set()
    for _ in range(int(round(duration / sim.config.timestep))):
        loop.step()
        if sim.data.ncon:
            for c in sim.self_contacts():
                if c.kind == "arm-arm":
                    if first is None:
                        first = loop.t - t0
                    bodies.add((c.body1, c.body2))
                else:
                    other.add((c.body1, c.body2))
    return {"collided": first is not None, "first_contact_s": first,
            "bodies": sorted(bodies), "arm_torso": sorted(other), "time_scale": scale}


def recall_precision(pred: np.ndarray, truth: np.ndarray) -> tuple[float | None, float | None]:
    """(recall, precision) of boolean predictions against the physics; None when undefined
    (no positives)."""
    pred, truth = np.asarray(pred, bool), np.asarray(truth, bool)
    tp = int(np.sum(pred & truth))
    recall = tp / int(truth.sum()) if truth.any() else None
    precision = tp / int(pred.sum()) if pred.any() else None
    return recall, precision
