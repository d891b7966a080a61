"""``python -m icub_pmp.demo.learned_reach``: PMP on the learned body vs on the URDF, in physics.

The body-schema paper's claim (Bhat and Mohan, "Internal Body Model"; docs/references.md): a
robot that learned its arm's forward model from babbling can reach with PMP relaxing on the
Jacobian of that model (eq 2). This demo

1. takes a right-arm body network learned earlier (``--model FILE``, ``BodyNetwork.save``) or
   learns one now as the bench does: ``--babbles`` random postures within the URDF limits with
   the hand from pinocchio forward kinematics (``analytic_babbling``), Levenberg-Marquardt on
   the normal equations within ``--budget`` s of CPU (``--dataset FILE`` learns from a ROS
   babbling run's ``q`` and ``hand_seen`` instead); the model is saved in the output folder;
2. starts the simulator in lockstep with the 1 kHz impedance controller, then ``pmp_planner``
   with ``jacobian_source: learned`` (the model file), and reaches each fixed table target with
   the right hand from the rest posture (``/pmp/reach_action``; the arm goes back to rest through
   the controller's trajectory action between reaches);
3. restarts ``pmp_planner`` with ``jacobian_source: analytic`` (the URDF through pinocchio) and
   reaches the same targets from the same posture;
4. judges every reach in the physics: the true hand (``r_hand_dh_frame`` of the URDF at the
   simulator's measured joint angles, /joint_states, after the planner's arrival check; for a
   model learned from a babbling run, the marker on it, ``marker_offset``) against the target,
   and prints both planners side by side (also as ``summary.json``).

The targets are fixed (``TARGETS``: above the table, right of the midline, reachable without
the torso); the vision target is not used here (``make demo``'s vision phase is on the
analytic planner). Exit status 1 when a reach fails to execute or the graph does not come up.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from icub_pmp.config import repo_root
from icub_pmp.graph import NodeGraph, NodeProcess, param_text, reserve_domain_id, ros_environment
from icub_pmp.kinematics import IcubModel, RobotSpec

__all__ = ["TARGETS", "ReachRecord", "body_model", "run_reaches", "main"]

#: right-hand targets in root_link [m] (x backward, y right, z up): above the table in front
TARGETS = np.array([[-0.30, 0.15, 0.05], [-0.25, 0.20, 0.10], [-0.28, 0.10, 0.00],
                    [-0.32, 0.22, 0.02], [-0.22, 0.12, 0.12]])
PLANNERS = ("learned", "analytic")
SUCCESS = 0.01  # [m] true hand error counted as a reach within 1 cm


@dataclass(frozen=True)
class ReachRecord:
    """One reach judged in the physics."""

    planner: str  # 'learned' | 'analytic'
    target: list[float]  # [m] root_link
    outcome: str  # the action's outcome (reached, not_reached, unreachable, ...)
    true_error: float  # [m] URDF hand at the measured joints vs the target (nan: not executed)
    planner_error: float  # [m] the arrival error the planner reported (nan: none)
    planned_residual: float  # [m] the plan's own residual in its body model


def body_model(out_dir: Path, model: str = "", dataset: str = "", babbles: int = 3000,
               budget: float = 30.0, seed: int = 100) -> tuple[Path, str, np.ndarray]:
    """The right-arm body model file the learned planner uses, a line saying where it came
    from and the point it stands for in the hand frame [m] (a babbling run's marker offset;
    0 for pinocchio babbles): ``model`` as given (checked to be a right-arm model), else
    learned from ``dataset`` (a ROS babbling run) or from ``babbles`` pinocchio babbles within
    ``budget`` s of CPU."""
    from icub_pmp.body_schema import BodyNetwork, LmTrainer, LmTrainerConfig, load_dataset

    if model:
        net = BodyNetwork.load(model, arm="right")
        return (Path(model), f"loaded {model} ({net.info.get('samples', '?')} babbles)",
                np.array(net.info.get("marker_offset", [0.0, 0.0, 0.0]), dtype=float))
    spec = RobotSpec.load()
    urdf = IcubModel(spec)
    joints = spec.right_arm_joints
    idx = urdf.indices(joints)
    if dataset:
        d = load_dataset(dataset)
        if tuple(d.meta.get("joint_names", ())) != tuple(joints):
            raise ValueError(f"{dataset}: babbled joints {d.meta.get('joint_names')}, expected "
                             f"the right arm's {list(joints)}")
        q, hand, what = d.learner["q"], d.learner["hand_seen"], f"the babbling run {dataset}"
        offset = np.array(d.meta.get("marker_offset", [0.0, 0.0, 0.0]), dtype=float)
    else:
        from icub_pmp.peripersonal import analytic_babbling

        b = analytic_babbling("right", babbles, seed=seed)
        q, hand, what = b.q, b.hand, f"{babbles} pinocchio babbles"
        offset = np.zeros(3)
    trainer = LmTrainer(LmTrainerConfig(
        method="lm-normal", max_evaluations=100000, time_budget=budget, budget_clock="cpu",
        curvature_dtype="float32", curvature_samples=min(3000, len(q))))
    net, report = BodyNetwork.train("right", joints, q, hand, urdf.lower[idx], urdf.upper[idx],
                                    spec.hand_frame("right"), trainer=trainer)
    net.info["marker_offset"] = offset.tolist()
    path = net.save(out_dir / "body_right.npz")
    return path, (f"learned from {what} in {report.cpu_seconds:.0f} s CPU ({report.iterations} "
                  f"iterations): validation RMSE {report.validation_rmse * 1e3:.2f} mm"), offset


def _graph_parameters() -> dict[str, dict[str, object]]:
    """Simulator (no cameras) in lockstep with the stiff position-mode controller."""
    return {
        "sim_bridge": {"mode": "lockstep", "use_sim_time": False, "cameras_enabled": False},
        "impedance_controller": {"lockstep": True, "use_sim_time": True, "mode": "position",
                                 "wait_for_estimate": False},
    }


class _Driver:
    """Goals to the running graph and the true hand from /joint_states."""

    def __init__(self, probe) -> None:  # noqa: ANN001 - RosProbe
        from rclpy.qos import qos_profile_sensor_data
        from sensor_msgs.msg import JointState

        self.probe = probe
        self.spec = RobotSpec.load()
        self.urdf = IcubModel(self.spec)
        self.frame = self.spec.hand_frame("right")
        self.js = None
        self._sub = probe.node.create_subscription(
            JointState, "/joint_states", lambda m: setattr(self, "js", m),
            qos_profile_sensor_data)
        self._clients: dict[str, object] = {}

    def true_hand(self, offset: np.ndarray) -> np.ndarray:
        """The point ``offset`` [m] of the URDF ``r_hand_dh_frame`` in root_link [m] at the
        latest measured joint angles."""
        js = self.js
        q = self.urdf.q_from_dict(dict(zip(js.name, js.position)),
                                  default=self.urdf.posture("rest"))
        T = self.urdf.frame_pose(q, self.frame).homogeneous
        return T[:3, 3] + T[:3, :3] @ offset

    def _client(self, name: str, action_type):  # noqa: ANN001, ANN202 - ROS types
        if name not in self._clients:
            self._clients[name] = self.probe.action_client(name, action_type, timeout=180.0)
        return self._clients[name]

    def forget(self, name: str) -> None:
        """Drop the cached client of ``name`` (its server restarted)."""
        client = self._clients.pop(name, None)
        if client is not None:
            self.probe.destroy(client)

    def rest(self, duration: float = 2.0) -> None:
        """Right arm back to the rest posture through the controller's trajectory action."""
        from icub_interfaces.action import FollowJointTrajectory
        from icub_pmp.ros.conversions import arrays_to_trajectory

        rest = self.spec.posture("rest")
        names = list(self.spec.right_arm_joints)
        goal = FollowJointTrajectory.Goal()
        goal.trajectory = arrays_to_trajectory(names, [duration],
                                               np.array([[rest.get(j, 0.0) for j in names]]))
        self.probe.send_goal(self._client("/impedance_controller/follow_joint_trajectory",
                                          FollowJointTrajectory), goal, 600.0)

    def reach(self, planner: str, target: np.ndarray, tau: float,
              offset: np.ndarray) -> ReachRecord:
        """One right-hand PMP reach, judged on the true hand's point ``offset`` (the one the
        planner's body model stands for)."""
        from icub_interfaces.action import Reach

        goal = Reach.Goal()
        goal.hands = ["right"]
        goal.tau = tau
        goal.right_target.header.frame_id = "root_link"
        p = goal.right_target.pose.position
        p.x, p.y, p.z = (float(v) for v in target)
        res = self.probe.send_goal(self._client("/pmp/reach_action", Reach), goal, 900.0).result
        executed = res.outcome in ("reached", "not_reached")
        true = (float(np.linalg.norm(self.true_hand(offset) - target)) if executed
                else float("nan"))
        return ReachRecord(planner, [float(v) for v in target], res.outcome, true,
                           float(res.arrival_errors[0]) if res.arrival_errors else float("nan"),
                           float(res.planned_residuals[0]) if res.planned_residuals
                           else float("nan"))


def run_reaches(model_path: Path, targets: np.ndarray, tau: float = 2.0,
                offset: np.ndarray | None = None,
                log=print) -> list[ReachRecord]:  # noqa: ANN001 - a print-like callable
    """Start the graph in a private ROS domain, reach ``targets`` with each planner (module
    doc), stop everything; the records of every reach, learned first. ``offset`` [m]: the
    point of the hand frame the learned model stands for (the analytic planner's is 0)."""
    learned_offset = np.zeros(3) if offset is None else np.asarray(offset, dtype=float)
    from icub_pmp.ros.probe import RosProbe

    records: list[ReachRecord] = []
    with reserve_domain_id() as domain:
        env = ros_environment(domain)
        log(f"learned_reach: ROS_DOMAIN_ID={domain}; starting the simulator and the controller")
        with NodeGraph(["sim_bridge", "impedance_controller"], _graph_parameters(),
                       env=env) as graph:
            probe = RosProbe(domain, "learned_reach")
            try:
                drv = _Driver(probe)
                if not probe.wait_for(lambda: drv.js is not None, 300.0):
                    raise TimeoutError("no /joint_states after 300 s: " + graph.outputs()[-3000:])
                for planner in PLANNERS:
                    params = {"use_sim_time": True, "jacobian_source": planner}
                    if planner == "learned":
                        params["learned_model_right"] = str(model_path)
                    args = [a for k, v in params.items()
                            for a in ("-p", f"{k}:={param_text(v)}")]
                    node = NodeProcess(command=[str(repo_root() / "scripts/pmp_planner.sh"),
                                                "--ros-args", *args], env=env)
                    try:
                        for target in targets:
                            drv.rest()
                            rec = drv.reach(planner, np.asarray(target, dtype=float), tau,
                                            learned_offset if planner == "learned"
                                            else np.zeros(3))
                            log(f"learned_reach: {planner:8s} target {np.round(target, 3)}: "
                                f"{rec.outcome}, true error {rec.true_error * 1e3:.1f} mm")
                            records.append(rec)
                    finally:
                        drv.forget("/pmp/reach_action")
                        node.stop()
            finally:
                probe.close()
    return records


def summary(records: list[ReachRecord]) -> dict[str, dict[str, float]]:
    """Per planner: targets, success (true error within :data:`SUCCESS`), median and max
    true error [mm]."""
    out = {}
    for planner in PLANNERS:
        e = np.array([r.true_error for r in records if r.planner == planner])
        if len(e) == 0:
            continue
        ok = np.isfinite(e)
        out[planner] = {
            "targets": int(len(e)),
            "success": float(np.mean(ok & (np.nan_to_num(e, nan=np.inf) <= SUCCESS))),
            "true_err_mm_median": round(float(np.median(e[ok])) * 1e3, 2) if ok.any() else None,
            "true_err_mm_max": round(float(np.max(e[ok])) * 1e3, 2) if ok.any() else None,
        }
    return out


def main(argv: list[str] | None = None) -> int:
    """Entry point (module doc)."""
    ap = argparse.ArgumentParser(prog="python -m icub_pmp.demo.learned_reach",
                                 description=__doc__.splitlines()[0])
    ap.add_argument("--model", default="", help="a right-arm body model (.npz) learned earlier")
    ap.add_argument("--dataset", default="", help="learn from this babbling run (.npz) instead")
    ap.add_argument("--babbles", type=int, default=3000, help="pinocchio babbles to learn from")
    ap.add_argument("--budget", type=float, default=30.0, help="training CPU budget [s]")
    ap.add_argument("--targets", type=int, default=len(TARGETS),
                    help=f"how many of the {len(TARGETS)} fixed targets")
    ap.add_argument("--tau", type=float, default=2.0, help="reach duration [s]")
    ap.add_argument("--out", default="", help="output folder (default bags/learned-<time>)")
    args = ap.parse_args(argv)
    from icub_pmp.errors import IcubPmpError

    out = Path(args.out or repo_root() / "bags" / time.strftime("learned-%Y%m%d-%H%M%S"))
    out.mkdir(parents=True, exist_ok=True)
    if not 1 <= args.targets <= len(TARGETS):
        print(f"learned_reach: error: --targets: expected 1..{len(TARGETS)}, got {args.targets}",
              file=sys.stderr)
        return 2
    try:
        path, origin, offset = body_model(out, args.model, args.dataset, args.babbles,
                                          args.budget)
    except (IcubPmpError, ValueError) as exc:
        print(f"learned_reach: error: {exc}", file=sys.stderr)
        return 2
    print(f"learned_reach: body model {path}: {origin}", flush=True)
    try:
        records = run_reaches(path, TARGETS[:args.targets], args.tau, offset,
                              log=lambda s: print(s, flush=True))
    except (TimeoutError, RuntimeError) as exc:
        print(f"learned_reach: error: {exc}", file=sys.stderr)
        return 1
    table = summary(records)
    print("learned_reach: true hand error in the physics [mm] (target: learned | analytic)")
    for target in TARGETS[:args.targets]:
        row = [r for r in records if np.allclose(r.target, target)]
        cells = " | ".join(f"{r.true_error * 1e3:6.1f} ({r.outcome})" for r in row)
        print(f"  {np.round(target, 3)}: {cells}")
    for planner, s in table.items():
        print(f"learned_reach: {planner:8s} {s}")
    (out / "summary.json").write_text(json.dumps(
        {"model": str(path), "origin": origin, "summary": table,
         "reaches": [asdict(r) for r in records]}, indent=1))
    print(f"learned_reach: summary in {out / 'summary.json'}")
    executed = all(r.outcome in ("reached", "not_reached") for r in records)
    return 0 if executed else 1


if __name__ == "__main__":
    sys.exit(main())
