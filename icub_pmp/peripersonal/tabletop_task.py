"""TabletopTask: the tabletop task of two cooperating arms (Bhat and Mohan 2018, the
assembly task: "Coupled interaction between internal models of body and space").

Small objects lie on a table; each must be brought to a target area. The planner
(:class:`TabletopPlanner`) answers, with the peripersonal maps only (no ROS, no physics):

1. allocation: which arm picks which object, by reward (:meth:`PeripersonalSpace.allocate`);
   objects neither arm reaches are left (``unreachable``);
2. hand-over: an object whose target area the picking arm does not reach is put down in an
   empty area of the shared workspace (:meth:`PeripersonalSpace.empty_area`, at the height
   of the objects on the table) and the other arm takes it from there to the target area
   (the paper's cooperation), in a later round;
3. schedule: round r pairs the two arms' r-th jobs; the pair runs in parallel when the
   imagined check (a :data:`PairCheck`, e.g. :class:`ImaginedPairCheck`) says the two jobs'
   reaches do not collide, in series (one arm after the other, the waiting arm at the safe
   posture) when it says they do.

A job is a pick-and-place of one object by one arm through four hand targets
(:meth:`Job.waypoints`): onto the object (grasp), lifted above it, above the place point
(release), and up again. Frames: root_link [m].
"""

from __future__ import annotations

import dataclasses
import math
from typing import Callable, Mapping, NamedTuple, Sequence

import numpy as np

from icub_pmp.errors import InvalidInput, UnknownName
from icub_pmp.kinematics.robot_spec import HANDS
from icub_pmp.peripersonal.exceptions import NoEmptyArea
from icub_pmp.peripersonal.growing_neural_gas import as_points

__all__ = ["TabletopScene", "TabletopTaskConfig", "Job", "TaskRound", "TaskPlan",
           "TabletopPlanner", "ImaginedPairCheck", "PairCheck", "JOB_KINDS", "ROUND_MODES"]

#: deliver: pick and put in the target area; handover: pick and put in an empty area of the
#: shared workspace for the other arm
JOB_KINDS = ("deliver", "handover")
#: parallel: both jobs together; serial: one after the other; single: one arm only
ROUND_MODES = ("parallel", "serial", "single")


def _other(arm: str) -> str:
    return "right" if arm == "left" else "left"


@dataclasses.dataclass(frozen=True)
class TabletopTaskConfig:
    """Hand targets of a pick-and-place, relative to the object's centre [m] (root_link z up).

    Attributes:
        grasp_height: hand frame above the object's centre when reaching onto it (a little
            lower than where the palm stops on a 4 cm cube, so that it presses on it) [m].
        lift_height: hand frame above the object's centre when lifted [m].
        place_height: hand frame above the place point when releasing [m] (as imagined; the
            executor aims the object's centre ``drop_height`` above it).
        drop_height: the object's centre above its resting height at the release [m].
        retreat_height: hand frame above the place point after the release [m].
        empty_area_band: (low, high) heights [m] above the objects' centre where the
            shared-workspace neurons count as candidate release points of a hand-over.
        place_clearance: an empty area is at least this far from every object and target
            area [m].
        place_x_range: (low, high) x [m] of an empty area: over the table (its front edge
            is at x = -0.22 in ``config/sim_bridge.yaml``).
        slot_spacing: the objects brought to one target area are put down this far apart
            along y, the first at the area's centre, the next ones towards the middle [m].
    """

    grasp_height: float = 0.035
    lift_height: float = 0.10
    place_height: float = 0.06
    drop_height: float = 0.01
    retreat_height: float = 0.12
    empty_area_band: tuple[float, float] = (0.03, 0.09)
    place_clearance: float = 0.06
    place_x_range: tuple[float, float] = (-0.40, -0.24)
    slot_spacing: float = 0.08

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            vals = v if isinstance(v, tuple) else (v,)
            if not all(isinstance(x, (int, float)) and math.isfinite(x) for x in vals):
                raise InvalidInput(f"TabletopTaskConfig.{f.name}: expected finite values, "
                                   f"got {v!r}")
        for name in ("empty_area_band", "place_x_range"):
            lo, hi = getattr(self, name)
            if not lo < hi:
                raise InvalidInput(f"TabletopTaskConfig.{name}: expected (low, high) with low < "
                                   f"high, got {getattr(self, name)}")
        if self.slot_spacing <= 0:
            raise InvalidInput(f"TabletopTaskConfig.slot_spacing: expected > 0 m, got "
                               f"{self.slot_spacing}")
        if self.place_clearance <= 0:
            raise InvalidInput(f"TabletopTaskConfig.place_clearance: expected > 0 m, got "
                               f"{self.place_clearance}")


@dataclasses.dataclass(frozen=True)
class TabletopScene:
    """The task: object centres, target areas and which area each object goes to.

    Attributes:
        objects: name -> (3,) centre [m, root_link], resting on the table.
        areas: area name -> (3,) centre of the target area at the objects' height [m].
        destinations: object name -> area name.
    """

    objects: Mapping[str, tuple[float, float, float]]
    areas: Mapping[str, tuple[float, float, float]]
    destinations: Mapping[str, str]

    def __post_init__(self) -> None:
        if not self.objects:
            raise InvalidInput("objects: the scene has no objects (empty)")
        if not self.areas:
            raise InvalidInput("areas: the scene has no target areas (empty)")
        objs = {str(n): tuple(float(v) for v in as_points(p, f"objects[{n!r}]")[0])
                for n, p in self.objects.items()}
        areas = {str(n): tuple(float(v) for v in as_points(p, f"areas[{n!r}]")[0])
                 for n, p in self.areas.items()}
        for name in objs:
            if name not in self.destinations:
                raise InvalidInput(f"destinations: object {name!r} has no target area")
        for name, area in self.destinations.items():
            if name not in objs:
                raise UnknownName("object", name, objs)
            if area not in areas:
                raise UnknownName("target area", area, areas)
        object.__setattr__(self, "objects", objs)
        object.__setattr__(self, "areas", areas)
        object.__setattr__(self, "destinations", dict(self.destinations))


class Job(NamedTuple):
    """One pick-and-place by one arm.

    Attributes:
        arm: 'left' | 'right'.
        object: the object's name.
        kind: one of :data:`JOB_KINDS`.
        pick: (3,) object centre where it is picked [m].
        place: (3,) object centre where it is put down [m] (its slot in the target area, or
            the empty area of a hand-over).
        area: the target area's name ('' for a hand-over's empty area).
    """

    arm: str
    object: str
    kind: str
    pick: np.ndarray
    place: np.ndarray
    area: str

    def waypoints(self, config: TabletopTaskConfig) -> tuple[np.ndarray, ...]:
        """The hand targets (4 x (3,)) [m]: onto the object (then grasp), lifted, above the
        place point (then release), up again."""
        up = np.array([0.0, 0.0, 1.0])
        return (self.pick + config.grasp_height * up, self.pick + config.lift_height * up,
                self.place + config.place_height * up, self.place + config.retreat_height * up)


class TaskRound(NamedTuple):
    """A round: each arm's job (None: idle) and how they run (:data:`ROUND_MODES`);
    ``first``: the arm that goes first in a serial round."""

    jobs: Mapping[str, Job | None]
    mode: str
    first: str


class TaskPlan(NamedTuple):
    """The planned task.

    Attributes:
        rounds: in execution order.
        unreachable: objects neither arm reaches (not planned).
        undeliverable: objects whose target area no arm reaches, or for which no empty area
            was found (not planned), with the reason.
        handovers: number of hand-over jobs.
        checks: number of pair checks made, and how many said collision.
    """

    rounds: tuple[TaskRound, ...]
    unreachable: tuple[str, ...]
    undeliverable: Mapping[str, str]
    handovers: int
    checks: tuple[int, int]

    def jobs(self) -> list[Job]:
        """Every job, in round order (left before right within a round)."""
        return [r.jobs[a] for r in self.rounds for a in HANDS if r.jobs[a] is not None]


#: the imagined check of two jobs run together: (left job, right job) -> collision predicted
PairCheck = Callable[[Job, Job], bool]


class TabletopPlanner:
    """Plans a :class:`TabletopScene` (module doc).

    Args:
        space: the two arms' peripersonal maps (:class:`PeripersonalSpace`).
        pair_check: the imagined collision check of two jobs (:data:`PairCheck`).
        config: the hand targets of a job (:class:`TabletopTaskConfig`).
    """

    def __init__(self, space: object, pair_check: PairCheck,
                 config: TabletopTaskConfig | None = None):
        if not callable(pair_check):
            raise InvalidInput(f"pair_check: expected a callable (left job, right job) -> bool, "
                               f"got {pair_check!r}")
        self.space = space
        self.pair_check = pair_check
        self.config = config or TabletopTaskConfig()

    def reaches(self, arm: str, point: Sequence[float]) -> bool:
        """Whether ``arm``'s map holds ``point`` (3,) [m]."""
        return bool(self.space.reachability(arm, np.asarray(point, float)[None])
                    .inside[0])

    def plan(self, scene: TabletopScene) -> TaskPlan:
        """Allocate, insert hand-overs and schedule the rounds (module doc). Reachability is
        asked of the hand targets: the grasp point above an object, the release point above
        a target area."""
        c = self.config
        names = list(scene.objects)
        pts = np.array([scene.objects[n] for n in names])
        up = np.array([0.0, 0.0, 1.0])
        alloc = self.space.allocate(pts + c.grasp_height * up)
        undeliverable: dict[str, str] = {}
        slot = self._slots(scene, names)
        entries: dict[str, list[tuple[int, str]]] = {a: [] for a in HANDS}
        for arm in HANDS:
            for i in alloc.assignments[arm]:
                dest = slot[names[i]]
                if self.reaches(arm, dest + c.place_height * up):
                    entries[arm].append((i, "deliver"))
                elif self.reaches(_other(arm), dest + c.place_height * up):
                    entries[arm].append((i, "handover"))
                else:
                    undeliverable[names[i]] = (f"no arm reaches its target area "
                                               f"{scene.destinations[names[i]]!r}")
        picked_in = {i: r for a in HANDS for r, (i, _) in enumerate(entries[a])}
        queues: dict[str, list[Job | None]] = {a: [] for a in HANDS}
        spots: list[np.ndarray] = []
        followups: list[tuple[int, Job]] = []  # (round of the hand-over, the other arm's job)
        for arm in HANDS:
            for r, (i, kind) in enumerate(entries[arm]):
                name = names[i]
                area = scene.destinations[name]
                dest = slot[name]
                if kind == "deliver":
                    queues[arm].append(Job(arm, name, "deliver", pts[i].copy(), dest, area))
                    continue
                # still on the table when this object is put down: objects not picked in an
                # earlier round, the target areas and the other hand-overs' spots
                occupied = [pts[k] for k in range(len(names)) if picked_in.get(k, r) >= r]
                occupied += list(slot.values()) + spots
                spot = self._empty_area(arm, occupied, float(pts[:, 2].mean()))
                if spot is None:
                    undeliverable[name] = "no empty area in the shared workspace for a hand-over"
                    queues[arm].append(None)
                    continue
                spots.append(spot)
                queues[arm].append(Job(arm, name, "handover", pts[i].copy(), spot, ""))
                followups.append((r, Job(_other(arm), name, "deliver", spot.copy(), dest,
                                         area)))
        for r, job in sorted(followups, key=lambda f: f[0]):
            q = queues[job.arm]
            while len(q) <= r:  # the other arm takes it in a later round than the hand-over
                q.append(None)
            q.append(job)
        n_rounds = max(len(q) for q in queues.values())
        rounds, checks, hits = [], 0, 0
        for r in range(n_rounds):
            jobs = {a: (queues[a][r] if r < len(queues[a]) else None) for a in HANDS}
            if jobs["left"] is not None and jobs["right"] is not None:
                checks += 1
                collide = bool(self.pair_check(jobs["left"], jobs["right"]))
                hits += collide
                mode = "serial" if collide else "parallel"
            elif jobs["left"] is None and jobs["right"] is None:
                continue
            else:
                mode = "single"
            first = "left" if jobs["left"] is not None else "right"
            rounds.append(TaskRound(jobs, mode, first))
        handovers = sum(1 for r in rounds for j in r.jobs.values()
                        if j is not None and j.kind == "handover")
        return TaskPlan(tuple(rounds), tuple(names[i] for i in alloc.unreachable),
                        undeliverable, handovers, (checks, hits))

    def _slots(self, scene: TabletopScene, names: list[str]) -> dict[str, np.ndarray]:
        """Each object's place point (3,) [m] in its target area: the k-th object of an area
        ``k * slot_spacing`` from its centre along y, towards y = 0."""
        count: dict[str, int] = {}
        out = {}
        for name in names:
            area = scene.destinations[name]
            c = np.asarray(scene.areas[area], dtype=float)
            k = count.get(area, 0)
            count[area] = k + 1
            out[name] = c - np.array([0.0, np.sign(c[1]) * k * self.config.slot_spacing, 0.0])
        return out

    def _empty_area(self, arm: str, occupied: list[np.ndarray], z: float
                    ) -> np.ndarray | None:
        """An empty area of the shared workspace for an object centre at height ``z`` [m]:
        the hand's release point (``place_height`` above it) in ``empty_area_band``; None
        if there is none."""
        c = self.config
        lo, hi = c.empty_area_band
        hand = np.array(occupied) + [0.0, 0.0, c.place_height]
        try:
            area = self.space.empty_area(hand, arm, radius=c.place_clearance,
                                         z_range=(z + lo, z + hi), x_range=c.place_x_range)
        except NoEmptyArea:
            return None
        return np.array([area.point[0], area.point[1], z])


class ImaginedPairCheck:
    """:data:`PairCheck` by mental simulation: both jobs' reaches, phase by phase (the four
    waypoints of :meth:`Job.waypoints`), imagined together with
    :meth:`ImaginedCollisionCheck.plan_pair`, each phase from the postures where the previous
    one ended (the first from ``q_start``, default the rest posture). A collision in any phase
    serialises the pair.

    Args:
        check: an :class:`~icub_pmp.peripersonal.ImaginedCollisionCheck`.
        config: the job's hand targets.
        q_start: the configuration {joint: rad} the jobs start from (default rest).
    """

    def __init__(self, check: object, config: TabletopTaskConfig | None = None,
                 q_start: Mapping[str, float] | None = None):
        self.check = check
        self.config = config or TabletopTaskConfig()
        self.q_start = q_start
        self.verdicts: list[object] = []  # the last call's verdicts, one per phase

    def __call__(self, left: Job, right: Job) -> bool:
        """True when a phase of the two jobs run together is imagined colliding."""
        planner = self.check.planner
        q = planner.start_configuration(self.q_start)
        names = list(planner.provider.joint_names)
        self.verdicts = []
        for wl, wr in zip(left.waypoints(self.config), right.waypoints(self.config)):
            pair = self.check.plan_pair({"left": wl, "right": wr}, q)
            self.verdicts.append(pair.verdict)
            if pair.verdict.collides:
                return True
            q = q.copy()
            for plan in pair.plans.values():
                idx = [names.index(j) for j in plan.joint_names]
                q[idx] = plan.positions[-1]
        return False
