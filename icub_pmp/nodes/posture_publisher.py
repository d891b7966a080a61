"""posture_publisher: publishes a named iCub posture as sensor_msgs/JointState.

The equivalent of ROS's joint_state_publisher for this robot: a source of /joint_states for
visualisation and for testing consumers without the simulator. Parameters: ``posture``
(a name from config/robot.yaml), ``rate_hz``, ``topic``
(:class:`~icub_pmp.ros.posture_publisher_config.PosturePublisherConfig`). The posture and the
rate can be changed at run time (validated).
"""

from __future__ import annotations

from rclpy.node import Node
from sensor_msgs.msg import JointState

from icub_pmp.kinematics.robot_spec import RobotSpec
from icub_pmp.ros.conversions import make_joint_state
from icub_pmp.ros.node_runner import run_node
from icub_pmp.ros.parameters import ConfigParameters
from icub_pmp.ros.posture_publisher_config import PosturePublisherConfig

__all__ = ["PosturePublisher", "main"]


class PosturePublisher(Node):
    """Publish ``posture`` at ``rate_hz`` on ``topic``."""

    def __init__(self) -> None:
        super().__init__("posture_publisher")
        self.spec = RobotSpec.load()
        self.params = ConfigParameters(
            self, PosturePublisherConfig, read_only=("topic",),
            check=lambda c: self.spec.posture(c.posture), on_change=self._on_change)
        cfg = self.params.config
        self._posture = self.spec.posture(cfg.posture)
        self.pub = self.create_publisher(JointState, cfg.topic, 10)
        self.timer = self.create_timer(1.0 / cfg.rate_hz, self._tick)
        self.get_logger().info(
            f"publishing posture '{cfg.posture}' at {cfg.rate_hz} Hz on {self.pub.topic_name}"
        )

    def _on_change(self, old: PosturePublisherConfig, new: PosturePublisherConfig,
                   changed: frozenset[str]) -> None:
        self._posture = self.spec.posture(new.posture)
        if new.rate_hz != old.rate_hz:
            self.timer.cancel()
            self.timer = self.create_timer(1.0 / new.rate_hz, self._tick)

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
