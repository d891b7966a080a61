"""robot_loop: sim_bridge, wrench_estimator and impedance_controller composed in one process.

As gazebo_ros2_control / gz_ros2_control load the controller manager inside the simulator
process, and as the iCub runs its torque loop on the boards next to the joints rather than
across the network (docs/decisions/0068), this process hosts the simulator and the torque loop
(the estimator and the controller of :mod:`icub_pmp.nodes.torque_loop`). The three nodes keep
their names, topics, parameters and services (each reads its own section of its YAML file):
/joint_states, the FT wrenches, /estimated_joint_torques, /effort_command and the rest are
still published for the other nodes. Inside the process:

- after each step the physics thread publishes the state as before, then hands the joint
  state and the two arm FT samples (their bytes) to the estimator
  (:meth:`WrenchEstimatorNode.take_joint_state`, :meth:`WrenchEstimatorNode.take_ft`); the
  joint state goes on to the controller and the estimate of that sample to the controller
  (the hooks of ``torque_loop``), whose step's effort command comes back to the simulator by
  :meth:`SimBridge.take_effort`: in lockstep the whole 1 kHz loop runs on the physics
  thread, with no DDS message and no thread hop;
- the subscriptions those hand-overs replace are not made (/joint_states and the arm FT topics
  by the estimator, /joint_states and /estimated_joint_torques by the controller,
  /effort_command by the simulator: in this process the simulator takes its commands from
  its own controller only);
- the estimator's and controller's other callbacks (trajectories, services, parameters,
  timers, /sim/status) run on the process's ``EventsExecutor`` thread, each holding the loop
  lock the physics thread holds while it runs their step, so the two threads never run the
  nodes at the same time.

Free run: the physics thread still hands every sample over; the controller steps on its
``rate_hz`` timer (executor thread) on the latest joint state, and its command reaches the
simulator through :meth:`SimBridge.take_effort` too.

    ros2 run icub_pmp robot_loop --ros-args --params-file config/sim_bridge.yaml \\
        --params-file config/wrench_estimator.yaml \\
        --params-file config/impedance_controller.yaml      # = scripts/robot_loop.sh
"""

from __future__ import annotations

import functools
import threading
from typing import Any, Callable

from rclpy.node import Node

from icub_pmp.nodes.impedance_controller import ImpedanceControllerNode
from icub_pmp.nodes.wrench_estimator import WrenchEstimatorNode
from icub_pmp.ros.node_runner import spin_nodes
from icub_sim_bridge.sim_bridge_node import SimBridge

__all__ = ["ROBOT_LOOP_NODES", "compose_robot_loop", "main"]

#: the nodes the robot_loop process hosts (names of their own processes and configs)
ROBOT_LOOP_NODES = ("sim_bridge", "wrench_estimator", "impedance_controller")


def _locked(fn: Callable[..., Any], lock: threading.RLock) -> Callable[..., Any]:
    """``fn`` run while holding ``lock``."""
    @functools.wraps(fn)
    def call(*args: Any, **kwargs: Any) -> Any:
        with lock:
            return fn(*args, **kwargs)
    return call


def guard_callbacks(node: Node, lock: threading.RLock) -> None:
    """Make every subscription, timer and service callback of ``node`` hold ``lock``, those
    it has and those it creates later (a timer of a changed ``rate_hz``, the /imu
    subscription of ``gravity_source: imu``)."""
    for entity in (*node.subscriptions, *node.timers, *node.services):
        entity.callback = _locked(entity.callback, lock)
    for name, position in (("create_subscription", 2), ("create_timer", 1),
                           ("create_service", 2)):
        setattr(node, name, _locking_factory(getattr(node, name), position, lock))


def _locking_factory(create: Callable[..., Any], position: int, lock: threading.RLock
                     ) -> Callable[..., Any]:
    """``create`` (a ``Node.create_*`` method) with its callback argument (at ``position``,
    or the keyword ``callback``) run while holding ``lock``."""
    @functools.wraps(create)
    def wrapped(*args: Any, **kwargs: Any) -> Any:
        if "callback" in kwargs:
            kwargs["callback"] = _locked(kwargs["callback"], lock)
        elif len(args) > position:
            args = (*args[:position], _locked(args[position], lock), *args[position + 1:])
        return create(*args, **kwargs)
    return wrapped


def compose_robot_loop() -> tuple[SimBridge, WrenchEstimatorNode, ImpedanceControllerNode]:
    """Build the three nodes and wire the in-process hand-overs (module doc)."""
    built: list[Node] = []
    try:
        sim = SimBridge(in_process_commands=True)
        built.append(sim)
        estimator = WrenchEstimatorNode(in_process_inputs=True)
        built.append(estimator)
        controller = ImpedanceControllerNode(in_process_inputs=True)
    except BaseException:
        for n in built:
            n.destroy_node()
        raise
    estimator.joint_state_listener = controller.take_joint_state
    estimator.estimate_listener = controller.take_estimate
    controller.effort_listener = sim.take_effort
    lock = threading.RLock()
    for n in (estimator, controller):
        guard_callbacks(n, lock)

    def on_state(ns: int, joint_state: bytes, ft: dict[str, bytes]) -> None:
        with lock:
            controller.set_sim_mode(sim.config.mode)
            estimator.take_joint_state(joint_state)
            estimator.take_ft("left", ft["l_arm_ft"])
            estimator.take_ft("right", ft["r_arm_ft"])

    sim.state_listener = on_state
    sim.get_logger().info("robot_loop: the wrench_estimator and impedance_controller run in "
                          "this process; state, estimates and commands handed over in-process")
    return sim, estimator, controller


def _nodes() -> list[Node]:
    return list(compose_robot_loop())


def main(args: list[str] | None = None) -> None:
    """Entry point (``ros2 run icub_pmp robot_loop``): the physics loop on its own thread
    (it runs the torque loop), the executor on the main thread."""
    spin_nodes(_nodes, args, "robot_loop", worker=SimBridge.run)


if __name__ == "__main__":
    main()
