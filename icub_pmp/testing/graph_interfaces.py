"""The graph's fuzzable interfaces: every service, action and subscribed topic of the nodes
of ``scripts/graph.sh``, with the node that serves it and its answer-time budget.

Budgets [s, wall] are each interface's documented time (README, config/<node>.yaml) with room
for a loaded two-core machine: a request not answered within its budget counts as a hang.
"""

from __future__ import annotations

import dataclasses
import os
import tempfile
from pathlib import Path
from typing import Any

__all__ = ["FuzzTarget", "FUZZ_GRAPH", "FUZZ_PARAMS", "PERIPERSONAL_FUZZ_MAPS", "services",
           "actions", "topics", "parameter_services", "effort_topic", "good_reach",
           "good_solve_pose", "good_look_at", "clear_obstacles", "fuzz_services",
           "fuzz_actions", "fuzz_topics", "fuzz_effort"]

#: the nodes fuzzed, started as scripts/graph.sh starts them, except: cameras off (images are
#: fuzzed) and the Cartesian solver on the CasADi VM (``codegen: false``: a fuzzed request on a
#: chain not prebuilt would otherwise compile its NLP with gcc inside the service call, minutes
#: on a fresh, loaded machine; docs/decisions/0045-fuzzing-derived-from-the-types.md)
#: ... plus the nodes a user starts beside it: the robot state publisher, the body schema
#: (babbling) and the peripersonal space (its maps grown small, once, in a scratch folder:
#: :data:`PERIPERSONAL_FUZZ_MAPS`).
FUZZ_GRAPH = ["sim_bridge", "wrench_estimator", "impedance_controller", "pmp_planner",
              "cartesian_solver", "gaze_controller", "motion_segmenter",
              "robot_state_publisher", "body_schema", "peripersonal_space"]
PERIPERSONAL_FUZZ_MAPS = Path(tempfile.gettempdir()) / f"icub_pmp_fuzz_peripersonal_{os.getuid()}"
FUZZ_PARAMS: dict[str, dict[str, object]] = {
    "sim_bridge": {"cameras_enabled": False},
    "cartesian_solver": {"codegen": False},
    "peripersonal_space": {"maps_dir": str(PERIPERSONAL_FUZZ_MAPS), "grow_if_missing": True,
                           "babble_samples": 2000},
}


@dataclasses.dataclass(frozen=True)
class FuzzTarget:
    """One interface: ``name`` (service, action or topic), its ROS ``type``, the ``nodes``
    serving or subscribing to it, the answer ``budget`` [s] and the number of ``cases``."""

    name: str
    type: Any
    nodes: tuple[str, ...]
    budget: float = 10.0
    cases: int = 10


def services(scale: float = 1.0) -> list[FuzzTarget]:
    """Every service of the graph (``scale`` multiplies the case counts)."""
    from std_srvs.srv import SetBool, Trigger

    from icub_interfaces.srv import (
        AllocateObjects,
        ApplyWrench,
        CheckReach,
        FindEmptyArea,
        GoToPose,
        Grasp,
        LookAt,
        MoveObject,
        PlanPair,
        Reach,
        ResetSim,
        SetObjectPose,
        SolvePose,
        StartBabbling,
    )

    def n(k: int) -> int:
        return max(1, int(round(k * scale)))

    return [
        FuzzTarget("/sim/reset", ResetSim, ("sim_bridge",), 10.0, n(6)),
        FuzzTarget("/sim/set_object_pose", SetObjectPose, ("sim_bridge",), 10.0, n(12)),
        FuzzTarget("/sim/move_object", MoveObject, ("sim_bridge",), 10.0, n(8)),
        FuzzTarget("/sim/apply_wrench", ApplyWrench, ("sim_bridge",), 10.0, n(12)),
        FuzzTarget("/sim/set_paused", SetBool, ("sim_bridge",), 10.0, n(4)),
        # no cubes in the fuzzed scene: every grasp is refused by name, the node answers
        FuzzTarget("/sim/grasp", Grasp, ("sim_bridge",), 10.0, n(6)),
        FuzzTarget("/impedance_controller/hold", Trigger, ("impedance_controller",), 10.0,
                   n(3)),
        FuzzTarget("/wrench_estimator/calibrate", Trigger, ("wrench_estimator",), 30.0, n(2)),
        FuzzTarget("/pmp/reach", Reach, ("pmp_planner",), 30.0, n(20)),
        FuzzTarget("/cartesian/solve_pose", SolvePose, ("cartesian_solver",), 15.0, n(12)),
        FuzzTarget("/cartesian/go_to_pose", GoToPose, ("cartesian_solver",), 20.0, n(10)),
        FuzzTarget("/gaze/look_at", LookAt, ("gaze_controller",), 45.0, n(10)),
        FuzzTarget("/gaze/set_tracking", SetBool, ("gaze_controller",), 10.0, n(4)),
        FuzzTarget("/peripersonal/check_reach", CheckReach, ("peripersonal_space",), 15.0,
                   n(10)),
        FuzzTarget("/peripersonal/allocate", AllocateObjects, ("peripersonal_space",), 15.0,
                   n(10)),
        FuzzTarget("/peripersonal/empty_area", FindEmptyArea, ("peripersonal_space",), 15.0,
                   n(10)),
        FuzzTarget("/peripersonal/plan_pair", PlanPair, ("peripersonal_space",), 30.0, n(8)),
        FuzzTarget("/peripersonal/reload", Trigger, ("peripersonal_space",), 30.0, n(2)),
        # babbling last among the services: an accepted request moves the arm until the
        # stop requests that follow
        FuzzTarget("/body_schema/start_babbling", StartBabbling, ("body_schema",), 10.0, n(8)),
        FuzzTarget("/body_schema/stop_babbling", Trigger, ("body_schema",), 10.0, n(3)),
    ]


def parameter_services(nodes: list[str], scale: float = 1.0) -> list[FuzzTarget]:
    """Every node's ``~/set_parameters`` (rcl_interfaces/SetParameters): drawn names and
    values; a node validates each change it accepts (config/<node>.yaml's dataclasses)."""
    from rcl_interfaces.srv import SetParameters

    return [FuzzTarget(f"/{node}/set_parameters", SetParameters, (node,), 10.0,
                       max(1, int(round(4 * scale)))) for node in nodes]


def actions(scale: float = 1.0) -> list[FuzzTarget]:
    """Every action of the graph."""
    from icub_interfaces.action import FollowJointTrajectory, GoToPose, Reach

    def n(k: int) -> int:
        return max(1, int(round(k * scale)))

    return [
        FuzzTarget("/impedance_controller/follow_joint_trajectory", FollowJointTrajectory,
                   ("impedance_controller",), 15.0, n(8)),
        FuzzTarget("/pmp/reach_action", Reach, ("pmp_planner",), 30.0, n(6)),
        FuzzTarget("/cartesian/go_to_pose_action", GoToPose, ("cartesian_solver",), 30.0,
                   n(6)),
    ]


def topics(scale: float = 1.0) -> list[FuzzTarget]:
    """Every topic the nodes subscribe to (the simulator's /effort_command is left to
    :func:`effort_topic`: fuzzing it stops the torque checks)."""
    from geometry_msgs.msg import PointStamped, WrenchStamped
    from sensor_msgs.msg import CameraInfo, Image, JointState
    from trajectory_msgs.msg import JointTrajectory

    from icub_interfaces.msg import Obstacles, SimStatus

    def n(k: int) -> int:
        return max(1, int(round(k * scale)))

    every_js = ("wrench_estimator", "impedance_controller", "pmp_planner", "cartesian_solver",
                "gaze_controller", "motion_segmenter", "robot_state_publisher", "body_schema")
    return [
        FuzzTarget("/joint_states", JointState, every_js, cases=n(40)),
        FuzzTarget("/estimated_joint_torques", JointState, ("impedance_controller",),
                   cases=n(30)),
        FuzzTarget("/joint_trajectory", JointTrajectory, ("impedance_controller",),
                   cases=n(30)),
        FuzzTarget("/impedance_controller/velocity_command", JointState,
                   ("impedance_controller",), cases=n(20)),
        FuzzTarget("/ft/r_arm_ft", WrenchStamped, ("wrench_estimator",), cases=n(20)),
        FuzzTarget("/ft/l_arm_ft", WrenchStamped, ("wrench_estimator",), cases=n(10)),
        FuzzTarget("/sim/status", SimStatus, ("impedance_controller",), cases=n(15)),
        # /imu is left out: the estimator subscribes to it only with gravity_source: imu,
        # not the shipped config (a publisher there reaches no node)
        FuzzTarget("/cam/left/image_raw", Image, ("motion_segmenter", "body_schema"),
                   cases=n(20)),
        FuzzTarget("/cam/right/camera_info", CameraInfo, ("motion_segmenter", "body_schema"),
                   cases=n(15)),
        FuzzTarget("/pmp/obstacles", Obstacles, ("pmp_planner",), cases=n(15)),
        FuzzTarget("/motion/target", PointStamped, ("gaze_controller",), cases=n(15)),
    ]


def effort_topic(scale: float = 1.0) -> FuzzTarget:
    """The simulator's command input."""
    from sensor_msgs.msg import JointState

    return FuzzTarget("/effort_command", JointState, ("sim_bridge",),
                      cases=max(1, int(round(30 * scale))))


def good_reach() -> Any:
    """A valid imagine-only /pmp/reach request (the right hand 25 cm in front of the chest)."""
    from icub_interfaces.srv import Reach

    req = Reach.Request()
    req.hands = ["right"]
    req.tau = 1.5
    req.simulate_only = True
    req.right_target.header.frame_id = "root_link"
    p = req.right_target.pose.position
    p.x, p.y, p.z = -0.30, 0.15, 0.05
    req.right_target.pose.orientation.w = 1.0
    return req


def good_solve_pose() -> Any:
    """A valid /cartesian/solve_pose request (position only)."""
    from icub_interfaces.srv import SolvePose

    req = SolvePose.Request()
    req.chain = "torso_right_arm"
    req.target.header.frame_id = "root_link"
    p = req.target.pose.position
    p.x, p.y, p.z = -0.30, 0.15, 0.05
    req.target.pose.orientation.w = 1.0
    return req


def good_look_at() -> Any:
    """A valid /gaze/look_at request (a point on the table, no waiting)."""
    from icub_interfaces.srv import LookAt

    req = LookAt.Request()
    req.target.header.frame_id = "root_link"
    req.target.point.x, req.target.point.y, req.target.point.z = -0.4, 0.0, 0.0
    req.duration = 1.0
    req.wait = False
    return req


# ---------------------------------------------------------------------- the fuzzing phases
# (the test runs them one per test function, bench/reliability.py all in a row)
def fuzz_services(fuzzer: Any, scale: float = 1.0) -> list[str]:
    """Every service fuzzed; returns their names. The graph is left as found: the simulator
    running (a drawn /sim/set_paused may have paused it) and no babbling."""
    from std_srvs.srv import SetBool, Trigger

    targets = services(scale) + parameter_services(list(fuzzer.graph.procs), scale)
    for t in targets:
        fuzzer.fuzz_service(t.name, t.type, t.nodes[0], t.budget, t.cases)
    fuzzer.probe.call("/sim/set_paused", SetBool, SetBool.Request(data=False), 30.0)
    if "body_schema" in fuzzer.graph.procs:
        fuzzer.probe.call("/body_schema/stop_babbling", Trigger, Trigger.Request(), 30.0)
    return [t.name for t in targets]


def fuzz_actions(fuzzer: Any, scale: float = 1.0) -> list[str]:
    """Every action fuzzed; returns their names."""
    targets = actions(scale)
    for t in targets:
        fuzzer.fuzz_action(t.name, t.type, t.nodes[0], t.budget, t.cases)
    return [t.name for t in targets]


def fuzz_topics(fuzzer: Any, scale: float = 1.0) -> list[str]:
    """Every subscribed topic fuzzed (drawn messages), then the 1 kHz inputs of the
    controller with out-of-order stamps, a 10x burst and corrupt CDR; the planner's obstacle
    scene is left empty (as found); returns the tally names."""
    from sensor_msgs.msg import JointState

    targets = topics(scale)
    for t in targets:
        fuzzer.fuzz_topic(t.name, t.type, t.nodes, t.cases)
    names = [t.name for t in targets]
    for topic, nodes in (("/joint_states", targets[0].nodes),
                         ("/estimated_joint_torques", ("impedance_controller",))):
        got = fuzzer.probe.collect(topic, JointState, 1, 30.0)
        if not got:
            raise AssertionError(f"{topic} is no longer published after the fuzzing")
        names.append(fuzzer.disorder_topic(topic, got[0], nodes).name)
    clear_obstacles(fuzzer.probe)
    return names


def clear_obstacles(probe: Any, timeout: float = 30.0) -> bool:
    """Publish an empty /pmp/obstacles scene (the planner keeps the last valid one it got,
    e.g. the fuzzer's last drawn scene); True once a subscriber matched and it was sent."""
    import time

    from rclpy.qos import QoSProfile, ReliabilityPolicy

    from icub_interfaces.msg import Obstacles

    pub = probe.node.create_publisher(
        Obstacles, "/pmp/obstacles", QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE))
    try:
        if not probe.wait_for(lambda: pub.get_subscription_count() >= 1, timeout):
            return False
        pub.publish(Obstacles())
        time.sleep(0.5)
        return True
    finally:
        probe.destroy(pub)


def fuzz_effort(fuzzer: Any, scale: float = 1.0) -> list[str]:
    """The simulator's /effort_command fuzzed (drawn, disordered, corrupt); run it last, with
    any torque watch paused (this publishes commands beyond the limits on purpose)."""
    from sensor_msgs.msg import JointState

    t = effort_topic(scale)
    fuzzer.fuzz_topic(t.name, t.type, t.nodes, t.cases)
    got = fuzzer.probe.collect("/effort_command", JointState, 1, 30.0)
    names = [t.name]
    if got:
        names.append(fuzzer.disorder_topic("/effort_command", got[0], t.nodes).name)
    return names
