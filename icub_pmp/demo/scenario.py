"""The demo scenario of the papers on the simulated iCub, driven over DDS.

Starts the node graph through its scripts (simulator in lockstep with the impedance
controller, so the 1 kHz loop is exact in simulated time), records every topic to
``bags/demo-<timestamp>/``, and runs six phases with no further input:

1. ``bimanual_reach``: PMP reach of both hands to the sides of the box, torso recruited
   (Mohan et al. 2009, Sect. 3.1): both hands arrive together at tau.
2. ``bimanual_squeeze`` and ``bimanual_transport``: both hands squeeze the box (the hand frames
   commanded ``SQUEEZE_OFFSET`` outside its sides, so the palms press a few mm in, with the
   palms' contact patches above the box's centre of mass, :func:`palm_contact_offsets`; the
   estimator's contact flags confirm both touch; then a force loop on the estimated contact
   forces, :func:`hold_squeeze`, sets the squeeze to ``SQUEEZE_FORCE`` and takes off what
   the arms' weight leaves on the box) and lift it 8 cm with the object coupling of
   Sect. 3.2 (Fig 8): the goal pulls the held box, the box pulls both hands, which keep their
   orientations (``use_orientation``). The planner starts a transport from the controller's
   set-point, so the squeeze is kept rather than released at the start and rebuilt during the
   lift. Judged in the physics (:func:`judge_transport`):
   the hand-to-hand distance from /joint_states through forward kinematics at every sample of
   the motion stays within 5 mm of its start, and the box rises by 4 cm or more.
3. ``vision_reach``: the cylinder is moved across the table while the gaze controller tracks
   the motion segmenter's stereo target (/motion/target); once it stops, the right hand goes
   through PMP to the pre-grasp point above the estimated top (via a point above it when the
   straight way could sweep the object). Judged against the object's ground truth: the hand
   within 2 cm of the point above the cylinder's true top centre, the estimate within 1 cm of
   the cylinder at the images' stamp, the cylinder not pushed by the reach.
4. ``cartesian_reach``: the same target reached with the IPOPT Cartesian solver (eq 11).
5. ``obstacle_reach``: the cylinder is placed on the table between the right hand and its
   target; the reach goes through /pmp/reach_action with the cylinder as an obstacle (its
   ground-truth pose, as a perception node would publish it) and a clearance the planner
   keeps for the hand's, wrist's and forearm's collision hulls (the fingers included). Judged
   in the physics (:func:`judge_obstacle_reach`): the hand within 1 cm of the target, no
   contact of any link with the cylinder (/ground_truth/object_contacts) and the cylinder not
   moved.
6. ``press``: the right hand presses down on the table top with 10 N: the position-mode joint
   springs realise a force through a target beyond the contact (``x_contact + C F``, the
   fingertips' compliance ``C = J_c K^-1 J_c^T``, the hand's orientation kept), corrected
   from the wrench estimator's force by a guarded force loop that fits the compliance to the
   measured force changes (:class:`~icub_pmp.control.press_loop.PressLoop`); the goals carry
   the force target (``right_force``). Judged by :func:`judge_press`: the estimated
   external force within 10 % of the target, reported beside the simulator's contact force.

7. ``tabletop`` (with ``--tabletop``): the two arms' tabletop task of issue 19
   (:func:`tabletop_phase`): four cubes allocated by reward, pairs of reaches in parallel or in
   series by the imagined collision check, a hand-over; judged on the cubes delivered and 0
   arm-arm contacts in the physics.

A phase that fails does not stop the next. Every phase is measured in the physics: the hand
positions come from the simulator's /joint_states through the model's forward kinematics.
Then the bag is replayed and checked, and a report (PNG plots + ``report.md``) is written
beside it.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path
from typing import Callable

import numpy as np

from icub_pmp.config import repo_root
from icub_pmp.demo.demo_runner import PROVISIONAL_PHASES, DemoRunner, PhaseResult
from icub_pmp.graph import (
    NodeGraph,
    NodeProcess,
    realism_parameters,
    reserve_domain_id,
    ros_environment,
)
from icub_pmp.kinematics import IcubModel
from icub_pmp.ros.conversions import time_to_sec
from icub_pmp.ros.probe import RosProbe

__all__ = ["PhaseResult", "DemoRunner", "main"]

GRAPH = [
    "sim_bridge",
    "wrench_estimator",
    "impedance_controller",
    "pmp_planner",
    "cartesian_solver",
    "motion_segmenter",
    "gaze_controller",
    "robot_state_publisher",
]

#: the demo's phases as ``--phases`` names them, in their order: ``bimanual`` = reach, squeeze
#: and coupled transport (phases 1-2), ``vision`` = the reach to the seen cylinder (3),
#: ``cartesian`` (4; without ``vision`` it aims 12 cm above the cylinder's true pose),
#: ``obstacle`` (5), ``press`` (6)
PHASES = ("bimanual", "vision", "cartesian", "obstacle", "press")
#: the nodes (and the simulator's cameras) only some phases need
_PHASE_NODES = {"cartesian_solver": ("cartesian",),
                "motion_segmenter": ("vision",),
                "gaze_controller": ("vision",)}
#: the services each node offers that :meth:`DemoRunner.wait_ready` waits for
_NODE_SERVICES = {"pmp_planner": ("/pmp/reach",), "cartesian_solver": ("/cartesian/go_to_pose",),
                  "sim_bridge": ("/sim/set_object_pose", "/sim/move_object"),
                  "gaze_controller": ("/gaze/look_at",)}


def parse_phases(text: str) -> tuple[str, ...]:
    """``--phases`` text (comma-separated names of :data:`PHASES`, or ``all``) -> the phases
    in the demo's order; ValueError naming the unknown ones."""
    names = [n.strip() for n in text.split(",") if n.strip()]
    if not names:
        raise ValueError(f"no phase given (choose from {', '.join(PHASES)} or all)")
    if names == ["all"]:
        return PHASES
    unknown = [n for n in names if n not in PHASES]
    if unknown:
        raise ValueError(f"unknown phase(s) {', '.join(unknown)} (choose from "
                         f"{', '.join(PHASES)} or all)")
    return tuple(p for p in PHASES if p in names)


def phase_graph(phases: tuple[str, ...], params: dict[str, dict[str, object]]
                ) -> tuple[list[str], dict[str, dict[str, object]]]:
    """The demo graph's nodes and parameters for ``phases``: nodes only other phases need
    are left out, and the simulator renders no cameras unless ``vision`` runs."""
    nodes = [n for n in GRAPH
             if n not in _PHASE_NODES or any(p in phases for p in _PHASE_NODES[n])]
    out = {n: dict(params[n]) for n in nodes}
    if "vision" not in phases:
        out["sim_bridge"]["cameras_enabled"] = False
    return nodes, out


def ready_services(nodes: list[str]) -> tuple[str, ...]:
    """The services of ``nodes`` the demo waits for before its first goal."""
    return tuple(s for n in nodes for s in _NODE_SERVICES.get(n, ()))


#: judging of the vision reach against the object's ground truth [m]
VISION_ARRIVAL_TOLERANCE = 0.02
VISION_TARGET_TOLERANCE = 0.01
VISION_PUSH_TOLERANCE = 0.01
#: coupled transport (issue 20): the measured hand-to-hand distance may change by at most this
#: during the whole motion [m]; the box must rise by at least TRANSPORT_MIN_LIFT [m]
TRANSPORT_DISTANCE_TOLERANCE = 0.005
TRANSPORT_MIN_LIFT = 0.04
#: the planner's orientation field in the demo [N m/rad] (config default 10): an 8 cm lift with
#: the hands' orientations as targets turned the right hand by 11.7 deg on the way with 10,
#: 3.8 deg with 100, 0.5 deg with 1000 (free: 17.4 deg), the plan's hand distance within 0.3 mm
TRANSPORT_ROTATION_STIFFNESS = 1000.0
#: reach around an obstacle: the hand within OBSTACLE_ARRIVAL_TOLERANCE of its target [m], the
#: obstacle moved by less than OBSTACLE_MOVE_TOLERANCE [m] (and never touched)
OBSTACLE_ARRIVAL_TOLERANCE = 0.01
OBSTACLE_MOVE_TOLERANCE = 0.002
#: press on the table: the estimated external force within this fraction of the target [-]
PRESS_FORCE_TOLERANCE = 0.10


def run_demo(out_dir: Path, quick: bool = False, realism: str | None = None,
             tabletop: bool = False, phases: tuple[str, ...] = PHASES) -> int:
    """Run the whole demo; returns the process exit code (non-zero if a phase failed).
    ``realism``: the simulator's realism preset (None = the shipped config's); ``tabletop``:
    the tabletop task as the last phase (:func:`tabletop_phase`); ``phases``: which of
    :data:`PHASES` to run (the graph leaves out the nodes and cameras only the others need:
    :func:`phase_graph`)."""
    out_dir.mkdir(parents=True, exist_ok=True)
    bag_dir = out_dir / "bag"
    results: list[PhaseResult] = []
    with reserve_domain_id() as domain:
        env = ros_environment(domain)
        print(f"demo: ROS_DOMAIN_ID={domain}, output in {out_dir}", flush=True)
        nodes, params = phase_graph(phases, graph_parameters(realism))
        if tabletop:
            nodes, params = GRAPH + TABLETOP_GRAPH, tabletop_parameters(params)
        with NodeGraph(nodes, params, env=env) as graph:
            recorder = NodeProcess(
                command=[str(repo_root() / "scripts/record.sh"), "-o", str(bag_dir), "--all"],
                env=env)
            probe = RosProbe(domain, "demo_driver")
            try:
                runner = DemoRunner(probe)
                print("demo: waiting for the graph ...", flush=True)
                runner.wait_ready(services=ready_services(nodes))
                runner.wait_sim(0.5)
                # the FT offsets, on the still robot before any goal (realism icub: a few N)
                print(f"demo: {runner.calibrate_estimator()}", flush=True)
                run_phases(runner, quick, results, phases)
                if tabletop:
                    print("demo: phase 7, the tabletop task of the two arms", flush=True)
                    results.append(guarded("tabletop", lambda: tabletop_phase(runner), runner))
            except Exception as exc:  # report what happened, never a bare traceback
                results.append(PhaseResult("graph", False, f"{type(exc).__name__}: {exc}"))
                print(graph.outputs()[-6000:], file=sys.stderr)
            finally:
                probe.close()
                recorder.stop(timeout=30.0)
                rec_out = recorder.output()
        print(rec_out[-2000:], flush=True)
        replay = replay_check(bag_dir, env)
    from icub_pmp.demo.report import write_report

    write_report(out_dir, bag_dir, results, replay)
    for r in results:
        if r.name in PROVISIONAL_PHASES:
            r.required = False
    failed = [r.name for r in results if not r.success and r.required]
    for r in results:
        status = "ok" if r.success else "FAILED" if r.required else "NOT MET"
        res = ", ".join(f"{h} {v * 1000:.1f} mm" for h, v in r.physics_residual.items())
        print(f"demo: {r.name:20s} {status:6s} physics residual: {res or '-'}  ({r.message})")
    provisional = [r.name for r in results if not r.success and not r.required]
    if provisional:
        print(f"demo: NOT MET (judged, not yet failing the demo: issue 20): "
              f"{', '.join(provisional)}", flush=True)
    print(f"demo: report in {out_dir / 'report.md'}", flush=True)
    if not replay.get("ok", False):
        failed.append("replay")
    return 1 if failed else 0


def judge_vision_reach(hand: np.ndarray, object_position: np.ndarray, object_height: float,
                       clearance: float, target_error: float, pushed: float
                       ) -> tuple[bool, str, dict[str, float]]:
    """Judge a reach to a seen object against the object's ground truth.

    Args:
        hand: (3,) the hand's final position measured in the physics [m].
        object_position: (3,) the object's true centre after the reach [m].
        object_height: its true height [m] (top = centre + height / 2).
        clearance: the pre-grasp height above the top [m].
        target_error: distance of the stereo estimate from the object at the images' stamp [m].
        pushed: how far the object moved during the reach [m].

    Returns:
        (success, message, figures): success needs the hand within
        ``VISION_ARRIVAL_TOLERANCE`` of the point ``clearance`` above the true top centre, the
        estimate within ``VISION_TARGET_TOLERANCE`` and the object moved less than
        ``VISION_PUSH_TOLERANCE``.
    """
    goal = np.asarray(object_position, float) + [0.0, 0.0, 0.5 * object_height + clearance]
    arrival = float(np.linalg.norm(np.asarray(hand, float) - goal))
    figures = {"arrival_vs_object_m": arrival, "target_error_m": float(target_error),
               "object_pushed_m": float(pushed)}
    faults = []
    if not arrival <= VISION_ARRIVAL_TOLERANCE:
        faults.append(f"the hand ended {arrival * 100:.1f} cm from the point above the object's "
                      f"top (> {VISION_ARRIVAL_TOLERANCE * 100:.0f} cm)")
    if not target_error <= VISION_TARGET_TOLERANCE:
        faults.append(f"the stereo estimate was {target_error * 100:.1f} cm from the object "
                      f"(> {VISION_TARGET_TOLERANCE * 100:.0f} cm)")
    if not pushed <= VISION_PUSH_TOLERANCE:
        faults.append(f"the reach pushed the object by {pushed * 100:.1f} cm")
    if faults:
        return False, "; ".join(faults), figures
    return True, (f"hand {arrival * 1000:.1f} mm from the point above the object, estimate "
                  f"{target_error * 1000:.1f} mm from it"), figures


def judge_transport(distances: np.ndarray, lift: float) -> tuple[bool, str, dict[str, float]]:
    """Judge a coupled transport in the physics.

    Args:
        distances: (n,) the measured hand-to-hand distance [m] at every /joint_states sample
            of the motion (forward kinematics of the measured joints), the first one at the
            start of the transport.
        lift: how far the box rose [m] (ground truth).

    Returns:
        (success, message, figures): success needs the distance to stay within
        ``TRANSPORT_DISTANCE_TOLERANCE`` of its start value at every sample (the largest change
        over the transport, not the end against the start) and the box lifted by
        ``TRANSPORT_MIN_LIFT`` or more.
    """
    d = np.asarray(distances, float).reshape(-1)
    if d.size < 2 or not np.all(np.isfinite(d)):
        return False, f"too few finite hand-to-hand distances measured ({d.size})", {}
    dev = d - d[0]
    k = int(np.argmax(np.abs(dev)))
    change = float(abs(dev[k]))
    figures = {"hand_distance_change_max_m": change, "hand_distance_change_end_m":
               float(dev[-1]), "hand_distance_samples": float(d.size), "box_lift_m": float(lift)}
    faults = []
    if not change <= TRANSPORT_DISTANCE_TOLERANCE:
        faults.append(f"the measured hand-to-hand distance changed by {change * 1e3:.1f} mm "
                      f"(sample {k} of {d.size}; > {TRANSPORT_DISTANCE_TOLERANCE * 1e3:.0f} mm)")
    if not lift >= TRANSPORT_MIN_LIFT:
        faults.append(f"box lifted only {lift * 100:.1f} cm "
                      f"(< {TRANSPORT_MIN_LIFT * 100:.0f} cm)")
    if faults:
        return False, "; ".join(faults), figures
    return True, (f"hand-to-hand distance kept within {change * 1e3:.1f} mm over {d.size} "
                  f"samples, box lifted {lift * 100:.1f} cm"), figures


def judge_obstacle_reach(hand: np.ndarray, target: np.ndarray, touching: list[str],
                         moved: float) -> tuple[bool, str, dict[str, float]]:
    """Judge a reach around an obstacle in the physics.

    Args:
        hand: (3,) the hand's final position measured in the physics [m].
        target: (3,) the reach target [m].
        touching: the robot's links seen touching the obstacle during the motion (ground
            truth /ground_truth/object_contacts; empty = no contact).
        moved: how far the obstacle moved during the motion [m] (ground truth).

    Returns:
        (success, message, figures): success needs the hand within
        ``OBSTACLE_ARRIVAL_TOLERANCE`` of the target, no contact and the obstacle moved less
        than ``OBSTACLE_MOVE_TOLERANCE``.
    """
    arrival = float(np.linalg.norm(np.asarray(hand, float) - np.asarray(target, float)))
    figures = {"arrival_m": arrival, "obstacle_moved_m": float(moved),
               "obstacle_contact_links": float(len(set(touching)))}
    faults = []
    if not arrival <= OBSTACLE_ARRIVAL_TOLERANCE:
        faults.append(f"the hand ended {arrival * 100:.1f} cm from the target "
                      f"(> {OBSTACLE_ARRIVAL_TOLERANCE * 100:.0f} cm)")
    if touching:
        faults.append(f"the robot touched the obstacle with {sorted(set(touching))}")
    if not moved < OBSTACLE_MOVE_TOLERANCE:
        faults.append(f"the obstacle moved by {moved * 1e3:.1f} mm")
    if faults:
        return False, "; ".join(faults), figures
    return True, (f"hand {arrival * 1e3:.1f} mm from the target, no contact with the "
                  f"obstacle (moved {moved * 1e3:.2f} mm)"), figures


def judge_press(estimated: np.ndarray, target: np.ndarray, ground_truth: np.ndarray | None
                ) -> tuple[bool, str, dict[str, float]]:
    """Judge a press with a target force.

    Args:
        estimated: (3,) the wrench estimator's external force on the hand [N] (root_link).
        target: (3,) the force the hand must exert on the world [N] (root_link; the world
            pushes back with ``-target``).
        ground_truth: (3,) the simulator's contact force on the hand [N], reported beside the
            estimate (not judged), or None.

    Returns:
        (success, message, figures): success needs ``|-estimated - target|`` within
        ``PRESS_FORCE_TOLERANCE`` of ``|target|``.
    """
    target = np.asarray(target, float)
    norm = float(np.linalg.norm(target))
    if not norm > 0.0 or not np.all(np.isfinite(target)):
        return False, f"no valid target force ({target.tolist()})", {}
    exerted = -np.asarray(estimated, float)
    err = float(np.linalg.norm(exerted - target)) / norm
    figures = {"target_force_N": norm, "estimated_force_N": float(exerted @ target) / norm,
               "estimated_force_error_rel": err}
    truth = ""
    if ground_truth is not None:
        gt = -np.asarray(ground_truth, float)
        figures["ground_truth_force_N"] = float(gt @ target) / norm
        figures["ground_truth_force_error_rel"] = float(np.linalg.norm(gt - target)) / norm
        truth = f", simulator's contact force {figures['ground_truth_force_N']:.1f} N"
    if not err <= PRESS_FORCE_TOLERANCE:
        return False, (f"the estimated force {np.round(exerted, 1).tolist()} N is "
                       f"{err * 100:.0f} % off the target {np.round(target, 1).tolist()} N "
                       f"(> {PRESS_FORCE_TOLERANCE * 100:.0f} %){truth}"), figures
    return True, (f"estimated force {figures['estimated_force_N']:.1f} N, {err * 100:.1f} % off "
                  f"the target {norm:.0f} N{truth}"), figures


def cylinder_height() -> float:
    """The simulated cylinder's height [m] (config/sim_bridge.yaml): ground truth for judging."""
    from icub_pmp.config import config_dir, load_params_file

    return float(load_params_file(config_dir() / "sim_bridge.yaml", "sim_bridge")
                 ["cylinder_height"])


#: a still target is settled once two successive still estimates are this close [m]: the first
#: still estimate of an object that just stopped can still lag behind it (the bench's fastest
#: motion, 0.25 m/s: 15, 9, then 2 mm off in three successive images; docs/decisions/0058)
STILL_SETTLE_TOLERANCE = 0.003


#: a still estimate counts only with at least this share of the most points any estimate of
#: the object had so far: one made of a few hundred points where the others had thousands is a
#: part of the object (a bench trial's goal was such a still pair, 226 and 264 points 33 mm
#: off, where the moving cylinder had given 2,672 and the next still ones 3,400-3,900, 2-5 mm)
STILL_MIN_POINTS_RATIO = 0.3


def settled_still_estimate(estimates: list, after: float,
                           tolerance: float = STILL_SETTLE_TOLERANCE,
                           min_points_ratio: float = STILL_MIN_POINTS_RATIO):  # noqa: ANN201
    """The first /motion/target/estimate (VisualTarget, in arrival order) stamped after
    ``after`` [s] that measured the object still (state ``still``, points > 0) within
    ``tolerance`` [m] of the still estimate measured just before it (also after ``after``);
    an estimate with fewer points than ``min_points_ratio`` times the most of any estimate
    before it (from the start of ``estimates``) is a partial measurement and skipped. None if
    there is none yet."""
    prev = None
    most = 0
    for m in estimates:
        partial = m.points < min_points_ratio * most
        most = max(most, int(m.points))
        if time_to_sec(m.header.stamp) <= after or m.points == 0 or partial:
            continue
        if m.state != "still":
            prev = None
            continue
        p = np.array([m.position.x, m.position.y, m.position.z])
        if prev is not None and np.linalg.norm(p - prev) <= tolerance:
            return m
        prev = p
    return None


def estimates_summary(estimates: list, after: float) -> str:
    """What the /motion/target/estimate messages stamped after ``after`` [s] said, in one
    line (why no settled still target came): how many per state, the points of the still
    ones against the most any estimate had, and the spread of the still positions [mm]."""
    late = [m for m in estimates if time_to_sec(m.header.stamp) > after]
    if not late:
        return "no estimate stamped after it"
    states: dict[str, int] = {}
    for m in late:
        states[m.state or "?"] = states.get(m.state or "?", 0) + 1
    most = max((int(m.points) for m in estimates), default=0)
    still = [m for m in late if m.state == "still" and m.points > 0]
    text = ", ".join(f"{n} {s}" for s, n in sorted(states.items()))
    if still:
        pts = [int(m.points) for m in still]
        pos = np.array([[m.position.x, m.position.y, m.position.z] for m in still])
        step = (np.linalg.norm(np.diff(pos, axis=0), axis=1) * 1e3 if len(pos) > 1
                else np.zeros(0))
        text += (f"; still points {min(pts)}-{max(pts)} (most of any estimate {most}, "
                 f"partial below {STILL_MIN_POINTS_RATIO * most:.0f})")
        if step.size:
            text += f", still steps {step.min():.1f}-{step.max():.1f} mm"
    last = late[-1]
    text += (f"; the last ({last.state}, source {last.source or '?'}) at "
             f"{np.round([last.position.x, last.position.y, last.position.z], 3).tolist()}")
    return text


def wait_still_target(runner: DemoRunner, after: float, timeout: float = 3.0):  # noqa: ANN201
    """The first settled still /motion/target/estimate stamped after ``after`` [s]
    (:func:`settled_still_estimate`), waiting up to ``timeout`` s of simulated time; None if
    none."""
    end = runner.sim_time() + timeout

    def found():  # noqa: ANN202
        # a copy: the probe's spin thread appends to the deque meanwhile
        return settled_still_estimate(list(runner.estimates), after)

    runner.probe.wait_for(lambda: found() is not None or runner.sim_time() >= end, 300.0)
    return found()


#: the body's midline in root_link (y = 0) splits the table between the arms: an object on
#: the left of it (y < 0) is reached with the left hand, else with the right (the arm on the
#: object's side, as the iCub's reaching demos choose it, docs/decisions/0058 rule 13)
REACHING_ARM_SPLIT_Y = 0.0


def reaching_arm(top: np.ndarray) -> str:
    """The hand that reaches an object whose top centre is at ``top`` (3,) [m, root_link]:
    ``left`` for an object left of the body's midline (``y < REACHING_ARM_SPLIT_Y``), else
    ``right``: a hand reaching across the body passes over the other, resting hand."""
    return "left" if float(top[1]) < REACHING_ARM_SPLIT_Y else "right"


def vision_reach(runner: DemoRunner, start: np.ndarray, velocity: np.ndarray, duration: float,
                 bias: np.ndarray | None = None, name: str = "vision_reach",
                 arm: str | None = None) -> PhaseResult:
    """Phase 3: move the cylinder from ``start`` [m] at ``velocity`` [m/s] for ``duration``
    [s] while the head tracks the stereo target; once the target is still, reach the
    pre-grasp point above its top with the hand on its side (:func:`reaching_arm`; ``arm``
    forces one), via a point above when needed, and judge against the ground truth
    (:func:`judge_vision_reach`). ``bias`` (3,) [m] is added to the estimate before the reach
    (tests prove with it that the judge can fail)."""
    from icub_pmp.pmp.pre_grasp import PreGrasp

    pre = PreGrasp()
    runner.look_at(np.array([-0.36, float(start[1] + 0.5 * velocity[1] * duration), -0.03]))
    runner.set_object("cylinder", start)
    runner.wait_sim(0.3)
    # a new object is shown: what the eyes followed before (a place the last reach left, a
    # target held for up to hold_time) must not keep the gaze away from it (0058, rule 12)
    runner.reset_target()
    runner.set_tracking(True)
    runner.estimates.clear()
    # the simulator moves the cylinder in simulated time: it stops at exactly t_end
    t0, t_end = runner.move_object("cylinder", start, velocity, duration)
    est = wait_still_target(runner, t_end)
    if est is None:
        runner.set_tracking(False)
        return PhaseResult(name, False, "no still stereo target of the cylinder after it "
                           "stopped (/motion/target/estimate: "
                           f"{estimates_summary(list(runner.estimates), t_end)})", sim_start=t0,
                           extra={"motion_s": t_end - t0})
    stamp = time_to_sec(est.header.stamp)
    first = min((time_to_sec(m.header.stamp) for m in list(runner.estimates)),
                default=stamp)
    position = np.array([est.position.x, est.position.y, est.position.z])
    top = np.array([est.top.x, est.top.y, est.top.z])
    target_error = float(np.linalg.norm(position - runner.object_position_at("cylinder", stamp)))
    if bias is not None:
        top = top + np.asarray(bias, float)
    arm = arm or reaching_arm(top)
    hand = runner.hand_positions()[arm]
    points = pre.waypoints(hand, top, est.radius, est.height)
    object_before = runner.object_position("cylinder")
    goal_sent = runner.sim_time() - t0
    for k, p in enumerate(points[:-1]):
        runner.pmp_reach(f"{name}_via{k}", {arm: p}, use_torso=True, tau=1.5,
                         judge_physics=False)
    vr = runner.pmp_reach(name, {arm: points[-1]}, use_torso=True, tau=1.5,
                          judge_physics=False)
    runner.set_tracking(False)
    truth = runner.object_position("cylinder")
    ok, message, figures = judge_vision_reach(
        runner.hand_positions()[arm], truth, cylinder_height(), pre.config.clearance,
        target_error, float(np.linalg.norm(truth - object_before)))
    cov = np.array(est.covariance).reshape(3, 3)
    vr.extra.update(figures)
    vr.extra.update({
        "target_sigma_m": float(np.sqrt(max(np.linalg.eigvalsh(cov)[-1], 0.0))),
        "target_age_s": runner.sim_time() - stamp,
        "first_target_after_motion_s": first - t0,
        "via_points": float(len(points) - 1),
        "goal_sent_s": goal_sent,
        "motion_s": t_end - t0,
        "left_arm": float(arm == "left"),
    })
    vr.success = bool(vr.success and ok)
    vr.message = f"{arm} hand: {message} ({vr.message})"
    vr.sim_start = t0
    return vr


def cylinder_obstacle(position: np.ndarray) -> object:
    """The cylinder at ``position`` [m, root_link] as a PMP obstacle: the box around it
    (2 radius x 2 radius x height, config/sim_bridge.yaml), upright."""
    from icub_interfaces.msg import Obstacle
    from icub_pmp.config import config_dir, load_params_file

    params = load_params_file(config_dir() / "sim_bridge.yaml", "sim_bridge")
    ob = Obstacle()
    ob.type = "box"
    ob.header.frame_id = "root_link"
    ob.pose.position.x, ob.pose.position.y, ob.pose.position.z = (float(v) for v in position)
    ob.pose.orientation.w = 1.0
    ob.size.x = ob.size.y = 2.0 * float(params["cylinder_radius"])
    ob.size.z = float(params["cylinder_height"])
    return ob


#: phase 5: the right hand's start and target on either side of the cylinder, placed between
#: them on the table [m, root_link], and the clearance the plan keeps from it [m]: the planner
#: keeps the hand's, wrist's and forearm's collision hulls that far (``obstacle_body_links``,
#: docs/decisions/0060; with only the hand frame kept clear the fingers, up to 10 cm from it,
#: brushed the cylinder's top in demo runs). The straight way passes the hand frame 1-3 cm
#: above the top, the fingers 4 cm below the frame through it. The target is raised so that
#: the forearm, which ends above the cylinder, clears it without turning the wrist fast near
#: the end (at 2 cm the plan turned r_wrist_prosup at 5.6 rad/s, and the hand ended 3.7 cm
#: off in the physics).
OBSTACLE_START = np.array([-0.36, 0.34, 0.04])
OBSTACLE_TARGET = np.array([-0.36, 0.0, 0.06])
OBSTACLE_POSITION = np.array([-0.36, 0.17, -0.03])
OBSTACLE_CLEARANCE = 0.02


def obstacle_reach(runner: DemoRunner, name: str = "obstacle_reach") -> PhaseResult:
    """Phase 5: the cylinder is placed on the table between the right hand and its target;
    the reach goes through /pmp/reach_action with the cylinder as an obstacle (built from its
    ground-truth pose, as a perception node would give it) and is judged in the physics
    (:func:`judge_obstacle_reach`: arrival, no robot-object contact on
    /ground_truth/object_contacts, the cylinder not moved)."""
    runner.pmp_reach(f"{name}_up", {"right": np.array([-0.22, 0.34, 0.12])},
                     use_torso=True, tau=1.5, judge_physics=False)
    runner.set_object("cylinder", OBSTACLE_POSITION)
    runner.wait_sim(0.3)
    runner.pmp_reach(f"{name}_start", {"right": OBSTACLE_START}, use_torso=True, tau=1.5,
                     judge_physics=False)
    before = runner.object_position("cylinder")
    runner.object_contacts = []
    try:
        r = runner.pmp_reach(name, {"right": OBSTACLE_TARGET}, use_torso=True, tau=3.0,
                             judge_physics=False, obstacles=[cylinder_obstacle(before)],
                             obstacle_clearance=OBSTACLE_CLEARANCE)
    finally:
        touching, runner.object_contacts = runner.object_contacts, None
    moved = float(np.linalg.norm(runner.object_position("cylinder") - before))
    ok, message, figures = judge_obstacle_reach(
        runner.hand_positions()["right"], OBSTACLE_TARGET,
        [link for link, obj in touching if obj == "cylinder"], moved)
    r.extra.update(figures)
    r.success = bool(r.success and ok)
    r.message = f"{message} ({r.message})"
    return r


def joint_stiffness(joints: list[str]) -> dict[str, float]:
    """The position-mode stiffness [N m/rad] of ``joints`` (config/impedance_controller.yaml;
    the demo runs the controller in position mode)."""
    from icub_pmp.config import config_dir
    from icub_pmp.control import ImpedanceControllerConfig
    from icub_pmp.kinematics import RobotSpec

    cfg = ImpedanceControllerConfig.from_yaml(config_dir() / "impedance_controller.yaml",
                                              "impedance_controller")
    k = dict(zip(RobotSpec.load().actuated_joints, cfg.gains("position", "stiffness")))
    return {j: k[j] for j in joints}


#: phase 6: the point of the table top the right hand presses on [m, root_link] (table top
#: surface z = -0.09, config/sim_bridge.yaml) and the force it exerts on it [N]
PRESS_POINT = np.array([-0.30, 0.15, -0.09])
PRESS_FORCE = np.array([0.0, 0.0, -10.0])
#: the force loop: at most PRESS_MAX_ITERATIONS corrected presses, stopping once the estimate
#: is within PRESS_STOP_TOLERANCE of the target (below the judged PRESS_FORCE_TOLERANCE)
PRESS_MAX_ITERATIONS = 8
PRESS_STOP_TOLERANCE = 0.04
#: the largest move of the press target in one correction [m] (about 4 N at the fingertips)
PRESS_MAX_STEP = 0.004
#: each press's force: settle, then average the estimate over this [s of simulated time]
PRESS_SETTLE = 0.3
PRESS_AVERAGE = 0.3
#: where the cylinder waits during the press (far corner of the table) [m, root_link]
PRESS_CYLINDER_AWAY = np.array([-0.56, 0.38, -0.03])


def hand_contact_point(model: IcubModel, q: np.ndarray, link: str = "r_hand") -> np.ndarray:
    """The lowest point (3,) [m, root_link] of ``link``'s collision hull at posture ``q``:
    where a hand lowered onto the table touches it (the fingertips, up to 6 cm below the hand
    frame in the demo's press posture)."""
    from icub_pmp.geometry import LinkHull

    hull = _hand_hulls().get(link)
    if not isinstance(hull, LinkHull):
        raise KeyError(f"no collision hull for {link}")
    pose = model.frame_pose(q, link)
    pts = hull.points @ np.asarray(pose.rotation).T + np.asarray(pose.translation)
    return pts[int(np.argmin(pts[:, 2]))]


def _hand_hulls() -> dict:
    """link -> LinkHull of both hands' collision meshes (built once)."""
    if not hasattr(_hand_hulls, "cache"):
        from icub_pmp.geometry import urdf_link_hulls
        from icub_pmp.kinematics.robot_spec import HANDS, RobotSpec

        spec = RobotSpec.load()
        _hand_hulls.cache = {h.frame: h for arm in HANDS
                             for h in urdf_link_hulls(spec, arm, ("hand",))}
    return _hand_hulls.cache


def contact_compliance(model: IcubModel, q: np.ndarray, frame: str, contact: np.ndarray,
                       joint_stiffness: dict[str, float], keep_orientation: bool = False
                       ) -> np.ndarray:
    """``C = J_h K^-1 J_c^T`` (3, 3) [m/N]: how far the set-point of ``frame``'s origin must go
    beyond its measured position for the joint springs to push with a force at ``contact``
    (3,) [m] on the same link (``J_c = J_v - [c - x_h]x J_w``), the set-point's orientation
    free. With ``keep_orientation`` the set-point keeps the orientation the hand had before
    the load, while the loaded hand turns about the pinned contact by ``J_w K^-1 J_c^T F``,
    which moves the frame by ``[x_h - c]x`` that: ``C = J_c K^-1 J_c^T`` (the contact
    point's own compliance; docs/decisions/0069)."""
    names = list(joint_stiffness)
    k = np.array([joint_stiffness[n] for n in names], dtype=float)
    J = model.frame_jacobian(q, frame)[:, model.indices(names)]
    r = np.asarray(contact, float) - model.frame_position(q, frame)
    skew = np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])
    Jc = J[:3] - skew @ J[3:]
    return ((Jc if keep_orientation else J[:3]) / k) @ Jc.T


def _log_press(runner: DemoRunner, label: str, target: np.ndarray, exerted: np.ndarray
               ) -> None:
    """Print one press's figures: the hand frame's target, the force exerted as estimated
    and as the simulator's contact force, the hand frame and the fingertip (hull's lowest
    point) measured, the torso [deg]."""
    q = runner.q()
    gt = runner.latest.get("gt_right")
    g = (np.full(3, np.nan) if gt is None else
         -np.array([gt.wrench.force.x, gt.wrench.force.y, gt.wrench.force.z]))
    torso = q[runner.model.indices(list(runner.model.spec.torso_joints))]
    err = float(np.linalg.norm(exerted - PRESS_FORCE) / np.linalg.norm(PRESS_FORCE))

    def f(v: np.ndarray, n: int = 4) -> list:
        return np.round(np.asarray(v, float), n).tolist()

    hand = runner.hand_positions()["right"]
    print(f"demo: {label}: target {f(target)} m, force exerted {f(exerted, 2)} N "
          f"({err * 100:.1f} % off; simulator {f(g, 2)} N), hand {f(hand)}"
          f" m, fingertip {f(hand_contact_point(runner.model, q))} m, torso "
          f"{f(np.degrees(torso), 2)} deg", flush=True)


def _press_force(runner: DemoRunner) -> np.ndarray:
    """The force (3,) [N] the right hand exerts on the world: minus the estimator's external
    force, averaged over ``PRESS_AVERAGE`` s after ``PRESS_SETTLE`` s of settling."""
    runner.wait_sim(PRESS_SETTLE)
    t = runner.sim_time()
    runner.wait_sim(PRESS_AVERAGE)
    return -runner.force_since("right", t)


def press(runner: DemoRunner, name: str = "press") -> PhaseResult:
    """Phase 6: the right hand presses down on the table top with ``PRESS_FORCE``.

    The controller is a joint spring (position mode, ``tau = -K (q - q_d) + g``): a force is
    realised by a target beyond the surface, ``x_contact + C F`` with the compliance
    ``C = J_h K^-1 J_c^T`` of the hand frame for a force at the contact point (the lowest
    point of the hand's collision hull: the fingertips, about 5 cm below the frame;
    :func:`contact_compliance`). The hand goes above the point, then with its orientation
    kept (``use_orientation``, the orientation measured above the point) down until the
    fingertips touch the table (:func:`hand_contact_point`),
    then up to ``PRESS_MAX_ITERATIONS`` reaches through /pmp/reach_action with the force
    target (``right_force``) correct the target from the wrench estimator's force
    (:class:`~icub_pmp.control.press_loop.PressLoop`: an outer force loop on the estimate, as
    the iCub's force control closes it on the FT sensors, with Broyden's update of ``C``
    guarded against secants that disagree with the model, a capped step and a return to the
    best press), until the estimate is within ``PRESS_STOP_TOLERANCE``; when the last press
    is not the best, the hand goes back to the best one's target. Without the kept
    orientation the planner's position-only target let the hand turn about the fingertips:
    the frame went down with the target, the force did not (docs/decisions/0069).
    Judged by :func:`judge_press` on the last press's estimate (mean over
    ``PRESS_AVERAGE`` s), the simulator's contact force reported beside it."""
    from icub_pmp.control.press_loop import PressLoop, PressLoopConfig
    from icub_pmp.kinematics.rotations import matrix_to_quat_wxyz

    spec = runner.model.spec
    stiffness = joint_stiffness(list(spec.torso_joints) + list(spec.arm_joints("right")))
    frame = spec.hand_frame("right")
    runner.set_object("cylinder", PRESS_CYLINDER_AWAY)  # phase 5 left it beside the point
    runner.pmp_reach(f"{name}_above", {"right": PRESS_POINT + [0.0, 0.0, 0.08]},
                     use_torso=True, tau=1.5, judge_physics=False)
    # from here the hand keeps the orientation it has above the point
    q = runner.q()
    above = runner.model.frame_pose(q, frame)
    keep = {"right": matrix_to_quat_wxyz(np.asarray(above.rotation))}
    # touch: the hand frame lowered until its hull's lowest point (the fingertips) is 3 mm
    # into the table top, then 1 cm further while the estimator feels less than 1 N
    drop = float(above.translation[2]) - hand_contact_point(runner.model, q)[2]
    touch = PRESS_POINT + [0.0, 0.0, drop - 0.003]
    norm = float(np.linalg.norm(PRESS_FORCE))
    for _ in range(4):
        runner.pmp_reach(f"{name}_touch", {"right": touch}, use_torso=True, tau=1.5,
                         judge_physics=False, orientations=keep)
        exerted = _press_force(runner)
        if float(exerted @ PRESS_FORCE) / norm >= 1.0:
            break
        touch = touch + [0.0, 0.0, -0.01]
    _log_press(runner, f"{name}_touch", touch, exerted)
    q = runner.q()
    contact = runner.hand_positions()["right"]  # the hand at the measured contact posture
    C = contact_compliance(runner.model, q, frame, hand_contact_point(runner.model, q),
                           stiffness, keep_orientation=True)
    # the touch is the loop's first press: its target and force are measured like the others
    loop = PressLoop(PRESS_FORCE, C, PressLoopConfig(stop_tolerance=PRESS_STOP_TOLERANCE,
                                                     max_step=PRESS_MAX_STEP))
    loop.record(touch, exerted)

    def press_at(label: str, target: np.ndarray) -> PhaseResult:
        res = runner.pmp_reach(label, {"right": target}, use_torso=True, tau=1.0,
                               judge_physics=False, forces={"right": PRESS_FORCE},
                               orientations=keep)
        rec = loop.record(target, _press_force(runner))
        _log_press(runner, label, target, rec.exerted)
        return res

    r = None
    for k in range(PRESS_MAX_ITERATIONS):
        r = press_at(f"{name}_{k}", loop.next_target())
        if loop.done:
            break
    if r is None:  # PRESS_MAX_ITERATIONS < 1
        raise RuntimeError("press: no press was made")
    returned = loop.presses[-1] is not loop.best
    if returned:  # end on the best press: back to its target, measured again
        r = press_at(f"{name}_best", loop.best.target)
    final = loop.presses[-1]
    r.name = name
    r.extra["press_depth_m"] = float(np.linalg.norm(final.target - contact))
    r.extra["press_iterations"] = float(len(loop.presses) - 1)
    r.extra["press_touch_error_rel"] = loop.presses[0].error
    r.extra["press_first_error_rel"] = loop.presses[1].error
    r.extra["press_returned_to_best"] = float(returned)
    # the compliance down, the model's and as fitted by the loop [m/N]
    r.extra["press_model_compliance_zz"] = float(loop.model[2, 2])
    r.extra["press_fitted_compliance_zz"] = float(loop.compliance[2, 2])
    r.extra["press_secants_rejected"] = float(sum(
        1 for p in loop.presses[1:] if p.base >= 0 and not p.secant_accepted))
    r.extra.update({f"press_error_rel_{k}": p.error for k, p in enumerate(loop.presses[1:])})
    gt = runner.latest.get("gt_right")
    truth = None if gt is None else np.array([gt.wrench.force.x, gt.wrench.force.y,
                                              gt.wrench.force.z])
    ok, message, figures = judge_press(-final.exerted, PRESS_FORCE, truth)
    r.extra.update(figures)
    r.success = bool(r.success and ok)
    r.message = f"{message} after {len(loop.presses) - 1} presses ({r.message})"
    # lift the hand off the table
    runner.pmp_reach(f"{name}_off", {"right": PRESS_POINT + [0.0, 0.0, 0.08]},
                     use_torso=True, tau=1.0, judge_physics=False)
    return r


#: the demo controller's wall-time watchdog on joint states [s] (the shipped config's is 2 s)
DEMO_STATE_WALL_TIMEOUT = 10.0


def graph_parameters(realism: str | None = None) -> dict[str, dict[str, object]]:
    """The demo's node parameters over their config files: the simulator in lockstep with the
    controller, every other node on simulated time; ``realism`` sets the simulator's
    ``realism.preset`` and what goes with it (:func:`~icub_pmp.graph.realism_parameters`:
    the controller's friction compensation, the segmenter's eye calibration); None = the
    shipped config files' (``icub``)."""
    preset = realism_parameters(realism) if realism is not None else {}
    sim: dict[str, object] = {"mode": "lockstep", "use_sim_time": False,
                              **preset.get("sim_bridge", {})}
    # stiff position tracking for the reaches (the compliant mode is the controller's
    # default; config/impedance_controller.yaml)
    # state_wall_timeout: the lockstep simulator may stall for more than the shipped 2 s of
    # wall time on a loaded machine (cameras rendering beside the solvers): a run at load 9-13
    # went to safe hold in the Cartesian reach (0066); 10 s still finds a simulator gone
    controller: dict[str, object] = {"lockstep": True, "use_sim_time": True, "mode": "position",
                                     "state_wall_timeout": DEMO_STATE_WALL_TIMEOUT,
                                     **preset.get("impedance_controller", {})}
    segmenter: dict[str, object] = {"use_sim_time": True, **preset.get("motion_segmenter", {})}
    return {
        "sim_bridge": sim,
        "impedance_controller": controller,
        "wrench_estimator": {"use_sim_time": True},
        # the transport keeps the hands' orientations (use_orientation): a stiff orientation
        # field holds them along the way, not only at the end (docs/decisions/0053)
        "pmp_planner": {"use_sim_time": True, "rotation_stiffness": TRANSPORT_ROTATION_STIFFNESS},
        "cartesian_solver": {"use_sim_time": True},
        "motion_segmenter": segmenter,
        # a look_at's wait is bounded in wall time: under load the lockstep graph may run at a
        # few per cent of real time
        "gaze_controller": {"use_sim_time": True, "wait_timeout": 180.0},
        "robot_state_publisher": {"use_sim_time": True},
    }


#: box half width along y (config/sim_bridge.yaml box_size / 2) and the palm frame's offset from
#: the box side at the pre-grasp [m]
BOX_HALF_WIDTH = 0.10
PREGRASP_GAP = 0.045
#: the hand frames' offset outside the box sides at the squeeze's first reach [m]: the palms,
#: about 2 cm from the frames, are commanded a few mm into the box (measured squeeze per hand
#: on ideal before the contact patches were aimed: 8.3-8.6 N; 0.008 gave 14-15 N). The force
#: loop (:func:`hold_squeeze`) then sets the squeeze to SQUEEZE_FORCE from the estimated force
SQUEEZE_OFFSET = 0.012

#: the squeeze's force loop (:func:`hold_squeeze`): the force of the box on each palm [N]
#: along the hand-to-hand axis (none along x and z: the hands carry their own weight, not the
#: box), corrected at most SQUEEZE_ITERATIONS times until every component of both hands is
#: within SQUEEZE_FORCE_TOLERANCE [N]
SQUEEZE_FORCE = 9.0
SQUEEZE_ITERATIONS = 4
SQUEEZE_FORCE_TOLERANCE = 1.0

#: where the palms' contacts go on the box sides, from the box centre [m, root_link]: above
#: the centre of mass on the vertical through it, so that the held box hangs from the line
#: through the two contacts instead of swinging about it (:func:`palm_contact_offsets`)
SQUEEZE_CONTACT_HEIGHT = 0.01
#: hull points within this of a palm's innermost point form its contact patch [m]
PALM_PATCH_DEPTH = 0.003


def palm_contact_offsets(model: IcubModel, q: np.ndarray, box: np.ndarray
                         ) -> dict[str, np.ndarray]:
    """Each hand's contact patch on the box side against the hands' line through the box's
    centre of mass (``box`` (3,) [m], root_link) at posture ``q``: the centroid of the
    hand's collision hull points within ``PALM_PATCH_DEPTH`` of its innermost point along the
    hand-to-hand axis (y; the left hand is on the -y side), minus the point
    ``SQUEEZE_CONTACT_HEIGHT`` above the centre, x and z only (y = 0) [m]. The two palms touch
    a squeezed box in one small patch each (the convex hulls give one contact per pair),
    which leaves the box free to turn about the line through them: a line in front of or
    below the centre of mass lets it swing out of the grip at the lift (0066)."""
    from icub_pmp.geometry import LinkHull

    out = {}
    aim = np.asarray(box, float) + [0.0, 0.0, SQUEEZE_CONTACT_HEIGHT]
    for h, link, inward in (("left", "l_hand", 1.0), ("right", "r_hand", -1.0)):
        hull = _hand_hulls().get(link)
        if not isinstance(hull, LinkHull):
            raise KeyError(f"no collision hull for {link}")
        pose = model.frame_pose(q, link)
        pts = hull.points @ np.asarray(pose.rotation).T + np.asarray(pose.translation)
        depth = inward * pts[:, 1]
        patch = pts[depth >= depth.max() - PALM_PATCH_DEPTH]
        off = patch.mean(axis=0) - aim
        off[1] = 0.0
        out[h] = off
    return out


def bimanual_compliance(model: IcubModel, q: np.ndarray,
                        stiffness: dict[str, float]) -> np.ndarray:
    """``C = J K^-1 J^T`` (6, 6) [m/N] of both hand frames (left rows 0-2, right 3-5) for
    forces at the frames, through the joints of ``stiffness`` (the torso shared by both
    arms): how the hands' set-points must move for the position-mode joint springs to change
    the forces they exert by a given amount."""
    names = list(stiffness)
    k = np.array([stiffness[n] for n in names], dtype=float)
    idx = model.indices(names)
    J = np.vstack([model.frame_jacobian(q, model.spec.hand_frame(h))[:3, idx]
                   for h in ("left", "right")])
    return (J / k) @ J.T


def squeeze_force_error(forces: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The force of the box on each hand (``forces``: hand -> (3,) [N], root_link, as the
    wrench estimator gives it) minus the squeeze's target: ``SQUEEZE_FORCE`` pushing the left
    palm towards -y and the right towards +y, nothing along x and z."""
    target = {"left": np.array([0.0, -SQUEEZE_FORCE, 0.0]),
              "right": np.array([0.0, SQUEEZE_FORCE, 0.0])}
    return {h: np.asarray(forces[h], float) - target[h] for h in ("left", "right")}


def hold_squeeze(runner: DemoRunner, targets: dict[str, np.ndarray], name: str = "squeeze"
                 ) -> tuple[dict[str, np.ndarray], dict[str, float]]:
    """The squeeze as a force loop on the wrench estimator's contact forces: from the hands'
    ``targets`` (just reached, the palms on the box), up to ``SQUEEZE_ITERATIONS`` times the
    estimated force of the box on each hand (mean over 0.3 s) is compared with
    :func:`squeeze_force_error`'s target and both set-points move by ``C (F - F_target)``
    (:func:`bimanual_compliance`). Besides the squeeze along the hand-to-hand axis this
    removes what the joint springs' model gravity leaves on the box: with the masses of the
    ``icub`` robot the hands hang on the box with 6-8 N each, which turns into the box's
    weight at the lift and lets the grip roll and slip (docs/decisions/0066). Returns the
    corrected targets and figures (the force errors before and after)."""
    spec = runner.model.spec
    stiffness = joint_stiffness(list(spec.torso_joints) + list(spec.arm_joints("left"))
                                + list(spec.arm_joints("right")))
    targets = {h: np.asarray(p, float).copy() for h, p in targets.items()}
    figures: dict[str, float] = {}
    for k in range(SQUEEZE_ITERATIONS + 1):
        runner.wait_sim(0.3)
        t = runner.sim_time()
        runner.wait_sim(0.3)
        err = squeeze_force_error({h: runner.force_since(h, t) for h in ("left", "right")})
        worst = max(float(np.max(np.abs(e))) for e in err.values())
        if k == 0:
            figures.update({f"squeeze_force_error_first_{h}_N": float(np.linalg.norm(e))
                            for h, e in err.items()})
        for h, e in err.items():
            figures[f"squeeze_force_error_{h}_N"] = float(np.linalg.norm(e))
            figures.update({f"squeeze_force_error_{h}_{a}_N": float(v)
                            for a, v in zip("xyz", e)})
        figures["squeeze_corrections"] = float(k)
        if worst <= SQUEEZE_FORCE_TOLERANCE or k == SQUEEZE_ITERATIONS:
            break
        C = bimanual_compliance(runner.model, runner.q(), stiffness)
        dx = C @ np.concatenate([err["left"], err["right"]])
        targets = {"left": targets["left"] + dx[:3], "right": targets["right"] + dx[3:]}
        runner.pmp_reach(f"{name}_{k}", targets, use_torso=True, tau=0.5, judge_physics=False)
    return targets, figures


def bimanual_pregrasp(box: np.ndarray) -> dict[str, np.ndarray]:
    """Phase 1's hand targets: beside the box's two sides, at its centre height."""
    return {"left": box + [0.0, -(BOX_HALF_WIDTH + PREGRASP_GAP), 0.0],
            "right": box + [0.0, BOX_HALF_WIDTH + PREGRASP_GAP, 0.0]}


def run_phases(runner: DemoRunner, quick: bool,
               results: list[PhaseResult] | None = None,
               phases: tuple[str, ...] = PHASES) -> list[PhaseResult]:
    """The demo's ``phases`` (:data:`PHASES`), appended to ``results`` as each ends (so an
    error of the graph keeps what the earlier phases measured); from phase 3 on a phase that
    fails or times out does not stop the next one."""
    results = [] if results is None else results
    if "bimanual" in phases:
        bimanual_phases(runner, results)
    target = None
    if "vision" in phases:
        print("demo: phase 3, the eyes find the moving cylinder, the hand goes above it",
              flush=True)
        vr = guarded("vision_reach", lambda: vision_reach(
            runner, np.array([-0.36, -0.12, -0.03]), np.array([0.0, 0.2, 0.0]), 1.2), runner)
        results.append(vr)
        target = vr.targets.get("right")
    if "cartesian" in phases:
        if target is None:
            target = runner.object_position("cylinder") + [0, 0, 0.12]
        print("demo: phase 4, the same target with the Cartesian solver", flush=True)
        runner.pmp_reach("back", {"right": np.array([-0.22, 0.25, 0.12])}, use_torso=True,
                         tau=1.5, judge_physics=False)
        results.append(guarded("cartesian_reach", lambda: runner.cartesian_reach(
            "cartesian_reach", np.asarray(target)), runner))
    if "obstacle" in phases:
        print("demo: phase 5, a reach around the cylinder placed on the table", flush=True)
        results.append(guarded("obstacle_reach", lambda: obstacle_reach(runner), runner))
    if "press" in phases:
        print("demo: phase 6, the right hand presses on the table with 10 N", flush=True)
        results.append(guarded("press", lambda: press(runner), runner))
    return results


def bimanual_phases(runner: DemoRunner, results: list[PhaseResult]) -> None:
    """Phases 1-2: the bimanual reach to the box, the squeeze and the coupled transport
    (appended to ``results``); then the hands let the box go and the box leaves the table."""
    box = runner.object_position("box")
    half_w = BOX_HALF_WIDTH
    pre = bimanual_pregrasp(box)
    print("demo: phase 1, bimanual PMP reach to the box", flush=True)
    results.append(runner.pmp_reach("bimanual_reach", pre, use_torso=True, tau=2.0))
    print("demo: phase 2, bimanual squeeze and lift", flush=True)
    # squeeze: the hand frames are commanded SQUEEZE_OFFSET outside the box sides, which puts
    # the palms (about 1.5 cm from the frames) a few mm inside: the stiff joint controller
    # presses them on the box (about 8 N each); judged by the estimator's contact flags
    squeeze = {"left": box + [0.0, -(half_w + SQUEEZE_OFFSET), 0.0],
               "right": box + [0.0, half_w + SQUEEZE_OFFSET, 0.0]}
    # the palms' contacts above the box's centre of mass (palm_contact_offsets), measured at
    # the pre-grasp posture the squeeze starts from
    offsets = palm_contact_offsets(runner.model, runner.q(), box)
    squeeze = {h: p - offsets[h] for h, p in squeeze.items()}
    r = runner.pmp_reach("bimanual_squeeze", squeeze, use_torso=True, tau=1.0,
                         judge_physics=False)
    r.extra.update({f"palm_contact_offset_{h}_{a}_m": float(v) for h, o in offsets.items()
                    for a, v in zip("xz", o[[0, 2]])})
    contact = runner.contacts()
    r.extra.update({f"contact_{h}": float(v) for h, v in contact.items()})
    for h in ("left", "right"):
        gt = runner.latest.get(f"gt_{h}")
        if gt is not None:
            f = gt.wrench.force
            r.extra[f"gt_force_{h}_N"] = float(np.linalg.norm([f.x, f.y, f.z]))
    if r.success and not all(contact.values()):
        r.success = False
        r.message += f"; contact flags {contact} (both hands should touch the box)"
    # the squeeze held by a force loop on the estimated contact forces (hold_squeeze)
    squeeze, figures = hold_squeeze(runner, squeeze)
    r.extra.update(figures)
    runner.wait_sim(0.5)  # the squeeze settles
    box0 = runner.object_position("box")
    # the object coupling (Sect. 3.2): the grasp points are where the hands are commanded (the
    # planner starts a transport from the controller's set-point, so the squeeze is kept)
    r2 = runner.pmp_transport("bimanual_transport", box0, box0 + [0.0, 0.0, 0.08], tau=2.0)
    ok, message, figures = judge_transport(runner.transport_distances,
                                           float(runner.object_position("box")[2] - box0[2]))
    r2.extra.update(figures)
    r2.success = bool(r2.success and ok)
    r2.message = f"{message} ({r2.message})"
    results += [r, r2]
    # open the hands (the box drops back on the table), then clear the table for phase 3
    runner.pmp_reach("release", {h: p + [0.0, 0.0, 0.08] for h, p in pre.items()},
                     use_torso=True, tau=1.0, judge_physics=False)
    runner.pmp_reach("hands_up", {"left": np.array([-0.22, -0.25, 0.12]),
                                  "right": np.array([-0.22, 0.25, 0.12])},
                     use_torso=True, tau=1.5, judge_physics=False)
    runner.set_object("box", np.array([-0.52, -0.33, -0.05]))


def guarded(name: str, phase: Callable[[], PhaseResult], runner: DemoRunner) -> PhaseResult:
    """Run ``phase``; an exception (a timeout, a missing message) fails this phase only, with
    its reason, so the next phase still runs."""
    t0 = runner.sim_time()
    try:
        return phase()
    except (RuntimeError, TimeoutError, KeyError, ValueError) as exc:
        return PhaseResult(name, False, f"{type(exc).__name__}: {exc}", sim_start=t0,
                           sim_end=runner.sim_time())


def replay_check(bag_dir: Path, env: dict[str, str]) -> dict[str, object]:
    """Replay the bag (icub bag play) to a counting subscriber; compare with the bag's counts."""
    out: dict[str, object] = {"ok": False}
    if not (bag_dir / "metadata.yaml").exists():
        out["message"] = "no bag was written"
        return out
    info = subprocess.run([str(repo_root() / "scripts/env.sh"), "icub", "bag", "info",
                           str(bag_dir)], capture_output=True, text=True, env=env, timeout=120)
    out["info"] = info.stdout
    with reserve_domain_id() as dom:
        from rclpy.qos import QoSProfile, ReliabilityPolicy
        from sensor_msgs.msg import JointState

        probe = RosProbe(dom, "demo_replay_check")
        got: list[float] = []
        qos = QoSProfile(depth=1000, reliability=ReliabilityPolicy.BEST_EFFORT)
        probe.node.create_subscription(JointState, "/joint_states",
                                       lambda m: got.append(time.monotonic()), qos)
        cmd = [str(repo_root() / "scripts/replay.sh"), str(bag_dir), "--topics", "/joint_states",
               "--rate", "2.0", "--wait-for-subscribers", "20", "--delay", "1.0"]
        play = subprocess.run(cmd, capture_output=True, text=True, env=ros_environment(dom),
                              timeout=1800)
        probe.wait_for(lambda: False, 1.0)
        probe.close()
    out["replay_stdout"] = play.stdout[-2000:]
    recorded = _count_in_bag(bag_dir, "/joint_states")
    out["recorded_joint_states"] = recorded
    out["replayed_joint_states"] = len(got)
    # best-effort QoS as recorded: a replay may lose a few messages, never most of them
    out["ok"] = play.returncode == 0 and recorded > 0 and len(got) >= 0.9 * recorded
    out["message"] = (f"replay exit {play.returncode}: {len(got)} of {recorded} recorded "
                      "/joint_states received by a subscriber")
    return out


def _count_in_bag(bag_dir: Path, topic: str) -> int:
    from icub_pmp.bags import BagReader
    from icub_pmp.errors import BagError

    try:
        return sum(t.count for t in BagReader(bag_dir).info().topics if t.name == topic)
    except BagError:  # unreadable bag: the replay check fails on its own
        return 0


# ----------------------------------------------------------------- tabletop (issue 19)
#: the tabletop phase's extra node (``--tabletop``)
TABLETOP_GRAPH = ["peripersonal_space"]
#: where the tabletop cubes wait until their phase (behind the robot, below the table) [m]
TABLETOP_AWAY = (0.6, -0.3, -0.55)


def tabletop_parameters(params: dict[str, dict[str, object]]) -> dict[str, dict[str, object]]:
    """The demo's node parameters with the tabletop phase's: the task's cubes in the simulator
    (behind the robot until the phase puts them on the table: the other phases' scene is
    unchanged), ``peripersonal_space`` on simulated time with the saved maps (the phase grows
    them first if there are none)."""
    from icub_pmp.demo.tabletop import SCENE

    away = np.array(TABLETOP_AWAY)
    spec = " ".join(f"{n}:{away[0]:.2f},{away[1] + 0.1 * k:.2f},{away[2]:.2f}"
                    for k, n in enumerate(SCENE.objects))
    out = {k: dict(v) for k, v in params.items()}
    out["sim_bridge"]["tabletop_objects"] = spec
    out["peripersonal_space"] = {"use_sim_time": True, "grow_if_missing": False}
    return out


def tabletop_phase(runner: DemoRunner, name: str = "tabletop") -> PhaseResult:
    """The tabletop task of issue 19 (:mod:`icub_pmp.demo.tabletop_dds`): four cubes, two
    target areas, the allocation by reward, pairs in parallel or in series by the imagined
    check through ``/peripersonal/plan_pair``, one hand-over through an empty area, the grasp
    emulated by ``/sim/grasp``. For the phase the controller goes to its shipped impedance
    mode (in the demo's position mode the palm presses a cube into the table) and the
    planner to the task's :data:`PLANNER_PARAMETERS` (1 cm success tolerance with frozen
    wrists, joint motion counted as progress); both are put back after. Judged in
    the physics: every cube delivered (within 5 cm of its place, on the table), 0 arm-arm
    contacts and 0 collisions of an arm with a cube it is not working on."""
    from std_srvs.srv import Trigger

    from icub_pmp.demo.tabletop import SCENE, WRISTS, _space
    from icub_pmp.demo.tabletop_dds import (
        PLANNER_PARAMETERS,
        ServicePairCheck,
        execute_over_dds,
        set_parameters,
    )
    from icub_pmp.peripersonal.tabletop_task import TabletopPlanner

    t0 = runner.sim_time()
    space = _space(None)  # data/peripersonal, grown and saved there if missing
    res = runner.probe.call("/peripersonal/reload", Trigger, Trigger.Request(), 120.0)
    if not res.success:
        raise RuntimeError(f"/peripersonal/reload: {res.message}")
    old = [("/impedance_controller", set_parameters(runner.probe, "/impedance_controller",
                                                     {"mode": "impedance"})),
           ("/pmp_planner", set_parameters(runner.probe, "/pmp_planner",
                                           PLANNER_PARAMETERS))]
    try:
        plan = TabletopPlanner(space, ServicePairCheck(runner.probe)).plan(SCENE)
        report = execute_over_dds(runner, SCENE, plan, frozen=WRISTS)
    finally:
        for node, values in old:
            set_parameters(runner.probe, node, values)
    n = len(report["delivered"])
    message = (f"{n} of {report['objects']} cubes delivered, {report['arm_arm_contacts']} "
               f"arm-arm contacts, {len(report['arm_object_collisions'])} arm-object "
               f"collisions, {report['handovers']} hand-over(s); rounds {report['rounds']}")
    if report["grasp_refusals"]:
        message += f"; grasps refused: {report['grasp_refusals']}"
    return PhaseResult(name, bool(report["success"]), message,
                       extra={"delivered": float(n), "objects": float(report["objects"]),
                              "arm_arm_contacts": float(report["arm_arm_contacts"]),
                              "arm_object_collisions":
                                  float(len(report["arm_object_collisions"])),
                              "handovers": float(report["handovers"]),
                              "task_sim_s": float(report["duration"])},
                       sim_start=t0, sim_end=runner.sim_time(), wall_s=report["wall_time"])


def main(argv: list[str] | None = None) -> int:
    """``python -m icub_pmp.demo`` (what ``make demo`` runs)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=None, help="output folder (default bags/demo-<ts>)")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--realism", choices=("ideal", "icub"), default="icub",
                    help="the simulator's realism preset (default icub, the shipped robot of "
                         "config/sim_bridge.yaml; ideal: the exact simulator)")
    ap.add_argument("--tabletop", action="store_true",
                    help="add the tabletop task of the two arms as the last phase (about 10 "
                         "more minutes on a loaded 2-core machine)")
    ap.add_argument("--phases", default="all",
                    help=f"comma-separated phases to run (default all: {','.join(PHASES)}); "
                         "e.g. --phases bimanual runs the reach, squeeze and coupled transport "
                         "alone, on a graph without cameras")
    args = ap.parse_args(argv)
    try:
        phases = parse_phases(args.phases)
    except ValueError as exc:
        ap.error(f"--phases: {exc}")
    out = args.out or repo_root() / "bags" / time.strftime("demo-%Y%m%d-%H%M%S")
    rc = run_demo(out, args.quick, args.realism, args.tabletop, phases)
    (out / "summary.json").write_text(json.dumps({"exit_code": rc}, indent=2))
    return rc

