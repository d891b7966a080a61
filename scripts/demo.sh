#!/usr/bin/env bash
# `make demo`: the main job of the project. Runs inside scripts/env.sh.
# Until the full demo (bimanual PMP reach on the simulator, recorded and replayed) lands, this
# runs what exists: a posture source, the graph listing and a measured rate.
set -eo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
export ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST
echo "demo: starting posture_publisher (domain $ROS_DOMAIN_ID)"
"$ROOT/scripts/run_node.sh" posture_publisher --ros-args -p rate_hz:=100.0 &
PID=$!
trap 'kill -INT $PID 2>/dev/null; wait $PID 2>/dev/null || true' EXIT
icub graph --wait 3
icub hz /joint_states --duration 2 --timeout 20
