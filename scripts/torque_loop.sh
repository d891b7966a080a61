#!/usr/bin/env bash
# Start the torque_loop process (the wrench_estimator and impedance_controller nodes composed in one process, docs/decisions/0067) with config/wrench_estimator.yaml and config/impedance_controller.yaml; extra arguments: --ros-args -p NAME:=VALUE ... (a -p applies to both nodes; use a --params-file with /**/NODE sections for one)
exec "$(dirname "${BASH_SOURCE[0]}")/node.sh" torque_loop "$@"
