"""posture_publisher: publishes a named iCub posture as sensor_msgs/JointState.

The equivalent of ROS's joint_state_publisher for this robot: a source of /joint_states for
visualisation and for testing consumers without the simulator. Parameters: ``posture``
(a name from config/robot.yaml), ``rate_hz``, ``topic``. The posture can be changed at run
time (``posture`` parameter, validated).
"""

from __future__ import annotations

from rcl_interfaces.msg import ParameterDescriptor, SetParametersResult
from rclpy.node import Node
from sensor_msgs.msg import JointState

from icub_pmp.kinematics.robot_spec import RobotSpec
from icub_pmp.ros.conversions import make_joint_state
from icub_pmp.ros.node_runner import run_node

__all__ = ["PosturePublisher", "main"]


class PosturePublisher(Node):
    """Publish ``posture`` at ``rate_hz`` on ``topic``."""

    def __init__(self) -> None:
        super().__init__("posture_publisher")
        self.spec = RobotSpec.load()
        self.declare_parameter(
            "posture", "rest", ParameterDescriptor(description="named posture of robot.yaml")
        )
        self.declare_parameter("rate_hz", 100.0, ParameterDescriptor(description="[Hz]"))
        self.declare_parameter("topic", "joint_states", ParameterDescriptor(read_only=True))
        self.add_on_set_parameters_callback(self._on_set)
        self._posture = self.spec.posture(self.get_parameter("posture").value)
        rate = float(self.get_parameter("rate_hz").value)
        if not rate > 0:
            raise SystemExit(f"posture_publisher: rate_hz must be > 0, got {rate}")
        self.pub = self.create_publisher(JointState, self.get_parameter("topic").value, 10)
        self.timer = self.create_timer(1.0 / rate, self._tick)
        self.get_logger().info(
            f"publishing posture '{self.get_parameter('posture').value}' at {rate} Hz "
            f"on {self.pub.topic_name}"
        )

    def _on_set(self, params: list) -> SetParametersResult:
        for p in params:
            if p.name == "posture":
                if p.value not in self.spec.postures:
                    return SetParametersResult(
                        successful=False,
                        reason=f"unknown posture {p.value!r}; valid: {sorted(self.spec.postures)}",
                    )
                self._posture = self.spec.posture(p.value)
            elif p.name == "rate_hz" and not (isinstance(p.value, float) and p.value > 0):
                return SetParametersResult(successful=False, reason="rate_hz must be > 0.0")
            elif p.name == "rate_hz":
                self.timer.cancel()
                self.timer = self.create_timer(1.0 / p.value, self._tick)
        return SetParametersResult(successful=True)

    def _tick(self) -> None:
        names = list(self._posture)
        self.pub.publish(
            make_joint_state(
                names,
                position=[self._posture[n] for n in names],
                velocity=[0.0] * len(names),
                stamp=self.get_clock().now().to_msg(),
            )
        )


def main(args: list[str] | None = None) -> None:
    """Entry point (``ros2 run icub_pmp posture_publisher``)."""
    run_node(PosturePublisher, args, "posture_publisher")

if __name__ == "__main__":
    main()
