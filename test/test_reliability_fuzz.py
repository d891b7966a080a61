"""Every interface of the graph fuzzed over DDS (issue 22): drawn requests, goals and messages
(icub_pmp.testing.message_fuzz, derived from the types) sent to the real nodes started as a
user starts them.

Claims: no node dies, whatever it receives; every service and action answers within its
budget (icub_pmp.testing.graph_interfaces); every rejection says why; the controller never
commands a torque beyond the joints' limits; after the fuzzing each node still serves a good
request. The per-interface tally is printed (``pytest -s``) and kept for the failure message.
"""

from __future__ import annotations

import pytest

from icub_pmp.testing import NodeGraph
from icub_pmp.testing import graph_interfaces as gi
from icub_pmp.testing.fuzz_tally import FuzzTally
from icub_pmp.testing.interface_fuzzer import InterfaceFuzzer
from icub_pmp.testing.torque_watch import TorqueWatch

pytestmark = [pytest.mark.integration, pytest.mark.slow]

#: case counts x this (the full counts are bench/reliability.py's). The draws are
#: derandomised: at 0.7 every service and action that draws a plausible case (one that gets
#: past validation into planning, solving or executing) at full scale still draws one; at 0.5
#: the look-at, the trajectory and the reach goals drew none (decision 0027)
SCALE = 0.7


@pytest.fixture(scope="module")
def fuzz(ros_domain_id, ros_probe_module):
    """The graph (cameras off), a torque watch on /effort_command and the fuzzer."""
    from sensor_msgs.msg import JointState

    from icub_interfaces.srv import Reach

    probe = ros_probe_module
    with NodeGraph(gi.FUZZ_GRAPH, gi.FUZZ_PARAMS) as graph:
        assert probe.wait_for_service("/pmp/reach", Reach, 180.0), graph.outputs()
        assert probe.collect("/joint_states", JointState, 1, 60.0), graph.outputs()
        assert probe.wait_for(
            lambda: probe.node.count_publishers("/effort_command") >= 1, 60.0), graph.outputs()
        watch = TorqueWatch(probe)
        fuzzer = InterfaceFuzzer(probe, graph, tally=FuzzTally())
        yield fuzzer, watch
        print("\n" + fuzzer.tally.table() + "\n" + fuzzer.tally.reasons())


def _clean(tally, names) -> None:
    bad = [tally.interfaces[n] for n in names if n in tally.interfaces]
    problems = [f"{t.name} ({t.node}): {t.crashes} crashes, {t.hangs} hangs, {t.unclear} "
                f"unclear; e.g. {t.examples}" for t in bad if t.crashes or t.hangs or t.unclear]
    assert not problems, "\n".join(problems)
    assert all(tally.interfaces[n].cases >= 1 for n in names), names


def _answers_good_requests(fuzzer) -> None:
    from std_srvs.srv import SetBool

    from icub_interfaces.srv import LookAt, Reach, SolvePose

    probe = fuzzer.probe
    req = SetBool.Request()
    req.data = False
    assert probe.call("/sim/set_paused", SetBool, req, 30.0).success
    res = probe.call("/pmp/reach", Reach, gi.good_reach(), 60.0)
    assert res.success, res.message
    res = probe.call("/cartesian/solve_pose", SolvePose, gi.good_solve_pose(), 60.0)
    assert res.success, res.message
    res = probe.call("/gaze/look_at", LookAt, gi.good_look_at(), 60.0)
    assert res.success, res.message


def test_services_survive_fuzzed_requests(fuzz):
    """Every service: drawn requests answered within budget, rejections with a message, the
    serving node alive; then a good request to each planner still succeeds."""
    fuzzer, _ = fuzz
    _clean(fuzzer.tally, gi.fuzz_services(fuzzer, SCALE))
    _answers_good_requests(fuzzer)


def test_actions_survive_fuzzed_goals(fuzz):
    """Every action: drawn goals acknowledged and ended (or canceled) within budget; an
    aborted goal says why; the serving node alive."""
    fuzzer, _ = fuzz
    _clean(fuzzer.tally, gi.fuzz_actions(fuzzer, SCALE))
    assert all(fuzzer.graph.alive().values()), fuzzer.graph.outputs()


def test_topics_survive_fuzzed_messages(fuzz):
    """Every subscribed topic: drawn messages, out-of-order stamps, a 10x burst and corrupt
    CDR; every subscriber alive, the controller's torques within the limits throughout, and
    the nodes still serve good requests."""
    from sensor_msgs.msg import JointState

    fuzzer, watch = fuzz
    _clean(fuzzer.tally, gi.fuzz_topics(fuzzer, SCALE))
    assert watch.messages > 100, "the controller published (almost) no torques"
    assert watch.violations == 0, watch.examples
    assert fuzzer.probe.collect("/effort_command", JointState, 5, 30.0), \
        "the controller stopped commanding"
    _answers_good_requests(fuzzer)


def test_simulator_survives_fuzzed_commands(fuzz):
    """/effort_command (the simulator's input; the torque watch is off from here on):
    drawn commands, disordered and corrupt; the simulator keeps stepping."""
    from rosgraph_msgs.msg import Clock

    fuzzer, watch = fuzz
    watch.pause()
    _clean(fuzzer.tally, gi.fuzz_effort(fuzzer, SCALE))
    clocks = fuzzer.probe.collect("/clock", Clock, 3, 30.0)
    assert len(clocks) == 3, fuzzer.graph.outputs()
