#!/usr/bin/env bash
# Start the robot_loop process (sim_bridge, wrench_estimator and impedance_controller composed in one process, the torque loop inside the simulator: docs/decisions/0068) with config/sim_bridge.yaml, config/wrench_estimator.yaml and config/impedance_controller.yaml; extra arguments: --ros-args -p NAME:=VALUE ... (a -p applies to all three nodes; use a --params-file with /**/NODE sections for one)
exec "$(dirname "${BASH_SOURCE[0]}")/node.sh" robot_loop "$@"
