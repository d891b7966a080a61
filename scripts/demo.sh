#!/usr/bin/env bash
# `make demo`: the papers' scenario on the simulated iCub, recorded to bags/demo-<timestamp>/
# and reported (see icub_pmp/demo/scenario.py), on the shipped icub robot (--realism ideal: the
# exact simulator; --phases bimanual,...: some phases only). Runs inside scripts/env.sh; extra arguments
# are passed on (--out DIR).
set -eo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
export ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST
cd "$ROOT"
exec python -m icub_pmp.demo "$@"
