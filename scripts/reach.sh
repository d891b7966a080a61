#!/usr/bin/env bash
# Send a PMP reach goal to /pmp/reach and print the answer (see `icub reach --help`).
#   scripts/reach.sh right=-0.30,0.15,0.05 --tau 2
#   scripts/reach.sh left=-0.3,-0.1,0.1 right=-0.3,0.1,0.1 --torso --simulate
set -eo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
if [[ ! -f "$ROOT/install/.build-stamp" ]]; then
  echo "reach.sh: the environment is not built; run 'make env' first" >&2
  exit 2
fi
echo "reach.sh: icub reach $* (ROS_DOMAIN_ID=${ROS_DOMAIN_ID:-42})" >&2
exec "$ROOT/scripts/env.sh" icub reach "$@"
