"""A Reach service server for interface tests (not a planner): answers each request with the
distance of each target from root_link's origin as the residual and one trajectory point per
hand, and prints one line per request so tests can count what was sent.

    python -m icub_pmp.testing.reach_echo_server
"""

from __future__ import annotations

import math

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from trajectory_msgs.msg import JointTrajectoryPoint

from icub_interfaces.srv import Reach


class ReachEchoServer(Node):
    """Serve /pmp/reach with echoes (module doc)."""

    def __init__(self) -> None:
        super().__init__("reach_echo_server")
        self.create_service(Reach, "/pmp/reach", self.on_request)
        print("READY", flush=True)

    def on_request(self, req: Reach.Request, res: Reach.Response) -> Reach.Response:
        """Answer with the targets' distances from the origin [m] as residuals."""
        print(f"REQUEST hands={list(req.hands)} tau={req.tau}", flush=True)
        res.hands = list(req.hands)
        for hand in req.hands:
            p = (req.left_target if hand == "left" else req.right_target).pose.position
            res.residuals.append(math.sqrt(p.x**2 + p.y**2 + p.z**2))
        res.trajectory.joint_names = [f"{h}_dummy" for h in req.hands]
        pt = JointTrajectoryPoint(positions=[1.0] * len(req.hands))
        pt.time_from_start.sec = int(req.tau)
        res.trajectory.points.append(pt)
        res.success = True
        res.message = f"frame={req.right_target.header.frame_id or req.left_target.header.frame_id}"
        return res


def main() -> None:
    """Serve until SIGINT."""
    rclpy.init()
    node = ReachEchoServer()
    try:
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


if __name__ == "__main__":
    main()
