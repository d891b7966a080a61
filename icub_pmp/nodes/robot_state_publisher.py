"""robot_state_publisher: the iCub URDF and link transforms for Foxglove and bags.

The job of ROS's ``robot_state_publisher`` (not on PyPI), computed with pinocchio from the same
icub-models URDF (:class:`~icub_pmp.kinematics.link_transforms.LinkTransforms`):

- ``/robot_description`` (std_msgs/String, reliable + transient local = latched): the URDF;
- ``/tf_static`` (tf2_msgs/TFMessage, latched): every fixed joint and the locked legs, once;
- ``/tf`` (tf2_msgs/TFMessage, reliable depth 100): the 20 upper-body joints from
  ``/joint_states``, stamped with the joint state's stamp, at most ``publish_frequency`` Hz.

Joint states are taken raw and decoded only when a /tf message is due, so a 1 kHz stream costs
little. A malformed joint state is dropped with a throttled warning. Joints missing from a
message keep their last value (eye joints, which the URDF lacks, are ignored).
"""

from __future__ import annotations

import time

from geometry_msgs.msg import TransformStamped
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy, qos_profile_sensor_data
from rclpy.serialization import deserialize_message
from sensor_msgs.msg import JointState
from std_msgs.msg import String
from tf2_msgs.msg import TFMessage

from icub_pmp.errors import IcubPmpError
from icub_pmp.kinematics.link_transforms import LinkTransform, LinkTransforms
from icub_pmp.ros.conversions import joint_state_field, validate_joint_state
from icub_pmp.ros.node_runner import spin_node
from icub_pmp.ros.parameters import ConfigParameters
from icub_pmp.ros.robot_state_publisher_config import RobotStatePublisherConfig

__all__ = ["RobotStatePublisher", "main", "LATCHED_QOS", "TF_QOS"]

LATCHED_QOS = QoSProfile(
    depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL
)
TF_QOS = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)


def _transform_msg(t: LinkTransform, stamp) -> TransformStamped:
    msg = TransformStamped()
    msg.header.stamp = stamp
    msg.header.frame_id = t.parent
    msg.child_frame_id = t.child
    tr, q = msg.transform.translation, msg.transform.rotation
    tr.x, tr.y, tr.z = (float(v) for v in t.translation)
    q.x, q.y, q.z, q.w = (float(v) for v in t.quat_xyzw)
    return msg


class RobotStatePublisher(Node):
    """Publish /robot_description, /tf_static once and /tf from /joint_states."""

    def __init__(self) -> None:
        super().__init__("robot_state_publisher")
        self.params = ConfigParameters(self, RobotStatePublisherConfig, read_only=("mesh_uris",))
        self.links = LinkTransforms()
        self._q = self.links.model.posture("zero")
        self._next_tf = 0.0  # monotonic time [s] from which the next /tf is due
        self._valid = set(self.links.model.joint_names)

        self.description_pub = self.create_publisher(String, "robot_description", LATCHED_QOS)
        self.static_pub = self.create_publisher(TFMessage, "tf_static", LATCHED_QOS)
        self.tf_pub = self.create_publisher(TFMessage, "tf", TF_QOS)
        prefix = self.links.mesh_file_prefix() if self.config.mesh_uris == "file" else None
        self.description_pub.publish(String(data=self.links.urdf_text(prefix)))
        stamp = self.get_clock().now().to_msg()
        self.static_pub.publish(
            TFMessage(transforms=[_transform_msg(t, stamp) for t in self.links.static()])
        )
        self.create_subscription(
            JointState, "joint_states", self._on_joint_states, qos_profile_sensor_data, raw=True
        )
        self.get_logger().info(
            f"publishing {self.links.urdf_file.parent.name} on /robot_description, "
            f"{len(self.links.static())} static and {len(self.links.moving_joints)} moving "
            f"transforms (/tf at most {self.config.publish_frequency} Hz)"
        )

    @property
    def config(self) -> RobotStatePublisherConfig:
        """The current configuration (``config/robot_state_publisher.yaml``)."""
        return self.params.config

    def _on_joint_states(self, data: bytes) -> None:
        now = time.monotonic()
        if now < self._next_tf:
            return
        try:
            try:
                msg = deserialize_message(data, JointState)
            except Exception as exc:  # a corrupt serialised message (Fast CDR's RMWError)
                raise ValueError(f"cannot deserialise it: {exc}") from exc
            validate_joint_state(msg, required=("position",))
        except (IcubPmpError, ValueError, TypeError) as exc:
            self.get_logger().warning(f"dropping /joint_states: {exc}",
                                      throttle_duration_sec=2.0)
            return
        period = 1.0 / self.config.publish_frequency
        self._next_tf = self._next_tf + period if now - self._next_tf < period else now + period
        positions = {k: v for k, v in joint_state_field(msg, "position").items()
                     if k in self._valid}
        self._q = self.links.q_from_positions(positions, previous=self._q)
        stamp = msg.header.stamp
        if stamp.sec == 0 and stamp.nanosec == 0:
            stamp = self.get_clock().now().to_msg()
        self.tf_pub.publish(
            TFMessage(transforms=[_transform_msg(t, stamp) for t in self.links.moving(self._q)])
        )


def main(args: list[str] | None = None) -> None:
    """Entry point (``ros2 run icub_pmp robot_state_publisher``)."""
    spin_node(RobotStatePublisher, args, "robot_state_publisher")

if __name__ == "__main__":
    main()
