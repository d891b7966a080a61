"""ament_python package for icub_pmp (entry points = ROS 2 executables)."""

from glob import glob

from setuptools import find_packages, setup

PACKAGE = "icub_pmp"

# One entry per node executable (`ros2 run icub_pmp <name>`): name -> module with its main().
NODES = {
    "body_schema": f"{PACKAGE}.nodes.body_schema",
    "cartesian_solver": f"{PACKAGE}.nodes.cartesian_solver",
    "gaze_controller": f"{PACKAGE}.nodes.gaze_controller",
    "impedance_controller": f"{PACKAGE}.nodes.impedance_controller",
    "motion_segmenter": f"{PACKAGE}.nodes.motion_segmenter",
    "peripersonal_space": f"{PACKAGE}.nodes.peripersonal_space",
    "pmp_planner": f"{PACKAGE}.nodes.pmp_planner",
    "posture_publisher": f"{PACKAGE}.nodes.posture_publisher",
    "robot_state_publisher": f"{PACKAGE}.nodes.robot_state_publisher",
    "robot_loop": "icub_sim_bridge.robot_loop_node",
    "sim_bridge": "icub_sim_bridge.sim_bridge_node",
    "torque_loop": f"{PACKAGE}.nodes.torque_loop",
    "wrench_estimator": f"{PACKAGE}.nodes.wrench_estimator",
}

setup(
    name=PACKAGE,
    version="0.1.0",
    packages=find_packages(include=["icub_pmp", "icub_pmp.*", "icub_sim_bridge",
                                    "icub_sim_bridge.*"]),
    data_files=[
        ("share/ament_index/resource_index/packages", [f"resource/{PACKAGE}"]),
        (f"share/{PACKAGE}", ["package.xml"]),
        (f"share/{PACKAGE}/config", glob("config/*.yaml")),
        (f"share/{PACKAGE}/scripts", glob("scripts/*.sh")),
    ],
    install_requires=["setuptools"],
    zip_safe=True,
    maintainer="icub_pmp developers",
    maintainer_email="icub-pmp@example.org",
    description="ROS 2 Jazzy iCub node graph: PMP planner, controllers, estimators, MuJoCo sim",
    license="BSD-3-Clause",
    entry_points={
        "console_scripts": [f"{n} = {module}:main" for n, module in NODES.items()]
        + ["icub = icub_pmp.cli.main:main"],
    },
)
