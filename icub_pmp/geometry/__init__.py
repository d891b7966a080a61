"""Link geometry shared by the planner and the peripersonal space: convex collision hulls
(surface samples), the capsules that bound them, and the hulls of the URDF's collision
meshes. Below :mod:`icub_pmp.pmp` and :mod:`icub_pmp.peripersonal`; no ROS imports."""

from icub_pmp.geometry.capsule import Capsule, fit_capsule, fit_capsules
from icub_pmp.geometry.link_hull import LinkHull, hull_points
from icub_pmp.geometry.urdf_hulls import arm_prefix, urdf_link_hulls

__all__ = ["Capsule", "LinkHull", "arm_prefix", "fit_capsule", "fit_capsules", "hull_points",
           "urdf_link_hulls"]
