"""torque_loop: the wrench_estimator and impedance_controller nodes composed in one process.

On the iCub, wholeBodyDynamics runs as a YARP device inside the same yarprobotinterface
process as the control boards it serves, so the joint torques it estimates reach the boards'
torque loop without a network hop (docs/decisions/0067). This process does the same with the
two ROS nodes: both keep their names, topics, parameters and services (each reads its own
section of ``config/wrench_estimator.yaml`` and ``config/impedance_controller.yaml``), so the
rest of the graph sees the same nodes; they run on one ``EventsExecutor``, and:

- /joint_states is received once, by the estimator node's subscription, which hands each
  message's bytes to the controller first (:meth:`ImpedanceControllerNode.take_joint_state`);
- the estimator pairs the joint state with the two arm FT wrenches of the same stamp
  (its ``require_same_stamp`` synchroniser: whichever of the three messages comes last
  completes the sample, which is processed once and released), and hands the joint torques
  of that sample to the controller (:meth:`ImpedanceControllerNode.take_estimate`) before it
  publishes anything: in lockstep the controller's step that waited for that estimate
  runs at once and its /effort_command goes out before /estimated_joint_torques and the
  decimated wrench, contact and predicted-FT topics, which the estimator still publishes
  for the other nodes;
- the controller's own subscriptions to /joint_states and /estimated_joint_torques are not
  made (no second delivery of the same message, no DDS hop between the two).

When the estimator stops producing estimates (its FT input stops, or a sample is refused),
the controller sees no estimate, as with a killed estimator process: its steps stop waiting
once the last estimate is older than ``estimate_timeout``, and ``estimate_lost_timeout``
latches the safe hold, said in the log and on /impedance_controller/status.

    ros2 run icub_pmp torque_loop --ros-args --params-file config/wrench_estimator.yaml \\
        --params-file config/impedance_controller.yaml      # = scripts/torque_loop.sh
"""

from __future__ import annotations

from rclpy.node import Node

from icub_pmp.nodes.impedance_controller import ImpedanceControllerNode
from icub_pmp.nodes.wrench_estimator import WrenchEstimatorNode
from icub_pmp.ros.node_runner import spin_nodes

__all__ = ["TORQUE_LOOP_NODES", "compose_torque_loop", "main"]

#: the nodes the torque_loop process hosts (names of their own processes and configs)
TORQUE_LOOP_NODES = ("wrench_estimator", "impedance_controller")


def compose_torque_loop() -> tuple[WrenchEstimatorNode, ImpedanceControllerNode]:
    """Build both nodes and wire the estimator's in-process outputs to the controller."""
    estimator = WrenchEstimatorNode()
    try:
        controller = ImpedanceControllerNode(in_process_inputs=True)
    except BaseException:
        estimator.destroy_node()
        raise
    estimator.joint_state_listener = controller.take_joint_state
    estimator.estimate_listener = controller.take_estimate
    controller.get_logger().info("in the torque_loop process: joint states and estimates "
                                 "come from the wrench_estimator node in-process")
    return estimator, controller


def _nodes() -> list[Node]:
    return list(compose_torque_loop())


def main(args: list[str] | None = None) -> None:
    """Entry point (``ros2 run icub_pmp torque_loop``)."""
    spin_nodes(_nodes, args, "torque_loop")


if __name__ == "__main__":
    main()
