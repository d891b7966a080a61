#!/usr/bin/env bash
# This project's `ros2 run icub_pmp NODE [--ros-args ...]`: runs the installed executable
# install/icub_pmp/lib/icub_pmp/NODE inside the project environment.
#   scripts/run_node.sh posture_publisher --ros-args -p rate_hz:=50.0
set -eo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
if [[ $# -lt 1 ]]; then
  echo "usage: scripts/run_node.sh NODE [--ros-args ...]" >&2
  exit 2
fi
NODE="$1"; shift
EXE="$ROOT/install/icub_pmp/lib/icub_pmp/$NODE"
if [[ ! -x "$EXE" && -f "$ROOT/install/.build-stamp" ]]; then
  echo "run_node.sh: no executable '$NODE'; available: $(ls "$ROOT/install/icub_pmp/lib/icub_pmp" | tr '\n' ' ')" >&2
  exit 2
fi
exec "$ROOT/scripts/env.sh" "$EXE" "$@"
