"""The emulated grasp over DDS (issue 19): sim_bridge's /sim/grasp refuses a grasp without
palm contact with a message that says so, accepts it once the cube touches the palm, and
/ground_truth/object_contacts reports the contact and the grasp; bad requests answer a clear
error while the node keeps running."""

from __future__ import annotations

import pytest
from geometry_msgs.msg import Pose

from icub_interfaces.msg import ObjectContacts
from icub_interfaces.srv import Grasp, SetObjectPose
from icub_pmp.config import config_dir
from icub_pmp.testing import NodeProcess, ros_environment
from icub_sim_bridge.sim_config import SimConfig
from icub_sim_bridge.simulator import Simulator

pytestmark = pytest.mark.integration

CUBES = "cube_a:-0.30,-0.15,-0.07"


def _call(probe, service: str, srv_type, request):
    clients = probe.__dict__.setdefault("grasp_clients", {})
    client = clients.get(service)
    if client is None:
        client = clients[service] = probe.node.create_client(srv_type, service)
    assert client.wait_for_service(timeout_sec=60.0), service
    future = client.call_async(request)
    assert probe.wait_for(future.done, 30.0), f"{service}: no answer"
    return future.result()


def _grasp(probe, obj: str, hand: str, attach: bool):
    req = Grasp.Request()
    req.object, req.hand, req.attach = obj, hand, attach
    return _call(probe, "/sim/grasp", Grasp, req)


def test_grasp_service(ros_domain_id, ros_probe):
    proc = NodeProcess("sim_bridge", env=ros_environment(ros_domain_id),
                       params_file=config_dir() / "sim_bridge.yaml",
                       parameters={"cameras_enabled": False, "tabletop_objects": CUBES})
    try:
        assert ros_probe.wait_for_topic("/joint_states", timeout=60.0), proc.output()[-3000:]
        # a first call on a fresh client can lose its answer: this one changes nothing
        r = _grasp(ros_probe, "cube_a", "middle", True)
        assert not r.success and "hand" in r.message and "left" in r.message
        r = _grasp(ros_probe, "cube_a", "left", True)
        assert not r.success and "does not touch" in r.message, r.message
        r = _grasp(ros_probe, "box", "left", True)
        assert not r.success and "graspable" in r.message, r.message
        # the cube onto the resting left palm (the node starts at rest, as this model)
        palm = Simulator(SimConfig(cameras_enabled=False, tabletop_objects=CUBES)).frame_pose(
            "l_hand_dh_frame").position
        req = SetObjectPose.Request()
        req.name = "cube_a"
        req.pose = Pose()
        req.pose.position.x, req.pose.position.y, req.pose.position.z = (float(v) for v in palm)
        req.pose.orientation.w = 1.0
        assert _call(ros_probe, "/sim/set_object_pose", SetObjectPose, req).success
        r = _grasp(ros_probe, "cube_a", "left", True)
        assert r.success, r.message
        msgs = ros_probe.collect("/ground_truth/object_contacts", ObjectContacts, 20)
        held = [c for m in msgs for c in m.contacts if c.object == "cube_a"]
        assert held and all(c.arm == "left" and c.grasped for c in held)
        assert "l_hand" in {c.body for c in held}
        r = _grasp(ros_probe, "cube_a", "left", False)
        assert r.success and "released" in r.message, r.message
        assert proc.alive()
    finally:
        rc = proc.stop()
        assert rc == 0, proc.output()[-3000:]
