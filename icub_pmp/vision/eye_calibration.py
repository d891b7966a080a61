"""EyeCalibration: each eye camera's real intrinsics and mounting, fitted from the hand marker.

The nominal camera model (``camera_info``, :class:`~icub_pmp.kinematics.eye_kinematics.
CameraIntrinsics` and the iKin eye chain of :class:`~icub_pmp.vision.head_cameras.HeadCameras`)
is what the robot was designed as; a built robot's cameras differ from it by a few pixels of
principal point, a few per cent of focal length and about a degree of mounting rotation. That is
enough to break stereo: a 0.9 deg rotation of one camera about its x axis puts the two images of
a point about 5 px apart in the rows that rectified stereo matching compares (decision 0038).

A real iCub's eyes are calibrated (icub-main's ``stereoCalib`` module, with a chessboard; the
result goes to the robot's ``icubEyes.ini``). We calibrate with the robot's own hand instead of
a chessboard: the robot looks at the marker on its hand at postures whose marker position it
knows from its arm's forward kinematics (the kinematics is the part of the model a robot can
trust to a millimetre), records the marker's pixels in both images, and fits per camera

    u = f s x_c / z_c + c_x,  v = f s y_c / z_c + c_y,  p_c = R(r)^T T_nom^-1 p_root,

with ``s`` the focal-length scale, ``(c_x, c_y)`` the principal point and ``r`` a rotation
vector of the camera against its nominal optical frame (``T_true = T_nom R(r)``), by robust
non-linear least squares on the reprojection error (``scipy.optimize.least_squares``, soft-L1
loss, so a few wrong marker detections do not pull the fit). A small rotation about the
camera's x or y axis and a principal-point shift move the image almost alike; a weak prior
(``rotation_prior_deg``) keeps the fit well posed, and either way the fitted projection is what
triangulation needs. Everything is in the REP-103 optical frame (x right, y down, z forward).

The calibration is a robot's configuration (as the iCub's ``icubEyes.ini`` in
robots-configuration): ``save``/``load`` a small YAML file that the motion segmenter reads
(``eye_calibration_file``).
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from icub_pmp.errors import InvalidInput, ModelError
from icub_pmp.kinematics.eye_kinematics import CameraIntrinsics
from icub_pmp.vision.head_cameras import CameraPoses

__all__ = ["CameraCorrection", "EyeCalibration", "EyeCalibrator", "rotation_matrix",
           "MarkerObservations"]

SIDES = ("left", "right")


def rotation_matrix(rvec: Sequence[float]) -> np.ndarray:
    """The rotation (3, 3) of the rotation vector ``rvec`` (3,) [rad] (Rodrigues)."""
    r = np.asarray(rvec, dtype=float).reshape(3)
    theta = float(np.linalg.norm(r))
    if theta < 1e-12:
        return np.eye(3)
    k = r / theta
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + math.sin(theta) * K + (1.0 - math.cos(theta)) * (K @ K)


@dataclasses.dataclass(frozen=True)
class CameraCorrection:
    """One camera as built, relative to its nominal model.

    Attributes:
        focal_scale: the real focal length over the nominal one [-].
        cx, cy: the real principal point [px].
        rotation: rotation vector of the real optical frame in the nominal one [rad] (3,).
    """

    focal_scale: float = 1.0
    cx: float = 160.0
    cy: float = 120.0
    rotation: tuple[float, float, float] = (0.0, 0.0, 0.0)

    @classmethod
    def nominal(cls, intrinsics: CameraIntrinsics) -> CameraCorrection:
        """No correction: the nominal camera."""
        return cls(1.0, intrinsics.cx, intrinsics.cy, (0.0, 0.0, 0.0))

    def intrinsics(self, nominal: CameraIntrinsics) -> CameraIntrinsics:
        """The calibrated intrinsics of a camera whose nominal ones are ``nominal``."""
        return CameraIntrinsics(nominal.width, nominal.height, nominal.fx * self.focal_scale,
                                nominal.fy * self.focal_scale, self.cx, self.cy)

    def pose(self, T_root_nominal: np.ndarray) -> np.ndarray:
        """The calibrated optical frame (4, 4) in root_link given the nominal one (or
        (n, 4, 4) given n of them)."""
        T = np.array(T_root_nominal, dtype=float, copy=True)
        T[..., :3, :3] = T[..., :3, :3] @ rotation_matrix(self.rotation)
        return T

    def project(self, T_root_nominal: np.ndarray, points: np.ndarray,
                nominal: CameraIntrinsics) -> np.ndarray:
        """Pixels (n, 2) of ``points`` (n, 3) [m, root_link] through this camera at the
        nominal frames ``T_root_nominal`` (n, 4, 4) (or one (4, 4) for all); NaN for a point
        behind it."""
        T = self.pose(T_root_nominal)
        p = np.asarray(points, dtype=float).reshape(-1, 3)
        if T.ndim == 2:
            T = np.broadcast_to(T, (len(p), 4, 4))
        pc = np.einsum("nji,nj->ni", T[:, :3, :3], p - T[:, :3, 3])
        z = np.where(pc[:, 2] > 1e-6, pc[:, 2], np.nan)
        f = self.focal_scale
        return np.stack([nominal.fx * f * pc[:, 0] / z + self.cx,
                         nominal.fy * f * pc[:, 1] / z + self.cy], axis=1)


@dataclasses.dataclass(frozen=True)
class EyeCalibration:
    """Both eyes' corrections and how well they fit.

    Attributes:
        left, right: the cameras' corrections.
        samples: marker observations used (after outliers).
        rms_px: reprojection error RMS of those [px] (both cameras, both axes).
        nominal_rms_px: the same observations' error through the nominal model [px].
        source: where the observations came from (a dataset path, a note).
    """

    left: CameraCorrection
    right: CameraCorrection
    samples: int = 0
    rms_px: float = 0.0
    nominal_rms_px: float = 0.0
    source: str = ""

    @classmethod
    def nominal(cls, left: CameraIntrinsics | None = None,
                right: CameraIntrinsics | None = None) -> EyeCalibration:
        """The identity calibration (the nominal cameras)."""
        left = left or CameraIntrinsics()
        return cls(CameraCorrection.nominal(left), CameraCorrection.nominal(right or left),
                   source="nominal")

    def camera(self, side: str) -> CameraCorrection:
        """The correction of ``side`` ('left' | 'right')."""
        if side not in SIDES:
            raise InvalidInput(f"side: expected one of {SIDES}, got {side!r}")
        return self.left if side == "left" else self.right

    def intrinsics(self, nominal_left: CameraIntrinsics,
                   nominal_right: CameraIntrinsics | None = None
                   ) -> tuple[CameraIntrinsics, CameraIntrinsics]:
        """The calibrated intrinsics of both eyes."""
        return (self.left.intrinsics(nominal_left),
                self.right.intrinsics(nominal_right or nominal_left))

    def poses(self, nominal: CameraPoses) -> CameraPoses:
        """The calibrated camera poses of nominal ones (e.g. from :class:`HeadCameras`)."""
        return CameraPoses(self.left.pose(nominal.T_root_left),
                           self.right.pose(nominal.T_root_right))

    # ------------------------------------------------------------------ file
    def to_dict(self) -> dict[str, Any]:
        """Plain data (what :meth:`save` writes)."""
        out: dict[str, Any] = {"format": "icub_pmp eye calibration 1", "samples": self.samples,
                               "rms_px": round(self.rms_px, 4),
                               "nominal_rms_px": round(self.nominal_rms_px, 4),
                               "source": self.source}
        for side in SIDES:
            c = self.camera(side)
            out[side] = {"focal_scale": float(c.focal_scale), "cx": float(c.cx),
                         "cy": float(c.cy), "rotation_rad": [float(v) for v in c.rotation]}
        return out

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], what: str = "eye calibration") -> EyeCalibration:
        """The calibration of :meth:`to_dict`'s data (:class:`ModelError` naming what is wrong)."""
        if not isinstance(data, Mapping) or data.get("format") != "icub_pmp eye calibration 1":
            raise ModelError(f"{what}: not an icub_pmp eye calibration (no "
                             "'format: icub_pmp eye calibration 1')")
        cams = []
        for side in SIDES:
            d = data.get(side)
            try:
                rot = tuple(float(v) for v in d["rotation_rad"])
                c = CameraCorrection(float(d["focal_scale"]), float(d["cx"]), float(d["cy"]),
                                     rot)  # type: ignore[arg-type]
            except (TypeError, KeyError, ValueError) as exc:
                raise ModelError(f"{what}: camera {side!r}: expected focal_scale, cx, cy and "
                                 f"rotation_rad (3 values): {exc}") from None
            vals = np.array([c.focal_scale, c.cx, c.cy, *c.rotation])
            if len(c.rotation) != 3 or not np.all(np.isfinite(vals)) or not (
                    0.5 < c.focal_scale < 2.0) or np.linalg.norm(c.rotation) > math.radians(20):
                raise ModelError(f"{what}: camera {side!r}: implausible values {vals.tolist()} "
                                 "(focal_scale in (0.5, 2), rotation < 20 deg)")
            cams.append(c)
        return cls(cams[0], cams[1], int(data.get("samples", 0)), float(data.get("rms_px", 0.0)),
                   float(data.get("nominal_rms_px", 0.0)), str(data.get("source", "")))

    def save(self, path: str | Path) -> Path:
        """Write the calibration as YAML; returns the path."""
        import yaml

        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text("# eye calibration (icub_pmp.vision.eye_calibration): the cameras as "
                        "built\n" + yaml.safe_dump(self.to_dict(), sort_keys=False))
        return path

    @classmethod
    def load(cls, path: str | Path) -> EyeCalibration:
        """Read a file of :meth:`save` (:class:`ModelError` if missing or malformed)."""
        import yaml

        path = Path(path)
        if not path.is_file():
            raise ModelError(f"eye calibration {str(path)!r}: no such file")
        try:
            data = yaml.safe_load(path.read_text())
        except yaml.YAMLError as exc:
            raise ModelError(f"eye calibration {str(path)!r}: not YAML: {exc}") from None
        return cls.from_dict(data, f"eye calibration {str(path)!r}")


@dataclasses.dataclass(frozen=True)
class MarkerObservations:
    """What the calibration fits: marker positions and where each eye saw them.

    Attributes:
        points: (n, 3) the marker in root_link from the arm's forward kinematics [m].
        T_left, T_right: (n, 4, 4) the nominal optical frames at each observation.
        pixels: (n, 4) u_l, v_l, u_r, v_r [px].
    """

    points: np.ndarray
    T_left: np.ndarray
    T_right: np.ndarray
    pixels: np.ndarray

    def __post_init__(self) -> None:
        n = len(self.points)
        shapes = {"points": (n, 3), "T_left": (n, 4, 4), "T_right": (n, 4, 4),
                  "pixels": (n, 4)}
        for name, shape in shapes.items():
            v = np.asarray(getattr(self, name), dtype=float)
            if v.shape != shape:
                raise InvalidInput(f"marker observations {name}: expected shape {shape}, got "
                                   f"{v.shape}")
        keep = np.all(np.isfinite(self.pixels), axis=1) & np.all(np.isfinite(self.points), axis=1)
        if not np.all(keep):
            raise InvalidInput(f"marker observations: {int(np.sum(~keep))} rows are not finite")


@dataclasses.dataclass(frozen=True)
class EyeCalibrator:
    """Fit an :class:`EyeCalibration` to marker observations (module doc).

    Attributes:
        nominal: the nominal intrinsics (both eyes).
        rotation_prior_deg: the prior's scale on the mounting rotation [deg] (weak).
        pixel_sigma_px: the marker detection's expected error [px] (the loss's scale).
        min_samples: fewer observations than this are refused.
        outlier_px: observations still off by more than this after a first fit are dropped.
    """

    nominal: CameraIntrinsics = dataclasses.field(default_factory=CameraIntrinsics)
    rotation_prior_deg: float = 3.0
    pixel_sigma_px: float = 1.0
    min_samples: int = 8
    outlier_px: float = 8.0

    def fit(self, obs: MarkerObservations, source: str = "") -> EyeCalibration:
        """Both cameras, each on its own pixels; raises :class:`InvalidInput` with too few
        observations."""
        n = len(obs.points)
        if n < self.min_samples:
            raise InvalidInput(f"eye calibration: {n} marker observations, at least "
                               f"{self.min_samples} needed (more postures of the hand in view)")
        cams, keep_all = [], np.ones(n, dtype=bool)
        for k, (side, T) in enumerate((("left", obs.T_left), ("right", obs.T_right))):
            px = np.asarray(obs.pixels, dtype=float)[:, 2 * k:2 * k + 2]
            cam = self._fit_one(np.asarray(T, float), np.asarray(obs.points, float), px,
                                np.ones(n, dtype=bool))
            err = np.nan_to_num(np.linalg.norm(cam.project(T, obs.points, self.nominal) - px,
                                               axis=1), nan=np.inf)
            # occluded or wrong detections: far off the first fit (a fixed bound, tightened
            # to 4 x the median error when the fit is good)
            keep = err <= min(self.outlier_px, max(4.0 * float(np.median(err)),
                                                   2.0 * self.pixel_sigma_px))
            if np.sum(keep) < self.min_samples:
                raise InvalidInput(f"eye calibration: only {int(np.sum(keep))} of {n} {side} "
                                   f"observations fit within {self.outlier_px} px")
            cams.append(self._fit_one(np.asarray(T, float), np.asarray(obs.points, float), px,
                                      keep, start=cam))
            keep_all &= keep
        calib = EyeCalibration(cams[0], cams[1], int(np.sum(keep_all)), source=source)
        return dataclasses.replace(
            calib, rms_px=self.reprojection_rms(calib, obs, keep_all),
            nominal_rms_px=self.reprojection_rms(EyeCalibration.nominal(self.nominal), obs,
                                                 keep_all))

    def reprojection_rms(self, calib: EyeCalibration, obs: MarkerObservations,
                         rows: np.ndarray | None = None) -> float:
        """RMS reprojection error [px] of ``calib`` on ``obs`` (both eyes, both axes)."""
        rows = np.ones(len(obs.points), dtype=bool) if rows is None else rows
        res = []
        for k, T in enumerate((obs.T_left, obs.T_right)):
            cam = calib.left if k == 0 else calib.right
            pred = cam.project(np.asarray(T, float)[rows], np.asarray(obs.points, float)[rows],
                               self.nominal)
            res.append(pred - np.asarray(obs.pixels, float)[rows, 2 * k:2 * k + 2])
        r = np.concatenate(res)
        return float(np.sqrt(np.nanmean(r ** 2)))

    def _fit_one(self, T: np.ndarray, points: np.ndarray, pixels: np.ndarray,
                 rows: np.ndarray, start: CameraCorrection | None = None) -> CameraCorrection:
        from scipy.optimize import least_squares

        T, points, pixels = T[rows], points[rows], pixels[rows]
        # the points in each nominal optical frame, once
        pn = np.einsum("nji,nj->ni", T[:, :3, :3], points - T[:, :3, 3])
        if np.any(pn[:, 2] <= 1e-3):
            raise InvalidInput("eye calibration: a marker observation lies behind its camera's "
                               "nominal frame (wrong joints or pixels?)")
        f = np.array([self.nominal.fx, self.nominal.fy])
        prior = math.radians(self.rotation_prior_deg)
        s0 = start or CameraCorrection.nominal(self.nominal)
        x0 = np.array([math.log(s0.focal_scale), s0.cx, s0.cy, *s0.rotation])

        def residuals(x: np.ndarray) -> np.ndarray:
            pc = pn @ rotation_matrix(x[3:6])
            z = np.maximum(pc[:, 2], 1e-3)
            uv = np.exp(x[0]) * f * pc[:, :2] / z[:, None] + x[1:3]
            r = (uv - pixels).ravel() / self.pixel_sigma_px
            return np.concatenate([r, x[3:6] / prior])

        sol = least_squares(residuals, x0, loss="soft_l1", f_scale=2.0, x_scale=[
            0.01, 1.0, 1.0, 0.01, 0.01, 0.01], max_nfev=200)
        x = sol.x
        return CameraCorrection(float(np.exp(x[0])), float(x[1]), float(x[2]),
                                (float(x[3]), float(x[4]), float(x[5])))


def observations_from_babbling(learner: Mapping[str, np.ndarray], meta: Mapping[str, Any],
                               cameras: Any = None) -> MarkerObservations:
    """Marker observations of a babbling dataset (:func:`icub_pmp.body_schema.load_dataset`'s
    ``learner`` arrays and ``meta``): the marker from the measured arm joints' forward
    kinematics and the dataset's ``marker_offset`` in its ``hand_frame``, the nominal camera
    frames from the recorded head joints; joints neither babbled nor recorded take the
    dataset's ``fixed`` values (torso). Uses only what the robot perceives (never the ground
    truth). ``cameras``: a :class:`HeadCameras` (default: a new one)."""
    from icub_pmp.vision.head_cameras import HeadCameras

    try:
        joint_names = list(meta["joint_names"])
        head_names = list(meta["head_joints"])
        frame = str(meta["hand_frame"])
        offset = np.asarray(meta["marker_offset"], dtype=float).reshape(3)
    except (KeyError, TypeError, ValueError) as exc:
        raise InvalidInput(f"babbling dataset metadata: missing {exc} (a dataset of the "
                           "body_schema node is needed)") from None
    q = np.asarray(learner["q"], dtype=float)
    head = np.asarray(learner["head"], dtype=float)
    pixels = np.asarray(learner["pixels"], dtype=float)
    if len(q) == 0:
        raise InvalidInput("babbling dataset: no samples")
    cams = cameras or HeadCameras()
    model = cams.model
    fixed = {j: float(v) for j, v in dict(meta.get("fixed", {})).items()}
    points, T_l, T_r = [], [], []
    for qi, hi in zip(q, head):
        joints = dict(fixed)
        joints.update(zip(joint_names, map(float, qi)))
        joints.update(zip(head_names, map(float, hi)))
        qm = model.q_from_dict(joints)  # names outside the model (eyes) are ignored
        pose = model.frame_pose(qm, frame)
        points.append(pose.translation + pose.rotation @ offset)
        poses = cams.poses(joints)
        T_l.append(poses.T_root_left)
        T_r.append(poses.T_root_right)
    return MarkerObservations(np.array(points), np.array(T_l), np.array(T_r), pixels)
