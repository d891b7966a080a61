"""TorqueWatch: every /effort_command the controller publishes, checked against the joints'
torque limits (config/robot.yaml)."""

from __future__ import annotations

import math
import threading

from icub_pmp.kinematics.robot_spec import RobotSpec
from icub_pmp.ros.probe import RosProbe

__all__ = ["TorqueWatch"]


class TorqueWatch:
    """Subscribes to ``topic`` on ``probe`` and counts commands beyond the limits.

    ``messages``: commands seen; ``violations``: commands with a torque beyond its joint's
    limit [N m] (more than ``tolerance`` [N m] over it), non-finite, or naming an unknown
    joint; ``worst``: the largest |torque| / limit seen; ``examples``: a few violations.
    :meth:`pause` stops counting (e.g. while a test itself publishes on the topic).
    """

    def __init__(self, probe: RosProbe, topic: str = "/effort_command",
                 tolerance: float = 1e-6):
        from rclpy.qos import qos_profile_sensor_data
        from sensor_msgs.msg import JointState

        spec = RobotSpec.load()
        self.limits = {j: spec.torque_limit(j) for j in spec.actuated_joints}
        self.tolerance = tolerance
        self.messages = 0
        self.violations = 0
        self.worst = 0.0
        self.examples: list[str] = []
        self.counting = True
        self._lock = threading.Lock()
        self.sub = probe.node.create_subscription(JointState, topic, self._on_command,
                                                  qos_profile_sensor_data)

    def _on_command(self, msg: object) -> None:
        if not self.counting:
            return
        bad: list[str] = []
        worst = 0.0
        for name, tau in zip(msg.name, msg.effort):  # type: ignore[attr-defined]
            limit = self.limits.get(name)
            if limit is None or not math.isfinite(tau):
                bad.append(f"{name}={tau}")
                continue
            worst = max(worst, abs(tau) / limit)
            if abs(tau) > limit + self.tolerance:
                bad.append(f"{name}={tau:.3f} (limit {limit})")
        with self._lock:
            self.messages += 1
            self.worst = max(self.worst, worst)
            if bad:
                self.violations += 1
                if len(self.examples) < 5:
                    self.examples.append(", ".join(bad[:4]))

    def pause(self) -> None:
        """Stop counting."""
        self.counting = False
