"""StereoTarget: the 3-D target of the eyes, frame pair by frame pair (no ROS).

Per stereo pair (both images of one stamp, the camera poses at that stamp, the two eyes'
motion segmentation results):

1. the blobs are paired across the eyes (:class:`~icub_pmp.vision.blob_pairing.BlobPairing`);
2. each pair, largest first, seeds a stereo measurement of the object
   (:class:`~icub_pmp.vision.object_locator.ObjectLocator`: its pixels' disparity, its support,
   its top face), unless the object is the robot's own arm (within ``self_radius`` of the
   forearm and hand segments given by the caller);
3. a target already followed is measured in its own image region (its projected shape) when no
   pair measures it: this keeps an object that stopped (the segmenter sees it only while it
   moves) and checks that it is still there;
4. the :class:`~icub_pmp.vision.object_tracker.ObjectTracker` fuses the measurement at the
   images' stamp.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from icub_pmp.errors import InvalidInput
from icub_pmp.kinematics.eye_kinematics import CameraIntrinsics, project_point
from icub_pmp.peripersonal.segment_distance import segment_distance
from icub_pmp.vision.blob_pairing import BlobPair, BlobPairing
from icub_pmp.vision.exceptions import ObjectNotFound
from icub_pmp.vision.head_cameras import CameraPoses
from icub_pmp.vision.motion_blobs import MotionBlobs
from icub_pmp.vision.object_locator import ObjectEstimate, ObjectGate, ObjectLocator, PointsFn
from icub_pmp.vision.object_tracker import ObjectTracker, TrackedObject
from icub_pmp.vision.stereo_rectification import StereoRectification
from icub_pmp.vision.stereo_target_config import StereoTargetConfig

__all__ = ["StereoTarget", "StereoTargetResult"]

_MAX_PAIRS = 2  # pairs measured per frame (CPU bound)
_RECENTRE = 3  # re-centred region measurements per frame at most
_RECENTRE_TOLERANCE = 0.002  # a re-centred measurement that moved less than this is done [m]


@dataclasses.dataclass(frozen=True)
class StereoTargetResult:
    """What one stereo pair gave.

    Attributes:
        target: the tracked object after this pair.
        measurement: this pair's measurement of it, if any (None: not measured).
        source: ``motion`` (measured from a blob pair), ``region`` (in the target's own
            region), ``none``.
        pairs: the consistent blob pairs of this frame.
        note: why nothing was measured ('' otherwise).
    """

    target: TrackedObject
    measurement: ObjectEstimate | None
    source: str
    pairs: tuple[BlobPair, ...]
    note: str


class StereoTarget:
    """Pairing, locating and tracking (module doc)."""

    def __init__(self, config: StereoTargetConfig | None = None,
                 left: CameraIntrinsics | None = None, right: CameraIntrinsics | None = None):
        self.config = config or StereoTargetConfig()
        self.left = left or CameraIntrinsics()
        self.right = right or self.left
        self.pairing = BlobPairing(self.config)
        self.locator = ObjectLocator(self.config)
        self.tracker = ObjectTracker(self.config)
        self._empty_since: float | None = None  # the target's place seen empty since [s]

    def reset(self) -> None:
        """Drop the target."""
        self.tracker.reset()
        self._empty_since = None

    def process(self, stamp: float, left: np.ndarray, right: np.ndarray, blobs_left: MotionBlobs,
                blobs_right: MotionBlobs, poses: CameraPoses,
                self_segments: np.ndarray | None = None,
                points_fn: PointsFn | None = None) -> StereoTargetResult:
        """One stereo pair (module doc).

        Args:
            stamp: time of both images [s].
            left, right: the images ((H, W) grey or (H, W, 3) RGB uint8).
            blobs_left, blobs_right: the segmenter's results for these images.
            poses: camera poses at ``stamp``.
            self_segments: (k, 2, 3) segments [m] of the robot's arms in root_link (e.g.
                elbow-wrist, wrist-hand); motion near them is the robot's own.
            points_fn: pixel pairs -> root_link points (default: ray triangulation).
        """
        rect = StereoRectification(self.left, self.right, poses.T_root_left, poses.T_root_right)
        pairs = self.pairing.pair(blobs_left, blobs_right, rect)
        target = self.tracker.target
        notes = []
        if not pairs and blobs_left.blobs and blobs_right.blobs:
            # why the largest blobs of the two eyes are not one object (for the node's log)
            notes.append("largest blobs unpaired: " + self.pairing.check(
                blobs_left.blobs[0], blobs_right.blobs[0], rect))
        meas: ObjectEstimate | None = None
        other: ObjectEstimate | None = None  # another object seen moving, far from the target
        source = "none"
        for p in pairs[:_MAX_PAIRS]:
            seed = _blob_seed(blobs_left, p.left)
            try:
                m = self.locator.locate(rect, left, right, seed, points_fn)
            except ObjectNotFound as exc:
                notes.append(f"pair {p.left}/{p.right}: {exc}")
                continue
            if self._is_self(m, self_segments):
                notes.append(f"pair {p.left}/{p.right}: the robot's own arm")
                continue
            if target.valid and np.linalg.norm(m.position - target.position) \
                    > self.config.track_gate:
                notes.append(f"pair {p.left}/{p.right}: another object")
                if other is None:
                    other = m
                continue
            meas, source = m, "motion"
            break
        moving = source == "motion"
        if source != "motion" and target.valid:
            try:
                m, seed = self._region(rect, left, right, target, poses, points_fn,
                                       self_segments)
                meas, source = m, "region"
                moving = bool(np.any(blobs_left.mask[seed] > 0)) and \
                    float(np.mean(blobs_left.mask[seed] > 0)) > 0.1
            except ObjectNotFound as exc:
                notes.append(f"region: {exc}")
                if self._place_is_empty(stamp, exc, target, poses):
                    notes.append("the target's place is in view and empty: target dropped")
                    self.tracker.reset()
        if source != "none":
            self._empty_since = None
        if meas is None and other is not None:
            meas, other, source = other, None, "motion"  # another object, a candidate
            moving = True
        tracked = self.tracker.update(stamp, meas, moving,
                                      other if source == "region" else None)
        return StereoTargetResult(tracked, meas if source != "none" else None, source, pairs,
                                  "" if meas is not None else "; ".join(notes))

    def _region(self, rect: StereoRectification, left: np.ndarray, right: np.ndarray,
                target: TrackedObject, poses: CameraPoses, points_fn: PointsFn | None,
                self_segments: np.ndarray | None) -> tuple[ObjectEstimate, np.ndarray]:
        """Measure the followed object in its own image region: (the measurement, the left
        seed mask it was measured in).

        The object is still there without motion, but it may have moved since it was last
        measured without the segmenter seeing it move (a stop the prediction overshot, a small
        jump): the region measured within ``2 sigma`` (at least 1.5 cm) of the target is
        re-centred on what it found until it no longer moves (the gate cut the object's side
        that lies beyond it, so a measurement that moved is biased towards the old place);
        when nothing is found there, the object is looked for within ``track_gate`` of the
        target and re-centred the same way. What either search finds on the robot's own arm
        (within ``self_radius`` of ``self_segments``) is not the object.

        Raises:
            ObjectNotFound: no object there (reason ``self``: only the robot's arm).
        """
        c = self.config
        tight = max(0.015, 2.0 * self._sigma(target))

        def measure(top: np.ndarray, radius: float, height: float, margin: float
                    ) -> tuple[ObjectEstimate, np.ndarray]:
            seed = ObjectLocator.seed_from_object(top, radius, height, poses.T_root_left,
                                                  self.left, margin=max(0.01, margin - tight))
            gate = ObjectGate(top, radius, margin)
            return self.locator.locate(rect, left, right, seed, points_fn, gate), seed

        try:
            m, seed = measure(target.top, target.radius, target.height, tight)
        except ObjectNotFound:
            if c.track_gate <= tight:
                raise
            m, seed = measure(target.top, target.radius, target.height, c.track_gate)
        if self._is_self(m, self_segments):
            # also within the tight gate: a target held for long has a wide covariance, and
            # the robot's hand beside its place was taken for the object (bench trial, 0058)
            raise ObjectNotFound("self", "only the robot's own arm near the target")
        if np.linalg.norm(m.top - target.top) >= 0.5 * tight:
            for _ in range(_RECENTRE):
                try:
                    m2, seed2 = measure(m.top, m.radius, m.height, tight)
                except ObjectNotFound:
                    break
                if self._is_self(m2, self_segments):
                    break
                moved = float(np.linalg.norm(m2.top - m.top))
                m, seed = m2, seed2
                if moved < _RECENTRE_TOLERANCE:
                    break
        return m, seed

    def _place_is_empty(self, stamp: float, exc: ObjectNotFound, target: TrackedObject,
                        poses: CameraPoses) -> bool:
        """Whether the target's place has been seen empty for ``empty_hold_time``: both eyes
        see all of it (its top and bottom project inside both images) and the region
        measurement found nothing standing there (``no_object``: not the robot's own arm,
        which may hide the object, nor a measurement that failed for another reason). A
        target held that way would keep the gaze on an empty place for ``hold_time``
        (docs/decisions/0058)."""
        if exc.reason != "no_object" or not self._in_view(target, poses):
            self._empty_since = None
            return False
        if self._empty_since is None:
            self._empty_since = stamp
        if stamp - self._empty_since >= self.config.empty_hold_time:
            self._empty_since = None
            return True
        return False

    def _in_view(self, target: TrackedObject, poses: CameraPoses) -> bool:
        """Both eyes see the target's top and bottom centre inside their images."""
        bottom = target.top - np.array([0.0, 0.0, target.height])
        for T, cam in ((poses.T_root_left, self.left), (poses.T_root_right, self.right)):
            for p in (target.top, bottom):
                try:
                    u, v = project_point(T, p, cam)
                except InvalidInput:  # behind the camera
                    return False
                if not (0.0 <= u < cam.width and 0.0 <= v < cam.height):
                    return False
        return True

    def _is_self(self, m: ObjectEstimate, segments: np.ndarray | None) -> bool:
        if segments is None or len(segments) == 0:
            return False
        s = np.asarray(segments, float).reshape(-1, 2, 3)
        pts = np.stack([m.top, m.position])
        d = segment_distance(pts[:, None, :], pts[:, None, :], s[None, :, 0], s[None, :, 1])
        return bool(d.min() < self.config.self_radius)

    @staticmethod
    def _sigma(t: TrackedObject) -> float:
        return float(np.sqrt(max(np.linalg.eigvalsh(t.covariance)[-1], 0.0)))


def _blob_seed(blobs: MotionBlobs, index: int) -> np.ndarray:
    """The motion mask of one blob: the frame's mask inside the blob's bounding box."""
    h, w = blobs.mask.shape
    u0, v0, u1, v1 = blobs.blobs[index].bbox
    seed = np.zeros((h, w), bool)
    seed[max(v0, 0):min(v1 + 1, h), max(u0, 0):min(u1 + 1, w)] = True
    return seed & (blobs.mask > 0)
