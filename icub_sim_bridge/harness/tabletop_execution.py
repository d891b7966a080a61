"""TabletopExecution: a planned tabletop task (:class:`~icub_pmp.peripersonal.TaskPlan`)
executed in the physics, judged on the simulator's ground truth.

The in-process harness (:class:`SimLoop`: MuJoCo with the arms colliding with each other and
with the objects, the impedance controller core at 1 kHz, lockstep): every reach of a job is
imagined by PMP from the posture the robot is in (:meth:`ImaginedCollisionCheck.imagine`,
trunk still) and handed to the controller; after the reach onto the object the hand grasps
it with :meth:`Simulator.grasp` (the emulated grasp: a weld switched on only when the palm
touches the object in the simulator's contacts, refused otherwise), after the reach above the
place point it releases it. Rounds run as planned: ``parallel`` both arms' jobs phase by
phase together, ``serial`` the first arm's job while the other waits at the safe posture,
then the other's, ``single`` one arm, the idle one at the safe posture first (it may hover
where the other arm goes: over a hand-over's empty area, say). ``all_serial=True`` runs every
round serially: the same task without scheduling, the baseline of the speed-up (each job
waits for the previous one, the other arm at the safe posture meanwhile).

Judged in the physics: an object is delivered when it rests on the table within
``area_radius`` (horizontal distance) of its place in its target area at the end; arm-arm
contacts (:meth:`Simulator.self_contacts`) and arm-object collisions
(:meth:`Simulator.object_contacts` with an object other than the one the arm is working on)
are counted as events (a pair of bodies touching in consecutive
samples counts once). Time is simulated time.
"""

from __future__ import annotations

import time
from typing import Mapping, NamedTuple

import numpy as np

from icub_pmp.errors import InvalidInput
from icub_pmp.kinematics.robot_spec import HANDS
from icub_pmp.peripersonal.tabletop_task import Job, TabletopScene, TabletopTaskConfig, TaskPlan
from icub_sim_bridge.harness.arm_pair_execution import send_plans
from icub_sim_bridge.harness.sim_loop import SimLoop

__all__ = ["TabletopExecution", "TaskReport", "SETTLE", "AREA_RADIUS"]

#: run after each phase's reaches before the next phase [s]
SETTLE = 0.3
#: an object within this horizontal distance of its target area's centre is delivered [m]
AREA_RADIUS = 0.05
_PHASES = ("onto the object", "lift", "above the place", "retreat")
#: contacts are sampled every this many steps
_SAMPLE_EVERY = 5


class _Motion(NamedTuple):
    """A joint motion in the shape :func:`send_plans` takes (a ReachPlan's fields)."""

    joint_names: tuple[str, ...]
    t: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray
    tau: float


class TaskReport(NamedTuple):
    """What the physics did with a :class:`TaskPlan`.

    Attributes:
        delivered: objects resting in their target area at the end.
        objects: number of objects in the scene.
        duration: simulated time of the whole task [s].
        arm_arm_contacts: arm-arm contact events (goal 0).
        arm_object_collisions: arm-object contact events with objects other than the one the
            arm is working on (goal 0), as (arm, object) strings.
        handovers: hand-overs done (the object put down in the empty area and taken from
            there by the other arm into its target area).
        grasp_refusals: grasps the simulator refused (no palm contact), as messages.
        rounds: the modes the rounds ran in.
        wall_time: wall time of the execution [s].
    """

    delivered: tuple[str, ...]
    objects: int
    duration: float
    arm_arm_contacts: int
    arm_object_collisions: tuple[str, ...]
    handovers: int
    grasp_refusals: tuple[str, ...]
    rounds: tuple[str, ...]
    wall_time: float

    @property
    def success(self) -> bool:
        """Every object delivered, no arm-arm contact, no arm-object collision."""
        return (len(self.delivered) == self.objects and self.arm_arm_contacts == 0
                and not self.arm_object_collisions)

    def as_dict(self) -> dict:
        """Plain JSON-ready fields."""
        d = self._asdict()
        d["success"] = self.success
        return {k: (list(v) if isinstance(v, tuple) else v) for k, v in d.items()}


class TabletopExecution:
    """Executes task plans on an in-process :class:`SimLoop` (module doc).

    Args:
        loop: the loop; its simulator must have the scene's objects as tabletop cubes.
        check: the :class:`~icub_pmp.peripersonal.ImaginedCollisionCheck` whose planner
            imagines each reach and whose safe posture the waiting arm goes to.
        config: the job's hand targets (the planner's).
    """

    def __init__(self, loop: SimLoop, check: object, config: TabletopTaskConfig | None = None,
                 area_radius: float = AREA_RADIUS):
        self.loop, self.check = loop, check
        self.config = config or TabletopTaskConfig()
        self.area_radius = float(area_radius)
        self._names = list(check.planner.provider.joint_names)
        self._sim_names = list(loop.sim.joint_names)

    # ------------------------------------------------------------------ set-up
    def reset(self, scene: TabletopScene) -> None:
        """Robot at rest, the demo's box and cylinder off the table, the cubes at the scene's
        positions, the controller holding."""
        sim, ctl = self.loop.sim, self.loop.controller
        missing = [n for n in scene.objects if n not in sim.graspable]
        if missing:
            raise InvalidInput(f"scene objects {missing} are not tabletop cubes of the "
                               f"simulator (SimConfig.tabletop_objects: {list(sim.graspable)})")
        sim.reset("rest")
        for name, pos in (("box", (0.6, 0.4, -0.55)), ("cylinder", (0.6, -0.4, -0.55))):
            sim.set_object_pose(name, pos)  # off the table, behind the robot
        for name, pos in scene.objects.items():
            sim.set_object_pose(name, pos)
        for name in sim.graspable:
            if name not in scene.objects:  # cubes not in this scene: off the table too
                sim.set_object_pose(name, (0.6, 0.0, -0.55))
        js = sim.joint_state()
        ctl.step(js.time, js.position, js.velocity)
        ctl.hold()
        self.loop.run(0.3)  # the cubes settle on the table

    # ------------------------------------------------------------------ motion
    def _q(self) -> np.ndarray:
        """The planner's full configuration at the robot's measured joints."""
        js = self.loop.sim.joint_state()
        q = self.check.planner.start_configuration(None)
        for i, n in enumerate(self._names):
            if n in self._sim_names:
                q[i] = js.position[self._sim_names.index(n)]
        return q

    def _hand(self, arm: str) -> np.ndarray:
        """``arm``'s hand frame (3,) [m] from the measured joints (forward kinematics)."""
        frame = self.loop.sim.spec.hand_frames[arm]
        return np.asarray(self.check.provider.positions(self._q(), [frame]))[0]

    def _park(self, arm: str) -> _Motion:
        t, names, pos = self.check.park_motion(arm, self._q())
        vel = np.gradient(pos, t, axis=0)
        vel[0] = vel[-1] = 0.0
        return _Motion(tuple(names), np.asarray(t), np.asarray(pos), vel, float(t[-1]))

    def _run(self, motions: Mapping[str, object], busy: Mapping[str, str]) -> None:
        """Execute ``motions`` (arm -> plan) together, then settle; contacts sampled."""
        if not motions:
            return
        duration, self._scale = send_plans(self.loop, motions)
        n = int(round((duration + SETTLE) / self.loop.sim.config.timestep))
        for k in range(n):
            self.loop.step()
            if k % _SAMPLE_EVERY == 0:
                self._sample(busy)

    def _sample(self, busy: Mapping[str, str]) -> None:
        sim = self.loop.sim
        if not sim.data.ncon:
            self._touching = set()
            return
        now = set()
        for c in sim.self_contacts():
            if c.kind == "arm-arm":
                now.add(("arm-arm", c.body1, c.body2))
        for c in sim.object_contacts():
            if c.arm in HANDS and busy.get(c.arm) != c.object:
                now.add(("arm-object", c.arm, c.object))
        for event in now - self._touching:
            if event[0] == "arm-arm":
                self._arm_arm += 1
            else:
                self._arm_object.append(f"{event[1]}:{event[2]}")
        self._touching = now

    def _phases(self, jobs: Mapping[str, Job], busy: dict[str, str]) -> list[str]:
        """Run the arms' jobs phase by phase together; returns grasp refusals."""
        sim = self.loop.sim
        refusals = []
        way = {a: list(j.waypoints(self.config)) for a, j in jobs.items()}
        held: set[str] = set()
        for phase in range(4):
            q = self._q()
            plans = {a: self.check.imagine(a, way[a][phase], q) for a in jobs
                     if phase == 0 or a in held}
            for a in jobs:
                busy[a] = jobs[a].object
            self._run(plans, busy)
            self.trace.append({
                "t": round(self.loop.t, 3), "phase": _PHASES[phase],
                "time_scale": round(self._scale, 2), "arm_arm": self._arm_arm,
                "targets": {a: np.round(way[a][phase], 3).tolist() for a in plans},
                "hands": {a: np.round(sim.frame_pose(sim.built.hand_frames[a]).position,
                                      3).tolist() for a in plans},
                "objects": {n: np.round(sim.object_pose(n).position, 3).tolist()
                            for n in sim.graspable}})
            if phase == 0:
                for a, j in jobs.items():
                    try:
                        sim.grasp(j.object, a)
                        held.add(a)
                    except InvalidInput as exc:
                        refusals.append(str(exc))
                        continue
                    # the cube sits where the palm stopped on it: carry it so that its centre
                    # (not the hand) arrives above the place point. The hand from the
                    # measured joints through the planner's kinematics; the cube where the
                    # scene said it was
                    offset = self._hand(a) - j.pick
                    drop = np.array([0.0, 0.0, self.config.drop_height])
                    way[a][2] = j.place + offset + drop
                    way[a][3] = way[a][2] + np.array(
                        [0.0, 0.0, self.config.retreat_height - self.config.place_height])
            elif phase == 2:
                for a in held:
                    sim.release(a)
                self.loop.run(SETTLE)  # the cubes land
        for a in jobs:
            busy.pop(a, None)
        return refusals

    # ------------------------------------------------------------------ task
    def execute(self, scene: TabletopScene, plan: TaskPlan, all_serial: bool = False
                ) -> TaskReport:
        """Reset to ``scene`` and run ``plan`` (module doc); ``all_serial``: every round
        one arm after the other."""
        wall0 = time.perf_counter()
        self.reset(scene)
        self._arm_arm, self._arm_object, self._touching = 0, [], set()
        #: after each phase: time, targets, measured hands and the cubes' true positions
        self.trace: list[dict] = []
        t0 = self.loop.t
        refusals: list[str] = []
        busy: dict[str, str] = {}
        modes = []
        for rnd in plan.rounds:
            mode = "serial" if (all_serial and rnd.mode == "parallel") else rnd.mode
            modes.append(mode)
            jobs = {a: j for a, j in rnd.jobs.items() if j is not None}
            if mode == "parallel":
                refusals += self._phases(jobs, busy)
                continue
            order = [rnd.first] + [a for a in HANDS if a != rnd.first]
            for arm in order:
                if arm not in jobs:
                    continue
                # the waiting (serial) or idle (single) arm out of the shared workspace first
                self._run({a: self._park(a) for a in HANDS if a != arm}, busy)
                refusals += self._phases({arm: jobs[arm]}, busy)
        sim = self.loop.sim
        places = {j.object: j.place for j in plan.jobs() if j.kind == "deliver"}
        delivered = []
        for name, area in scene.destinations.items():
            if name in plan.unreachable or name in plan.undeliverable:
                continue
            p = sim.object_pose(name).position
            c = places.get(name, np.asarray(scene.areas[area]))
            if np.hypot(*(p[:2] - c[:2])) <= self.area_radius and abs(p[2] - c[2]) < 0.01:
                delivered.append(name)
        handovers = sum(1 for j in plan.jobs() if j.kind == "handover"
                        and j.object in delivered)
        return TaskReport(tuple(delivered), len(scene.objects), self.loop.t - t0,
                          self._arm_arm, tuple(self._arm_object), handovers, tuple(refusals),
                          tuple(modes), time.perf_counter() - wall0)
