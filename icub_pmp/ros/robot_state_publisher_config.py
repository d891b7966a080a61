"""RobotStatePublisherConfig: parameters of the ``robot_state_publisher`` node
(``config/robot_state_publisher.yaml``)."""

from __future__ import annotations

import dataclasses

from icub_pmp.config import ConfigBase
from icub_pmp.errors import ConfigError

__all__ = ["RobotStatePublisherConfig", "MESH_URIS"]

#: "file": mesh URIs rewritten to file:// paths of this install (a viewer on this machine, e.g.
#: Foxglove desktop, loads them); "package": kept as package://iCub/... (needs ROS_PACKAGE_PATH).
MESH_URIS = ("file", "package")


@dataclasses.dataclass(frozen=True)
class RobotStatePublisherConfig(ConfigBase):
    """Rate of /tf and the form of the URDF published on /robot_description.

    Attributes:
        publish_frequency: highest rate of /tf messages [Hz] (wall clock).
        mesh_uris: file | package: form of the mesh URIs in the URDF (see MESH_URIS).
    """

    publish_frequency: float = 50.0
    mesh_uris: str = "file"

    def validate(self) -> None:
        """Check ranges."""
        if not 0.0 < self.publish_frequency <= 1000.0:
            raise ConfigError(
                f"publish_frequency: expected in (0, 1000] Hz, got {self.publish_frequency}"
            )
        if self.mesh_uris not in MESH_URIS:
            raise ConfigError(f"mesh_uris: got {self.mesh_uris!r}, valid: {', '.join(MESH_URIS)}")
