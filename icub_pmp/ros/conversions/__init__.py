"""Message <-> numpy conversions: pure functions, one import path for the whole project.

One module per message family (:mod:`.stamps`, :mod:`.joint_states`, :mod:`.geometry`,
:mod:`.trajectories`, :mod:`.images`), all re-exported here. Validation lives here too, so every
node rejects a malformed message the same way: the functions raise
:class:`~icub_pmp.errors.InvalidInput` (or ``UnknownName``) with a one-line message that the
node logs (throttled) before dropping the message.
"""

from icub_pmp.ros.conversions.geometry import (
    array_to_wrench,
    arrays_to_pose,
    point_to_array,
    pose_to_arrays,
    set_wrench,
    wrench_to_array,
)
from icub_pmp.ros.conversions.images import IMAGE_ENCODINGS, array_to_image, image_to_array
from icub_pmp.ros.conversions.joint_states import (
    joint_state_arrays,
    joint_state_field,
    make_joint_state,
    validate_joint_state,
)
from icub_pmp.ros.conversions.stamps import (
    duration_to_sec,
    sec_to_duration,
    sec_to_time,
    time_to_ns,
    time_to_sec,
)
from icub_pmp.ros.conversions.trajectories import (
    arrays_to_trajectory,
    positions_to_path,
    trajectory_extras,
    trajectory_to_arrays,
)

__all__ = [
    "time_to_sec",
    "time_to_ns",
    "sec_to_time",
    "sec_to_duration",
    "duration_to_sec",
    "make_joint_state",
    "joint_state_field",
    "validate_joint_state",
    "joint_state_arrays",
    "set_wrench",
    "trajectory_extras",
    "wrench_to_array",
    "array_to_wrench",
    "point_to_array",
    "pose_to_arrays",
    "arrays_to_pose",
    "trajectory_to_arrays",
    "arrays_to_trajectory",
    "positions_to_path",
    "image_to_array",
    "array_to_image",
    "IMAGE_ENCODINGS",
]
