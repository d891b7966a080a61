"""Node faults in the running lockstep graph (issue 22): a node killed in the middle of a
reach (icub_pmp.testing.fault_injection), the representative subset of the fault table (the
whole matrix, every node x SIGKILL/SIGTERM, is bench/reliability.py):

- the controller SIGKILLed: the simulator does not deadlock (it times out, says so on
  /sim/status, holds) and steps on the restarted controller's commands;
- the planner SIGTERMed: the controller holds the robot at the end of the trajectory it had,
  the restarted planner serves; a client made before the restart waits or answers;
- the estimator SIGKILLed: the controller keeps the robot safe (torque loop off or a safe
  hold, said on its status topic), the restarted estimator rejoins.

Every row: the other nodes keep running and the next reach goal succeeds on the robot.
"""

from __future__ import annotations

import signal

import pytest

from icub_pmp.testing import NodeGraph
from icub_pmp.testing.fault_injection import FAULT_GRAPH, FAULT_PARAMS, FaultInjector, format_table

pytestmark = [pytest.mark.integration, pytest.mark.slow]


@pytest.fixture(scope="module")
def injector(ros_domain_id, ros_probe_module):
    with NodeGraph(FAULT_GRAPH, FAULT_PARAMS) as graph:
        inj = FaultInjector(ros_probe_module, graph)
        assert inj.wait_ready(), graph.outputs()
        ok, text = inj.reach()
        assert ok, f"{text}\n{graph.outputs()}"
        rows: list = []
        yield inj, rows
        print("\n" + format_table(rows))


def _check(inj, row) -> None:
    assert row.others_alive, f"{row}\n{inj.graph.outputs()}"
    assert "HANG" not in row.early_call, row
    assert row.recovered, f"{row}\n{inj.graph.outputs()}"


def test_controller_sigkill_simulator_times_out_and_resumes(injector):
    inj, rows = injector
    row = inj.run("impedance_controller", signal.SIGKILL)
    rows.append(row)
    _check(inj, row)
    # the simulator says it holds because the controller's answer did not come in time
    assert "holding" in row.simulator.split(";")[0] and "lockstep_timeout" in row.simulator, row
    assert row.interrupted_goal and "hang" not in row.interrupted_goal, row


def test_planner_sigterm_controller_holds_and_planner_rejoins(injector):
    inj, rows = injector
    row = inj.run("pmp_planner", signal.SIGTERM)
    rows.append(row)
    _check(inj, row)
    assert row.early_call.startswith("ok"), row


def test_planner_sigkill_early_client_gets_an_answer_never_hangs(injector):
    """The service-discovery race: after a SIGKILL the dead planner stays "available" to a
    client until its DDS lease expires; a request sent to it is lost. The bounded wait ends
    in a clear error and the retry reaches the restarted planner."""
    inj, rows = injector
    row = inj.run("pmp_planner", signal.SIGKILL)
    rows.append(row)
    _check(inj, row)
    assert row.early_call.startswith("ok"), row


def test_estimator_sigkill_controller_stays_safe(injector):
    inj, rows = injector
    row = inj.run("wrench_estimator", signal.SIGKILL)
    rows.append(row)
    _check(inj, row)
    assert row.controller != "(no status)", row


def test_short_soak_answers_every_goal(injector):
    """After the faults, a short soak on the same graph (three reach / squeeze / release
    cycles: the fewest that give a memory slope): every goal and call answered and
    succeeded, the loop keeps stepping, memory sampled. The timed soaks (2 and 30 min) are
    bench/reliability.py's."""
    import math

    from icub_pmp.testing.soak import SoakRunner

    inj, _ = injector
    report = SoakRunner(inj.probe, inj.graph, inj.client).run(0.0, min_cycles=3)
    print("\n", report.summary())
    assert report.goals_answered == report.goals_sent, report.summary()
    assert report.goals_succeeded == report.goals_sent, report.summary()
    assert report.loop_rate_first > 0 and report.loop_rate_last > 0, report.summary()
    assert all(math.isfinite(v) for v in report.rss_growth_mb_per_h.values()), report.summary()
