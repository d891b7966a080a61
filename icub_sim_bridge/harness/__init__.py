"""Simulator harness for tests and benchmarks (not used by any node).

- :mod:`.sim_loop`: :class:`SimLoop`, the simulator, the wrench estimator and the impedance
  controller closed in-process in lockstep;
- :mod:`.sim_scenarios`: the closed-loop scenarios shared by tests and benchmarks;
- :mod:`.sequence_generator`: eye-camera sequences rendered by the simulator with ground-truth
  motion masks.

The dependency points one way: the harness uses the simulator and the cores of ``icub_pmp``;
no core imports the harness or the simulator. Import the modules directly (MuJoCo loads with
them).
"""
