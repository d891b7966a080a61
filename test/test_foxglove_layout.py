"""The shipped Foxglove layout (config/foxglove/demo.json) parses and names the demo's views;
a file that is not a layout is refused with a clear error. (That the graph publishes every
topic it names is checked on the everyday graph, test/test_graph_everyday.py.)"""

from __future__ import annotations

import json

import pytest

from icub_pmp.bags.foxglove_layout import layout_topics


def test_the_demo_layout_shows_robot_cameras_masks_and_ft():
    topics = layout_topics()
    assert {"/robot_description", "/tf", "/pmp/predicted_path/right_hand",
            "/pmp/predicted_path/left_hand", "/cam/left/image_raw", "/cam/right/image_raw",
            "/motion/left/mask", "/motion/right/mask", "/ft/r_arm_ft", "/ft/l_arm_ft",
            "/wrench_estimator/predicted_ft/r_arm_ft"} <= topics


def test_a_file_that_is_not_a_layout_is_refused(tmp_path):
    f = tmp_path / "x.json"
    f.write_text(json.dumps({"layout": "Plot!a"}))
    with pytest.raises(ValueError, match="not a Foxglove layout"):
        layout_topics(f)
