#!/usr/bin/env bash
# Replay an MCAP bag on the graph (see `icub bag play --help`); Ctrl-C stops it.
#   scripts/replay.sh bags/run1
#   scripts/replay.sh bags/run1 --rate 0.5 --clock          # drive use_sim_time nodes
#   scripts/replay.sh bags/run1 --topics /joint_states /tf /tf_static /robot_description
set -eo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
if [[ ! -x "$ROOT/.venv/bin/python" || ! -f "$ROOT/install/.build-stamp" ]]; then
  echo "replay.sh: the environment is not built; run 'make env' first" >&2
  exit 2
fi
if [[ $# -lt 1 ]]; then
  echo "usage: scripts/replay.sh BAG_DIR [--rate R] [--clock [HZ]] [--topics T ...]" >&2
  exit 2
fi
echo "replay.sh: icub bag play $* (ROS_DOMAIN_ID=${ROS_DOMAIN_ID:-42})" >&2
exec "$ROOT/scripts/env.sh" icub bag play "$@"
