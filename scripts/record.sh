#!/usr/bin/env bash
# Record topics into an MCAP bag (rosbag2 layout) until Ctrl-C, which finalises the bag
# (see `icub bag record --help`). Without arguments: every topic to bags/<date-time>/.
#   scripts/record.sh                                   # --all -o bags/<date-time>
#   scripts/record.sh -o bags/run1 --all
#   scripts/record.sh -o bags/arm /joint_states /ft/r_arm_ft --compression zstd
set -eo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
if [[ ! -x "$ROOT/.venv/bin/python" || ! -f "$ROOT/install/.build-stamp" ]]; then
  echo "record.sh: the environment is not built; run 'make env' first" >&2
  exit 2
fi
ARGS=("$@")
if [[ $# -eq 0 ]]; then
  ARGS=(-o "$ROOT/bags/$(date +%Y-%m-%d_%H-%M-%S)" --all)
fi
echo "record.sh: icub bag record ${ARGS[*]} (ROS_DOMAIN_ID=${ROS_DOMAIN_ID:-42})" >&2
exec "$ROOT/scripts/env.sh" icub bag record "${ARGS[@]}"
