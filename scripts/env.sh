#!/usr/bin/env bash
# Run CMD inside the project's environment: the venv, the colcon install space, DDS kept on
# this machine (ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST) and a default ROS_DOMAIN_ID.
# Builds the environment first (make env) when it is missing.
#   scripts/env.sh python bench/pmp.py --quick
set -eo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
if [[ ! -x "$ROOT/.venv/bin/python" || ! -f "$ROOT/install/.build-stamp" ]]; then
  echo "env.sh: environment not built yet, running 'make env' (a few minutes the first time)" >&2
  make -C "$ROOT" --no-print-directory env >&2
fi
# shellcheck disable=SC1091
source "$ROOT/.venv/bin/activate"
export AMENT_PREFIX_PATH="$VIRTUAL_ENV${AMENT_PREFIX_PATH:+:$AMENT_PREFIX_PATH}"
export CMAKE_PREFIX_PATH="$VIRTUAL_ENV${CMAKE_PREFIX_PATH:+:$CMAKE_PREFIX_PATH}"
set +u
# shellcheck disable=SC1091
source "$ROOT/install/setup.bash"
export ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST
export ROS_DOMAIN_ID="${ROS_DOMAIN_ID:-42}"
export RMW_IMPLEMENTATION="${RMW_IMPLEMENTATION:-rmw_fastrtps_cpp}"
# deeper Fast DDS shared-memory buffers (see config/fastdds.xml): no 1 kHz message lost by a
# bag recorder that waits for the CPU
export FASTRTPS_DEFAULT_PROFILES_FILE="${FASTRTPS_DEFAULT_PROFILES_FILE:-$ROOT/config/fastdds.xml}"
export MUJOCO_GL="${MUJOCO_GL:-egl}"
export PYTHONPATH="$ROOT${PYTHONPATH:+:$PYTHONPATH}"
export ICUB_PMP_ROOT="$ROOT"
# the icub command line (console script installed beside the node executables)
export PATH="$ROOT/install/icub_pmp/lib/icub_pmp:$PATH"
if [[ $# -eq 0 ]]; then
  echo "usage: scripts/env.sh CMD [ARGS...]" >&2
  exit 2
fi
exec "$@"
