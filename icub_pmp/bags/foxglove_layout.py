"""The Foxglove layout shipped for the demo's bag (``config/foxglove/demo.json``): which topics
it shows, so a test can check that the running graph publishes every one of them.

The layout is Foxglove's panel-state JSON (``configById`` + ``layout``): a 3D panel (the robot
from ``/robot_description`` and ``/tf``, the planner's predicted hand paths, the objects' true
poses, the estimated external wrenches, the peripersonal maps), both cameras and their motion
masks, FT plots (measured beside the rigid-body prediction) and the controller's status.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from icub_pmp.config import repo_root

__all__ = ["DEMO_LAYOUT", "layout_topics"]

#: the layout file (open the demo's bag in Foxglove, then Layout > Import from file)
DEMO_LAYOUT = Path("config/foxglove/demo.json")


def _plot_topic(path: str) -> str:
    """``/ft/r_arm_ft.wrench.force.x`` -> ``/ft/r_arm_ft`` (a message path's topic)."""
    return path.split(".", 1)[0]


def layout_topics(path: Path | None = None) -> set[str]:
    """Every topic the layout at ``path`` (default :data:`DEMO_LAYOUT`) reads.

    Raises ValueError when the file is not a Foxglove layout (no ``configById``)."""
    file = path or repo_root() / DEMO_LAYOUT
    data: Any = json.loads(Path(file).read_text())
    panels = data.get("configById") if isinstance(data, dict) else None
    if not isinstance(panels, dict) or not panels:
        raise ValueError(f"{file}: not a Foxglove layout (no 'configById' panels)")
    topics: set[str] = set()
    for panel_id, cfg in panels.items():
        kind = panel_id.split("!", 1)[0]
        if kind == "3D":
            topics.update(cfg.get("topics", {}))
            for layer in cfg.get("layers", {}).values():
                if layer.get("sourceType") == "topic" and layer.get("topic"):
                    topics.add(layer["topic"])
            topics.add("/tf")
        elif kind == "Image":
            mode = cfg.get("imageMode", {})
            topics.update(t for t in (mode.get("imageTopic"), mode.get("calibrationTopic")) if t)
        elif kind == "Plot":
            topics.update(_plot_topic(p["value"]) for p in cfg.get("paths", []))
        elif kind == "RawMessages" and cfg.get("topicPath"):
            topics.add(_plot_topic(cfg["topicPath"]))
    return topics
