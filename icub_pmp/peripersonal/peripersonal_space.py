"""PeripersonalSpace: both arms' maps and the questions asked of them (Bhat and Mohan 2018).

One object holds the left and right arms' :class:`GrowingNeuralGas` maps and answers:
reachability of points per arm (inside the map, nearest neuron, reward), the shared
workspace, neural activity for a scene, the reward fields, target allocation and the
empty-area search. The maps are saved and loaded as ``peripersonal_<arm>.npz`` in a folder
(beside the body models). Frames: root_link, [m].
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Mapping, NamedTuple

import numpy as np

from icub_pmp.errors import InvalidInput, ModelError, UnknownName
from icub_pmp.kinematics.robot_spec import HANDS
from icub_pmp.peripersonal.empty_area_finder import EmptyArea, EmptyAreaFinder
from icub_pmp.peripersonal.gng_config import GrowingNeuralGasConfig
from icub_pmp.peripersonal.growing_neural_gas import GrowingNeuralGas, as_points
from icub_pmp.peripersonal.neural_activity import neural_activity
from icub_pmp.peripersonal.peripersonal_config import PeripersonalConfig
from icub_pmp.peripersonal.reward_field import RewardField
from icub_pmp.peripersonal.shared_workspace import SharedWorkspace
from icub_pmp.peripersonal.target_allocator import Allocation, TargetAllocator

__all__ = ["PeripersonalSpace", "Reachability", "map_file"]

_ARMS_FILE = "peripersonal_arms.json"


def map_file(directory: str | Path, arm: str) -> Path:
    """Where ``arm``'s map is saved in ``directory``."""
    return Path(directory) / f"peripersonal_{arm}.npz"


class Reachability(NamedTuple):
    """Points against one arm's map: ``inside`` (m,) bool, best-matching ``neuron`` (m,),
    its ``distance`` (m,) [m] and its ``reward`` (m,) [-]."""

    inside: np.ndarray
    neuron: np.ndarray
    distance: np.ndarray
    reward: np.ndarray


class PeripersonalSpace:
    """The two arms' peripersonal maps (module doc).

    Args:
        maps: {'left': map, 'right': map}, trained.
        arm_y: {'left': Y, 'right': Y}: each arm's y coordinate [m] for its reward field;
            default: the mean y of the arm's neurons outside the shared workspace (the middle
            of the space only that arm reaches, see :class:`RewardField`).
        config: radii and kernel widths (:class:`PeripersonalConfig`).
    """

    def __init__(self, maps: Mapping[str, GrowingNeuralGas],
                 arm_y: Mapping[str, float] | None = None,
                 config: PeripersonalConfig | None = None):
        self.config = config or PeripersonalConfig()
        c = self.config
        for a in list(maps) + list(arm_y or {}):
            if a not in HANDS:
                raise UnknownName("arm", a, HANDS)
        for a in HANDS:
            if a not in maps or (arm_y is not None and a not in arm_y):
                raise InvalidInput(f"maps (and arm_y when given) are needed for both arms, "
                                   f"missing {a!r}")
            maps[a].require_trained()
        self.maps = dict(maps)
        self.shared = SharedWorkspace(self.maps, c.reach_radius)
        if arm_y is None:
            arm_y = {}
            for a in HANDS:
                own = np.ones(self.maps[a].size, dtype=bool)
                own[self.shared.neurons(a)] = False
                pts = self.maps[a].neurons[own] if own.any() else self.maps[a].neurons
                arm_y[a] = float(pts[:, 1].mean())
        self.arm_y = {a: float(arm_y[a]) for a in HANDS}
        self.reward_fields = {a: RewardField(self.maps[a].neurons, self.arm_y[a], c.sigma_r,
                                             c.r_c) for a in HANDS}
        self.allocator = TargetAllocator(self.maps, self.reward_fields, c.reach_radius)
        self.empty_areas = EmptyAreaFinder(self.shared, c.gripper_width, c.sigma_s)

    # ------------------------------------------------------------------ construction
    def save(self, directory: str | Path) -> list[Path]:
        """Write both maps (and the arms' Y) to ``directory``."""
        d = Path(directory)
        d.mkdir(parents=True, exist_ok=True)
        out = [self.maps[a].save(map_file(d, a)) for a in HANDS]
        (d / _ARMS_FILE).write_text(json.dumps({"arm_y": self.arm_y, "frame": "root_link"}))
        return out + [d / _ARMS_FILE]

    @classmethod
    def load(cls, directory: str | Path, config: PeripersonalConfig | None = None
             ) -> "PeripersonalSpace":
        """Read the maps written by :meth:`save` (:class:`ModelError` when missing)."""
        d = Path(directory)
        try:
            arm_y = json.loads((d / _ARMS_FILE).read_text())["arm_y"]
        except (OSError, ValueError, KeyError) as exc:
            raise ModelError(f"no peripersonal maps in {d}: {exc}") from exc
        return cls({a: GrowingNeuralGas.load(map_file(d, a)) for a in HANDS}, arm_y, config)

    @classmethod
    def grow(cls, babble_samples: int, seed: int, gng_config: GrowingNeuralGasConfig | None = None,
             config: PeripersonalConfig | None = None) -> "PeripersonalSpace":
        """Grow both maps from ``babble_samples`` babbled hand positions per arm
        (:func:`analytic_babbling`, seeds ``seed`` (left) and ``seed + 1`` (right))."""
        from icub_pmp.peripersonal.analytic_babbling import analytic_babbling

        maps = {}
        for k, arm in enumerate(HANDS):
            maps[arm] = GrowingNeuralGas(gng_config, label=arm)
            maps[arm].fit(analytic_babbling(arm, int(babble_samples), seed=seed + k).hand)
        return cls(maps, config=config)

    # ------------------------------------------------------------------ queries
    def _arm(self, arm: str) -> str:
        if arm not in HANDS:
            raise UnknownName("arm", arm, HANDS)
        return arm

    def reachability(self, arm: str, points: object) -> Reachability:
        """Which ``points`` (m, 3) [m] ``arm`` reaches, their best-matching neurons, their
        distance to it [m] and their reward."""
        arm = self._arm(arm)
        idx, d = self.maps[arm].nearest(points)
        inside = d <= self.config.reach_radius
        return Reachability(inside, idx, d, np.where(inside, self.reward_fields[arm][idx], 0.0))

    def activity(self, arm: str, objects: object) -> np.ndarray:
        """Activity (N,) [1/m] of ``arm``'s neurons for a scene of objects (m, 3) [m]: the
        sum over objects of ``exp(-||s_i - S||^2 / 2 sigma_s^2) / (sqrt(2 pi) sigma_s)``."""
        arm = self._arm(arm)
        return neural_activity(self.maps[arm].neurons, as_points(objects, "objects"),
                               self.config.sigma_s)

    def allocate(self, objects: object) -> Allocation:
        """Which arm acts on which object, in which order (:class:`TargetAllocator`)."""
        return self.allocator.allocate(objects)

    def empty_area(self, objects: object, arm: str = "left", radius: float | None = None,
                   z_range: tuple[float, float] | None = None,
                   x_range: tuple[float, float] | None = None) -> EmptyArea:
        """An empty area of the shared workspace (:class:`EmptyAreaFinder`)."""
        return self.empty_areas.find(objects, self._arm(arm), radius, z_range, x_range)
