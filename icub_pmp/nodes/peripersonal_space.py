"""peripersonal_space: the two arms' peripersonal space and their cooperation as a ROS 2 node
(a thin adapter over :mod:`icub_pmp.peripersonal`; Bhat and Mohan 2018).

Services (every point in root_link [m]; bad input - NaN, an unknown arm, an empty object list,
no maps loaded yet - answers success=false with a message, the node never dies on it):

- ``/peripersonal/check_reach`` (icub_interfaces/srv/CheckReach): which arm reaches which
  point (inside the map, nearest neuron, distance, reward);
- ``/peripersonal/allocate`` (AllocateObjects): which arm acts on which object, in which round
  (the reward fields, :class:`~icub_pmp.peripersonal.TargetAllocator`);
- ``/peripersonal/empty_area`` (FindEmptyArea): the least active neuron of the shared
  workspace, farther than the gripper width (or a given radius) from every object;
- ``/peripersonal/plan_pair`` (PlanPair): both arms' imagined PMP reaches (from the rest
  posture, the measured one or a given one: ``start``), the collision verdict, the schedule
  (parallel or serial) and the posture both reaches end in (``final``, the start of the next
  pair of a sequence); nothing moves.
- ``/peripersonal/reload`` (std_srvs/Trigger): load the maps of ``maps_dir`` again.

Publishes ``map_topic`` (sensor_msgs/PointCloud2, latched): the neurons of both maps with
their arm and whether they are in the shared workspace, for Foxglove or RViz. Subscribes
``/joint_states`` (on a thread of its own) for plans that start from the measured posture.

The maps are loaded from ``maps_dir`` at start; when there are none and ``grow_if_missing``,
they are grown from babbling in the background and saved there (about a minute per arm at
the default 40,000 babbles), the services answering "not loaded yet" meanwhile. Parameters:
config/peripersonal_space.yaml.
"""

from __future__ import annotations

import math
import threading
import time
from pathlib import Path

import numpy as np
from geometry_msgs.msg import Point
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState, PointCloud2, PointField
from std_srvs.srv import Trigger

from icub_interfaces.srv import AllocateObjects, CheckReach, FindEmptyArea, PlanPair
from icub_pmp.body_schema.jacobian_source import JacobianSourceConfig
from icub_pmp.config import repo_root
from icub_pmp.errors import ConfigError, IcubPmpError, InvalidInput, ModelError, UnknownName
from icub_pmp.kinematics.robot_spec import HANDS
from icub_pmp.peripersonal import (
    CollisionCheckConfig,
    ImaginedCollisionCheck,
    PeripersonalConfig,
    PeripersonalSpace,
)
from icub_pmp.peripersonal.peripersonal_node_config import PeripersonalNodeConfig
from icub_pmp.ros.joint_state_cache import JointStateCache
from icub_pmp.ros.node_runner import spin_node
from icub_pmp.ros.parameters import ConfigParameters
from icub_pmp.ros.trajectory_action_server import FIRST_STATE_TIMEOUT

__all__ = ["PeripersonalSpaceNode", "main"]

_CONFIGS = (PeripersonalConfig, CollisionCheckConfig, PeripersonalNodeConfig,
            JacobianSourceConfig)
ROOT = "root_link"


def points_array(points: list[Point], name: str, allow_empty: bool = False) -> np.ndarray:
    """(m, 3) [m] of the message points; InvalidInput for none (unless allowed) or NaN/inf."""
    a = np.array([[p.x, p.y, p.z] for p in points], dtype=float).reshape(-1, 3)
    if not allow_empty and a.shape[0] == 0:
        raise InvalidInput(f"{name}: empty list (give at least one point)")
    bad = np.flatnonzero(~np.isfinite(a).all(axis=1))
    if bad.size:
        raise InvalidInput(f"{name}[{int(bad[0])}] is not finite: {a[bad[0]].tolist()}")
    return a


def _point(p: np.ndarray) -> Point:
    return Point(x=float(p[0]), y=float(p[1]), z=float(p[2]))


def _arm(name: str, allow_empty: bool = False) -> str:
    if allow_empty and name == "":
        return ""
    if name not in HANDS:
        raise UnknownName("arm", name, HANDS)
    return name


class PeripersonalSpaceNode(Node):
    """Serve the peripersonal-space queries and the imagined pair plans (module doc)."""

    def __init__(self) -> None:
        super().__init__("peripersonal_space")
        self._lock = threading.Lock()
        self.params = ConfigParameters(self, _CONFIGS, on_change=self._on_config_change,
                                       read_only=JacobianSourceConfig.field_names())
        self.space: PeripersonalSpace | None = None
        self.status = "not loaded yet"
        self.check = self._make_check(self.params.get(CollisionCheckConfig))
        self._listener = JointStateCache(self)
        latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                             durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self.map_pub = self.create_publisher(PointCloud2, self.node_config.map_topic, latched)
        self.create_service(CheckReach, "/peripersonal/check_reach", self._on_check_reach)
        self.create_service(AllocateObjects, "/peripersonal/allocate", self._on_allocate)
        self.create_service(FindEmptyArea, "/peripersonal/empty_area", self._on_empty_area)
        self.create_service(PlanPair, "/peripersonal/plan_pair", self._on_plan_pair)
        self.create_service(Trigger, "/peripersonal/reload", self._on_reload)
        self._loader = threading.Thread(target=self._load_or_grow, daemon=True)
        self._loader.start()

    # ------------------------------------------------------------------ maps
    @property
    def node_config(self) -> PeripersonalNodeConfig:
        """The node's own parameters."""
        return self.params.get(PeripersonalNodeConfig)

    def maps_dir(self) -> Path:
        """``maps_dir`` resolved against the repository root."""
        d = Path(self.node_config.maps_dir).expanduser()
        return d if d.is_absolute() else repo_root() / d

    def _load_or_grow(self) -> None:
        d, nc = self.maps_dir(), self.node_config
        try:
            space = PeripersonalSpace.load(d, self.params.get(PeripersonalConfig))
            how = f"loaded from {d}"
        except ModelError as exc:
            if not nc.grow_if_missing:
                self.status = (f"no maps loaded: {exc} (grow them with grow_if_missing, or "
                               "put PeripersonalSpace.save output there and call "
                               "/peripersonal/reload)")
                self.get_logger().warning(self.status)
                return
            self.status = (f"not loaded yet: growing the maps from {nc.babble_samples} "
                           "babbles per arm (about a minute per arm)")
            self.get_logger().info(self.status)
            t0 = time.monotonic()
            try:
                space = PeripersonalSpace.grow(nc.babble_samples, nc.babble_seed,
                                               config=self.params.get(PeripersonalConfig))
                space.save(d)
            except Exception as exc2:  # the node stays up and says why
                self.status = f"no maps loaded: growing them failed: {exc2}"
                self.get_logger().error(self.status)
                return
            how = f"grown in {time.monotonic() - t0:.0f} s and saved to {d}"
        except Exception as exc:
            self.status = f"no maps loaded: {d}: {exc}"
            self.get_logger().error(self.status)
            return
        with self._lock:
            self.space = space
            self.status = "loaded"
        sizes = {a: space.maps[a].size for a in HANDS}
        self.get_logger().info(f"peripersonal maps {how}: {sizes} neurons, "
                               f"{len(space.shared.neurons('left'))} + "
                               f"{len(space.shared.neurons('right'))} shared")
        self.map_pub.publish(self._cloud(space))

    def _space(self) -> PeripersonalSpace:
        space = self.space
        if space is None:
            raise ModelError(f"peripersonal maps {self.status}")
        return space

    def _cloud(self, space: PeripersonalSpace) -> PointCloud2:
        """Both maps' neurons as x, y, z, arm, shared (float32 fields)."""
        rows = []
        for k, arm in enumerate(HANDS):
            n = space.maps[arm].neurons
            shared = np.zeros(len(n))
            shared[space.shared.neurons(arm)] = 1.0
            rows.append(np.column_stack([n, np.full(len(n), k), shared]))
        data = np.vstack(rows).astype(np.float32)
        msg = PointCloud2()
        msg.header.frame_id = ROOT
        msg.header.stamp = self.get_clock().now().to_msg()
        msg.height, msg.width = 1, data.shape[0]
        msg.fields = [PointField(name=f, offset=4 * i, datatype=PointField.FLOAT32, count=1)
                      for i, f in enumerate(("x", "y", "z", "arm", "shared"))]
        msg.is_bigendian = False
        msg.point_step = 20
        msg.row_step = 20 * data.shape[0]
        msg.is_dense = True
        msg.data = data.tobytes()
        return msg

    def _make_check(self, config: CollisionCheckConfig) -> ImaginedCollisionCheck:
        """The imagined check on the body model of ``jacobian_source``: the URDF, or the
        body networks learned from babbling (one per arm; ConfigError naming the file)."""
        src = self.params.get(JacobianSourceConfig)
        if src.jacobian_source != "learned":
            return ImaginedCollisionCheck(config)
        files = {"left": src.learned_model_left, "right": src.learned_model_right}
        try:
            check = ImaginedCollisionCheck.learned(files, config)
        except IcubPmpError as exc:
            raise ConfigError(f"jacobian_source learned: {exc}") from exc
        self.get_logger().info(f"imagined reaches on the learned body models {files}")
        return check

    def _on_config_change(self, old: tuple, new: tuple, changed: frozenset[str]) -> None:
        if new[1] != old[1]:
            self.check = self._make_check(new[1])
        if new[0] != old[0] and self.space is not None:
            with self._lock:
                self.space = PeripersonalSpace(self.space.maps, self.space.arm_y, new[0])

    # ------------------------------------------------------------------ services
    def _serve(self, name: str, res, fn) -> object:
        """Run ``fn(res)``; any error becomes success=false and a message."""
        try:
            fn(res)
            res.success = True
        except IcubPmpError as exc:
            res.success, res.message = False, str(exc)
            self.get_logger().warning(f"{name} rejected: {exc}", throttle_duration_sec=1.0)
        except Exception as exc:  # never let a request kill the node
            res.success, res.message = False, f"internal error: {type(exc).__name__}: {exc}"
            self.get_logger().error(f"{name} failed: {res.message}")
        return res

    def _on_check_reach(self, req: CheckReach.Request, res: CheckReach.Response):
        def run(res: CheckReach.Response) -> None:
            pts = points_array(req.points, "points")
            arms = [_arm(req.arm, allow_empty=True)] if req.arm else list(HANDS)
            space = self._space()
            names, inside, nearest, distance, reward = [], [], [], [], []
            for arm in arms:
                r = space.reachability(arm, pts)
                names += [arm] * len(pts)
                inside += [bool(v) for v in r.inside]
                nearest += [_point(p) for p in space.maps[arm].neurons[r.neuron]]
                distance += [float(v) for v in r.distance]
                reward += [float(v) for v in r.reward]
            res.arms, res.inside, res.nearest = names, inside, nearest
            res.distance, res.reward = distance, reward
            counts = {a: int(np.sum(r)) for a, r in zip(
                arms, np.array(inside, dtype=bool).reshape(len(arms), -1))}
            res.message = f"{len(pts)} point(s); inside: {counts}"

        return self._serve("/peripersonal/check_reach", res, run)

    def _on_allocate(self, req: AllocateObjects.Request, res: AllocateObjects.Response):
        def run(res: AllocateObjects.Response) -> None:
            objs = points_array(req.objects, "objects")
            alloc = self._space().allocate(objs)
            arm = ["none"] * len(objs)
            rnd = [-1] * len(objs)
            for a in HANDS:
                for r, i in enumerate(alloc.assignments[a]):
                    arm[i], rnd[i] = a, r
            res.arm, res.round = arm, rnd
            res.reward_left = [float(v) for v in alloc.rewards[:, 0]]
            res.reward_right = [float(v) for v in alloc.rewards[:, 1]]
            res.rounds = int(alloc.rounds)
            res.message = (f"{len(objs)} object(s) in {alloc.rounds} round(s): left "
                           f"{list(alloc.assignments['left'])}, right "
                           f"{list(alloc.assignments['right'])}, unreachable "
                           f"{list(alloc.unreachable)}")

        return self._serve("/peripersonal/allocate", res, run)

    def _on_empty_area(self, req: FindEmptyArea.Request, res: FindEmptyArea.Response):
        def run(res: FindEmptyArea.Response) -> None:
            objs = points_array(req.objects, "objects", allow_empty=True)
            radius = float(req.radius)
            if not (math.isfinite(radius) and radius >= 0.0):
                raise InvalidInput(f"radius: expected 0 (the gripper width) or a distance > 0 "
                                   f"[m], got {req.radius}")
            area = self._space().empty_area(objs, _arm(req.arm), radius or None)
            res.point = _point(area.point)
            res.activity = float(area.activity)
            res.clearance = float(area.clearance)
            res.message = (f"empty area at {np.round(area.point, 3).tolist()} m ({area.arm} "
                           f"map, neuron {area.neuron}), clearance {area.clearance:.3f} m")

        return self._serve("/peripersonal/empty_area", res, run)

    def _on_plan_pair(self, req: PlanPair.Request, res: PlanPair.Response):
        def run(res: PlanPair.Response) -> None:
            targets = {"left": points_array([req.left_target], "left_target")[0],
                       "right": points_array([req.right_target], "right_target")[0]}
            first = _arm(req.first or "left")
            q_start: dict[str, float] | None = None
            if req.from_current:
                js = self._listener.latest(wait=FIRST_STATE_TIMEOUT)  # right after start-up
                if js is None:
                    raise InvalidInput("from_current: no /joint_states received yet (is "
                                       "sim_bridge running?)")
                q_start = dict(js.positions)
            if req.start.name or req.start.position:
                q_start = {**(q_start or {}), **self._start_posture(req.start)}
            plan = self.check.plan_pair(targets, q_start, first)
            v, sch = plan.verdict, plan.schedule
            res.collides = bool(v.collides)
            res.min_distal_distance = float(v.min_distal_distance)
            res.min_clearance = float(v.min_clearance)
            res.time_of_closest_approach = float(v.time_of_closest_approach)
            res.mode = sch.mode
            res.step_arm = [s.arm for s in sch.steps]
            res.step_action = [s.action for s in sch.steps]
            res.step_start = [float(s.start) for s in sch.steps]
            res.step_end = [float(s.end) for s in sch.steps]
            res.duration = float(sch.duration)
            res.left_path = [_point(p) for p in plan.plans["left"].hand_paths["left"]]
            res.right_path = [_point(p) for p in plan.plans["right"].hand_paths["right"]]
            res.planning_time = float(plan.planning_time)
            names = list(self.check.provider.joint_names)
            q_end = self.check.planner.start_configuration(q_start)
            for p in plan.plans.values():
                q_end[[names.index(j) for j in p.joint_names]] = p.positions[-1]
            res.final.name = names
            res.final.position = [float(v) for v in q_end]
            res.message = (f"{'collision predicted' if v.collides else 'no collision'} "
                           f"(distal {v.min_distal_distance * 1e3:.0f} mm, hulls "
                           f"{v.min_clearance * 1e3:.0f} mm): {sch.mode}, "
                           f"{len(sch.steps)} step(s), {sch.duration:.2f} s")

        return self._serve("/peripersonal/plan_pair", res, run)

    def _start_posture(self, start: JointState) -> dict[str, float]:
        """{joint: rad} of a request's ``start`` (InvalidInput for lists of different
        lengths, an unknown joint, a NaN)."""
        names, pos = list(start.name), list(start.position)
        if len(names) != len(pos):
            raise InvalidInput(f"start: {len(names)} names but {len(pos)} positions")
        known = self.check.provider.joint_names
        for n, v in zip(names, pos):
            if n not in known:
                raise UnknownName("joint", n, known)
            if not math.isfinite(v):
                raise InvalidInput(f"start: position of {n} is not finite: {v}")
        return dict(zip(names, (float(v) for v in pos)))

    def _on_reload(self, req: Trigger.Request, res: Trigger.Response) -> Trigger.Response:
        try:
            space = PeripersonalSpace.load(self.maps_dir(), self.params.get(PeripersonalConfig))
        except IcubPmpError as exc:
            res.success, res.message = False, str(exc)
            return res
        with self._lock:
            self.space = space
            self.status = "loaded"
        self.map_pub.publish(self._cloud(space))
        res.success = True
        res.message = (f"loaded {self.maps_dir()}: "
                       f"{ {a: space.maps[a].size for a in HANDS} } neurons")
        return res

    def destroy_node(self) -> None:
        """Stop the joint-state cache's thread, then destroy the node."""
        self._listener.close()
        super().destroy_node()


def main(args: list[str] | None = None) -> None:
    """Entry point (``ros2 run icub_pmp peripersonal_space``)."""
    spin_node(PeripersonalSpaceNode, args)


if __name__ == "__main__":
    main()
