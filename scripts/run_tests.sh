#!/usr/bin/env bash
# The test suite (called by `make test` inside scripts/env.sh). Lint first, then pytest.
# pytest's exit code 5 (nothing collected) is a failure here, never a silent pass.
set -eo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"
echo "== ruff"
LINT=()
for d in icub_pmp icub_sim_bridge test bench scripts; do [[ -e "$d" ]] && LINT+=("$d"); done
ruff check "${LINT[@]}"
echo "== pytest"
set +e
python -m pytest -q -p no:cacheprovider "$@"
rc=$?
set -e
if [[ $rc -eq 5 ]]; then
  echo "run_tests.sh: pytest collected no tests: failing" >&2
  exit 1
fi
exit $rc
