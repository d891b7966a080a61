#!/usr/bin/env bash
# Start the whole node graph (each node with its config/<node>.yaml) and keep it running until
# Ctrl-C; then stop exactly the children this script started (SIGINT, then SIGKILL).
#   scripts/graph.sh                 # all nodes
#   GRAPH_NODES="sim_bridge pmp_planner" scripts/graph.sh
set -uo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
if [[ ! -f "$ROOT/install/.build-stamp" ]]; then
  echo "graph.sh: the environment is not built; run 'make env' first" >&2
  exit 2
fi
export ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST
DEFAULT="sim_bridge wrench_estimator impedance_controller pmp_planner cartesian_solver gaze_controller motion_segmenter robot_state_publisher"
NODES="${GRAPH_NODES:-$DEFAULT}"
PIDS=()
stop() {
  trap - INT TERM EXIT
  echo "graph.sh: stopping ${#PIDS[@]} node(s): ${PIDS[*]}" >&2
  for p in "${PIDS[@]}"; do kill -INT "$p" 2>/dev/null; done
  for _ in $(seq 50); do
    alive=0
    for p in "${PIDS[@]}"; do kill -0 "$p" 2>/dev/null && alive=1; done
    [[ $alive -eq 0 ]] && break
    sleep 0.1
  done
  for p in "${PIDS[@]}"; do kill -KILL "$p" 2>/dev/null; done
  wait 2>/dev/null
}
trap stop INT TERM EXIT
for n in $NODES; do
  if [[ ! -x "$ROOT/install/icub_pmp/lib/icub_pmp/$n" ]]; then
    echo "graph.sh: skipping $n (not installed)" >&2
    continue
  fi
  "$ROOT/scripts/node.sh" "$n" &
  PIDS+=($!)
  echo "graph.sh: started $n (pid $!)" >&2
done
echo "graph.sh: running (ROS_DOMAIN_ID=${ROS_DOMAIN_ID:-42}); Ctrl-C stops the graph" >&2
wait
