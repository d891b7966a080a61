"""icub_pmp: iCub reaching and bimanual coordination as a ROS 2 Jazzy node graph.

Numerical cores (``pmp``, ``kinematics``, ``dynamics``, ``control``, ``cartesian``, ``vision``,
``bags``) import no ROS module; the thin rclpy adapters live in ``icub_pmp.nodes`` and the
command line in ``icub_pmp.cli``.
"""

__version__ = "0.1.0"
