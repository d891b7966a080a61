"""The graph split over two hosts (two network namespaces joined by a veth pair, DDS over UDP
with a peers list): the demo's first phase succeeds across the link, and with the default
setup (ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST, no peers) no DDS packet leaves the host."""

from __future__ import annotations

import os
import time

import pytest

from icub_pmp.config import repo_root
from icub_pmp.graph import NodeProcess, VethLink, VethLinkError, reserve_domain_id
from icub_pmp.graph import ros_environment as _ros_environment

pytestmark = [pytest.mark.integration, pytest.mark.slow]

ENV_SH = str(repo_root() / "scripts" / "env.sh")


@pytest.fixture(scope="module")
def link():
    """A veth link between two namespaces (skipped, with the system's error, where namespaces
    cannot be created: not root)."""
    if os.geteuid() != 0:
        pytest.skip("network namespaces need root (run the two-host setup on two machines: "
                    "README, 'Two hosts')")
    try:
        with VethLink(tag=f"t{os.getpid() % 100000}") as lk:
            yield lk
    except VethLinkError as exc:
        pytest.skip(f"network namespaces cannot be created here: {exc}")


def _talk(link: VethLink, env_pub: dict, env_sub: dict, pub_host, sub_host,
          timeout: float) -> tuple[bool, str]:
    """Publish /hello on ``pub_host``, listen on ``sub_host``: whether a message arrived."""
    echo = NodeProcess(command=[*link.prefix(sub_host), ENV_SH, "icub", "echo", "/hello",
                                "std_msgs/msg/String", "-n", "1", "--timeout", str(timeout)],
                       env=env_sub)
    pub = NodeProcess(command=[*link.prefix(pub_host), ENV_SH, "icub", "pub", "/hello",
                               "std_msgs/msg/String", "{data: across}", "-w", "0", "-r", "5",
                               ], env=env_pub)
    try:
        echo.proc.wait(timeout + 30)
    finally:
        pub.stop()
        echo.stop()
    return "data: across" in echo.output(), echo.output() + pub.output()


def test_default_setup_sends_nothing_over_the_link_and_peers_open_it(link):
    """LOCALHOST discovery and no peers: two nodes on one host talk, the other host never
    hears them (0 packets on the link); with ROS_STATIC_PEERS they find each other across."""
    with reserve_domain_id() as domain:
        env = _ros_environment(domain)
        env.pop("ROS_STATIC_PEERS", None)
        before = link.tx_packets(link.robot)
        ok, out = _talk(link, env, env, link.robot, link.robot, 20.0)
        assert ok, out  # the same host works
        time.sleep(1.0)
        assert link.tx_packets(link.robot) - before == 0, "DDS traffic left the host"
        ok, _ = _talk(link, env, env, link.robot, link.laptop, 8.0)
        assert not ok  # no peers: the other host is not discovered
        assert link.tx_packets(link.robot) - before == 0, "DDS traffic left the host"
        from icub_pmp.demo.two_hosts import host_environment

        ok, out = _talk(link, host_environment(domain, [link.laptop.address], udp_only=False),
                        host_environment(domain, [link.robot.address], udp_only=True),
                        link.robot, link.laptop, 30.0)
        assert ok, out
        assert link.tx_packets(link.robot) - before > 0


def test_demo_first_phase_succeeds_across_two_hosts():
    """Simulator, controller and estimator on the robot's PC, the planners and vision on the
    laptop: the bimanual PMP reach arrives in the physics, and the link carried the graph."""
    if os.geteuid() != 0:
        pytest.skip("network namespaces need root")
    from icub_pmp.demo.two_hosts import run_two_hosts

    try:
        # the ideal robot: the phase's 1 cm arrival tolerance is met with 0.5-0.7 mm to spare
        # there; on the shipped icub robot the hands end 9.3-9.8 mm off, at the tolerance
        out = run_two_hosts(calls=20, timeout=420.0, realism="ideal")
    except VethLinkError as exc:
        pytest.skip(f"network namespaces cannot be created here: {exc}")
    assert out["cross_host_reach_success"], out
    assert max(out["cross_host_hand_err_mm"].values()) <= 10.0, out
    assert out["link_packets"] > 1000, out
    assert out["cross_host_rtt_ms_median"] > 0 and out["cross_host_lockstep_rtf"] > 0


def test_enforced_dds_security_never_falls_back_to_an_open_graph(tmp_path):
    """ROS_SECURITY_ENABLE=true with the Enforce strategy: this machine's Fast DDS (the PyPI
    wheel) has no security plugins, and a node refuses to start with a one-line error rather
    than join the graph unprotected (README, 'Two hosts': how to run SROS2 on a stock ROS 2)."""
    import subprocess

    enclave = tmp_path / "keystore" / "enclaves" / "icub"
    enclave.mkdir(parents=True)
    for name in ("cert.pem", "key.pem", "governance.p7s", "permissions.p7s",
                 "identity_ca.cert.pem", "permissions_ca.cert.pem"):
        (enclave / name).write_text("placeholder\n")
    with reserve_domain_id() as domain:
        env = _ros_environment(domain)
        env.update(ROS_SECURITY_ENABLE="true", ROS_SECURITY_STRATEGY="Enforce",
                   ROS_SECURITY_KEYSTORE=str(tmp_path / "keystore"),
                   ROS_SECURITY_ENCLAVE_OVERRIDE="/icub")
        run = subprocess.run([ENV_SH, "icub", "echo", "/x", "std_msgs/msg/String",
                              "--timeout", "5"], env=env, capture_output=True, text=True,
                             timeout=120)
    assert run.returncode == 1
    assert "icub: error: ROS could not start a node" in run.stderr
    assert "security" in run.stderr and "Traceback" not in run.stderr
