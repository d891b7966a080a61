#!/usr/bin/env bash
# Start one node with its parameter file: scripts/node.sh NODE [--ros-args EXTRA...]
# = ros2 run icub_pmp NODE --ros-args --params-file config/NODE.yaml EXTRA...
# The per-node scripts (scripts/sim_bridge.sh, ...) call this. torque_loop (the
# wrench_estimator and impedance_controller nodes in one process) reads both their files,
# robot_loop (sim_bridge and those two) its three.
set -eo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
NODE="${1:?usage: scripts/node.sh NODE [--ros-args ...]}"; shift
if [[ ! -x "$ROOT/.venv/bin/python" || ! -f "$ROOT/install/.build-stamp" ]]; then
  echo "$NODE.sh: the environment is not built; run 'make env' first" >&2
  exit 2
fi
if [[ ! -x "$ROOT/install/icub_pmp/lib/icub_pmp/$NODE" ]]; then
  echo "$NODE.sh: node '$NODE' is not installed; run 'make env'" >&2
  exit 2
fi
ARGS=()
# a composed process reads the parameter file of each node it hosts
case "$NODE" in
  torque_loop) CONFIGS="wrench_estimator impedance_controller" ;;
  robot_loop) CONFIGS="sim_bridge wrench_estimator impedance_controller" ;;
  *) CONFIGS="$NODE" ;;
esac
for c in $CONFIGS; do
  PARAMS="$ROOT/config/$c.yaml"
  [[ -f "$PARAMS" ]] && ARGS+=(--params-file "$PARAMS")
done
if [[ "${1:-}" == "--ros-args" ]]; then shift; fi
ARGS+=("$@")
echo "$NODE.sh: ros2 run icub_pmp $NODE --ros-args ${ARGS[*]} (ROS_DOMAIN_ID=${ROS_DOMAIN_ID:-42})" >&2
exec "$ROOT/scripts/run_node.sh" "$NODE" --ros-args "${ARGS[@]}"
