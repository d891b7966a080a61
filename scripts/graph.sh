#!/usr/bin/env bash
# Start the whole node graph (each node with its config/<node>.yaml) and keep it running until
# Ctrl-C, SIGINT or SIGTERM; then stop exactly the children this script started (SIGTERM,
# then SIGKILL after 5 s) and exit. Works when started in the background by another script
# too: bash ignores SIGINT in background jobs and cannot trap a signal ignored on entry, so the
# script first re-executes itself with SIGINT restored to its default.
#   scripts/graph.sh                 # all nodes
#   GRAPH_NODES="sim_bridge pmp_planner" scripts/graph.sh
#   MODE=lockstep scripts/graph.sh   # simulator and controller in lockstep (exact 1 kHz loop)
# wrench_estimator and impedance_controller run composed in one process, torque_loop
# (scripts/torque_loop.sh, docs/decisions/0067);
#   TORQUE_LOOP=0 scripts/graph.sh  # ... or in their own processes
#   ROBOT_LOOP=1 scripts/graph.sh   # sim_bridge, wrench_estimator and impedance_controller in
#                                   # one process, the torque loop on the physics thread
#                                   # (scripts/robot_loop.sh, docs/decisions/0068)
set -uo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
# SIGINT ignored on entry (bit 2 of SigIgn): re-exec with it restored, once
if [[ -z "${ICUB_GRAPH_SIGNALS:-}" ]] && \
   (( 0x$(awk '/^SigIgn:/ {print $2}' /proc/$$/status) & 2 )); then
  export ICUB_GRAPH_SIGNALS=1
  exec python3 -c 'import os, signal, sys; signal.signal(signal.SIGINT, signal.SIG_DFL); os.execv("/bin/bash", ["/bin/bash"] + sys.argv[1:])' "${BASH_SOURCE[0]}" "$@"
fi
if [[ ! -f "$ROOT/install/.build-stamp" ]]; then
  echo "graph.sh: the environment is not built; run 'make env' first" >&2
  exit 2
fi
export ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST
DEFAULT="sim_bridge torque_loop pmp_planner cartesian_solver gaze_controller motion_segmenter robot_state_publisher"
case "${TORQUE_LOOP:-1}" in
  1|"") ;;
  0) DEFAULT="${DEFAULT/torque_loop/wrench_estimator impedance_controller}" ;;
  *) echo "graph.sh: TORQUE_LOOP must be 0 or 1, got '${TORQUE_LOOP}'" >&2; exit 2 ;;
esac
case "${ROBOT_LOOP:-0}" in
  0|"") ;;
  1) [[ "${TORQUE_LOOP:-1}" == 0 ]] && { echo "graph.sh: ROBOT_LOOP=1 and TORQUE_LOOP=0 contradict each other" >&2; exit 2; }
     DEFAULT="${DEFAULT/sim_bridge torque_loop/robot_loop}" ;;
  *) echo "graph.sh: ROBOT_LOOP must be 0 or 1, got '${ROBOT_LOOP}'" >&2; exit 2 ;;
esac
NODES="${GRAPH_NODES:-$DEFAULT}"
PIDS=()
stop() {
  trap - INT TERM EXIT
  echo "graph.sh: stopping ${#PIDS[@]} node(s): ${PIDS[*]}" >&2
  for p in "${PIDS[@]}"; do kill -TERM "$p" 2>/dev/null; done
  for _ in $(seq 50); do
    alive=0
    for p in "${PIDS[@]}"; do kill -0 "$p" 2>/dev/null && alive=1; done
    [[ $alive -eq 0 ]] && break
    sleep 0.1
  done
  for p in "${PIDS[@]}"; do kill -KILL "$p" 2>/dev/null; done
  wait 2>/dev/null
}
trap 'stop; exit 130' INT
trap 'stop; exit 143' TERM
trap stop EXIT
case "${MODE:-}" in
  ""|free_run|lockstep) ;;
  *) echo "graph.sh: MODE must be free_run or lockstep, got '${MODE}'" >&2; exit 2 ;;
esac
# hold the domain's domain_coordinator lock (the TCP port the tests bind to reserve a
# ROS_DOMAIN_ID, icub_pmp.graph.reserve_domain_id) while the graph runs: a test session then
# picks another domain instead of talking to this graph
DOMAIN="${ROS_DOMAIN_ID:-42}"
if [[ "$DOMAIN" =~ ^[0-9]+$ ]] && (( DOMAIN >= 1 && DOMAIN <= 100 )); then
  coproc LOCK { exec "$ROOT/scripts/env.sh" python "$ROOT/scripts/hold_domain_lock.py" "$DOMAIN"; }
  PIDS+=("$LOCK_PID")
  read -r -t 10 _ <&"${LOCK[0]}" || true  # "held" (or "taken") once the port is bound
fi
for n in $NODES; do
  if [[ ! -x "$ROOT/install/icub_pmp/lib/icub_pmp/$n" ]]; then
    echo "graph.sh: skipping $n (not installed)" >&2
    continue
  fi
  if [[ ( "$n" == sim_bridge || "$n" == robot_loop ) && -n "${MODE:-}" ]]; then
    "$ROOT/scripts/node.sh" "$n" --ros-args -p "mode:=$MODE" &
  else
    "$ROOT/scripts/node.sh" "$n" &
  fi
  PIDS+=($!)
  echo "graph.sh: started $n (pid $!)" >&2
done
echo "graph.sh: running (ROS_DOMAIN_ID=${ROS_DOMAIN_ID:-42}); Ctrl-C stops the graph" >&2
wait
