"""Cores import no ROS: the numerical packages load in a fresh interpreter without pulling in
rclpy or any generated message module (STYLE.md, 'Numerical cores free of ROS')."""

from __future__ import annotations

import pkgutil
import subprocess
import sys

import icub_pmp
from icub_pmp.testing import repo_root

CORE_PACKAGES = [
    "icub_pmp.errors",
    "icub_pmp.config",
    "icub_pmp.kinematics",
    "icub_pmp.pmp",
    "icub_pmp.control",
    "icub_pmp.dynamics",
    "icub_pmp.cartesian",
    "icub_pmp.vision",
    "icub_pmp.baselines",
    "icub_pmp.bags",
    "icub_pmp.demo.bag_series",
    "icub_pmp.demo.report",
    "icub_sim_bridge",
]
# modules allowed to talk to ROS inside otherwise ROS-free packages
ROS_SIDE_SUFFIXES = ("_node", "_ros", ".ros", ".recorder", ".player")


def core_modules() -> list[str]:
    """Every importable module of the core packages present in this tree."""
    out: list[str] = []
    root = repo_root()
    for name in CORE_PACKAGES:
        path = root / name.replace(".", "/")
        if path.with_suffix(".py").exists():
            out.append(name)
        elif (path / "__init__.py").exists():
            out.append(name)
            for m in pkgutil.walk_packages([str(path)], prefix=name + "."):
                if not m.name.endswith(ROS_SIDE_SUFFIXES):
                    out.append(m.name)
    return out


def test_cores_do_not_import_ros():
    """Importing every core module loads no rclpy, rosidl or *_msgs/*_srvs module."""
    mods = core_modules()
    assert "icub_pmp.kinematics.robot_model" in mods
    code = (
        "import importlib, sys\n"
        f"for m in {mods!r}: importlib.import_module(m)\n"
        "bad = sorted(m for m in sys.modules if m.split('.')[0] in ('rclpy', 'rosidl_runtime_py')"
        " or m.split('.')[0].endswith(('_msgs', '_srvs', '_interfaces')))\n"
        "print('ROS_MODULES', bad)\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=repo_root(), timeout=120
    )
    assert out.returncode == 0, out.stderr
    assert "ROS_MODULES []" in out.stdout, out.stdout
    assert icub_pmp.__version__
