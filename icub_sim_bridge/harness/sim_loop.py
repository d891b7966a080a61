"""SimLoop: simulator + wrench estimator + impedance controller closed in-process, in lockstep.

The same data flow as the node graph (sim_bridge -> wrench_estimator -> impedance_controller
-> sim_bridge), without DDS: each 1 ms step the estimator processes the joint state and FT
wrenches of the previous physics step (MuJoCo's sensors are computed from the state at the
start of a step, so that pair is consistent), the controller answers the current joint state
with the freshest estimate (1 ms old) and the simulator steps with the command. Used by the
closed-loop tests and benchmarks (the fastest honest test of the loop); the DDS version is
tested end to end with the nodes.
"""

from __future__ import annotations

import time
from typing import Callable, NamedTuple

import numpy as np

from icub_pmp.control.impedance_controller import ControlOutput, ImpedanceController
from icub_pmp.control.impedance_controller_config import ImpedanceControllerConfig
from icub_pmp.dynamics.wrench_estimator import WrenchEstimate, WrenchEstimator
from icub_pmp.dynamics.wrench_estimator_config import WrenchEstimatorConfig
from icub_sim_bridge.sim_config import SimConfig
from icub_sim_bridge.simulator import Simulator

__all__ = ["SimLoop", "LoopStep"]

_FT = {"left": "l_arm_ft", "right": "r_arm_ft"}


class LoopStep(NamedTuple):
    """One loop step: time [s], joint positions/velocities (n,) in the simulator's order,
    the controller output, the estimate, and the ground-truth hand wrenches {hand: (6,)} in
    root_link about the hand origin."""

    t: float
    q: np.ndarray
    v: np.ndarray
    control: ControlOutput
    estimate: WrenchEstimate | None
    ground_truth: dict[str, np.ndarray]


class SimLoop:
    """Closed loop of :class:`Simulator`, :class:`WrenchEstimator` and
    :class:`ImpedanceController` (module doc). ``estimator=False`` runs without estimates."""

    def __init__(
        self,
        controller_config: ImpedanceControllerConfig | None = None,
        estimator_config: WrenchEstimatorConfig | None = None,
        sim_config: SimConfig | None = None,
        sim: Simulator | None = None,
        estimator: bool = True,
    ):
        self.sim = sim or Simulator(sim_config or SimConfig(cameras_enabled=False))
        self.controller = ImpedanceController(controller_config, self.sim.spec)
        if self.controller.joint_names != self.sim.joint_names:
            raise ValueError("controller and simulator joint orders differ")
        self.estimator = WrenchEstimator(estimator_config, self.sim.spec) if estimator else None
        self._est_idx = (self.sim.indices(self.estimator.joint_names)
                         if self.estimator else None)
        self._prev = None  # joint state at the start of the last physics step
        #: wall-clock seconds per call of WrenchEstimator.update, ImpedanceController.step and
        #: Simulator.step (filled while ``record_timing``)
        self.timing = {"estimator": [], "controller": [], "sim": []}
        self.record_timing = False

    @property
    def t(self) -> float:
        """Simulated time [s]."""
        return self.sim.time

    def step(self) -> LoopStep:
        """One 1 ms lockstep iteration (module doc)."""
        sim = self.sim
        js = sim.joint_state()
        est = None
        clock = time.perf_counter
        if (self.estimator is not None and self._prev is not None
                and self.sim.steps % self.estimator.config.sample_every == 0):
            p = self._prev
            ft = {}
            for h, name in _FT.items():
                w = sim.ft(name)
                ft[h] = np.concatenate((w.force, w.torque))
            imu = sim.imu().linear_acceleration if \
                self.estimator.config.gravity_source == "imu" else None
            q, v = p.position[self._est_idx], p.velocity[self._est_idx]
            t0 = clock()
            est = self.estimator.update(p.time, q, v, ft, imu)
            if self.record_timing:
                self.timing["estimator"].append(clock() - t0)
            self.controller.set_estimate(est.t, self.estimator.joint_names, est.tau)
        t0 = clock()
        out = self.controller.step(js.time, js.position, js.velocity)
        if self.record_timing:
            self.timing["controller"].append(clock() - t0)
        gt = {}
        for h in _FT:
            w = sim.contact_wrench(h)
            gt[h] = np.concatenate((w.force, w.torque))
        sim.command_all(out.tau)
        t0 = clock()
        sim.step()
        if self.record_timing:
            self.timing["sim"].append(clock() - t0)
        self._prev = js
        return LoopStep(js.time, js.position, js.velocity, out, est, gt)

    def run(self, duration: float, callback: Callable[[LoopStep], None] | None = None
            ) -> list[LoopStep]:
        """Run for ``duration`` [s] of simulated time; returns every step (``callback`` is
        called after each)."""
        n = int(round(duration / self.sim.config.timestep))
        out = []
        for _ in range(n):
            s = self.step()
            out.append(s)
            if callback is not None:
                callback(s)
        return out
