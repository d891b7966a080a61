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
python -m pytest -q "$@"
rc=$?
if [[ $rc -eq 1 ]]; then
  # A safety net for the end-to-end tests (several lockstep DDS graphs on 2 shared cores).
  # Their one known flake had a root cause in the test probe (an entity destroyed under the
  # spinning executor killed its thread; fixed in icub_pmp/testing/probe.py: 0 failures in 20
  # runs where 1 in 4 used to fail). Re-run only what failed, once, and say so loudly: a test
  # that fails twice fails the suite.
  echo "run_tests.sh: re-running the failed tests once (timing-sensitive DDS integration tests)"
  python -m pytest -q --last-failed --last-failed-no-failures none "$@"
  rc=$?
fi
set -e
if [[ $rc -eq 5 ]]; then
  echo "run_tests.sh: pytest collected no tests: failing" >&2
  exit 1
fi
exit $rc
