"""``icub calibrate-eyes``: fit the eye cameras as built from the hand marker seen while babbling.

    icub babble --arm right --samples 80 --name eyecal      # the robot looks at its hand
    icub calibrate-eyes data/body_schema/eyecal.npz -o config/eye_calibration/my_robot.yaml
    # then: motion_segmenter's eye_calibration_file (config/motion_segmenter.yaml)

Fits each camera's focal length, principal point and mounting rotation against the marker
positions the arm's forward kinematics gives (:mod:`icub_pmp.vision.eye_calibration`), checks
the fit on a held-out third of the observations (reprojection error and the triangulated marker
against the kinematic one, nominal vs calibrated cameras), then refits on all and writes the
file. Uses only what the robot perceives (never a dataset's ground truth).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from icub_pmp.errors import InvalidInput

__all__ = ["register", "run", "heldout_figures"]


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``calibrate-eyes`` subcommand."""
    p = sub.add_parser("calibrate-eyes", help="fit the eye cameras' calibration to a babbling "
                       "dataset (the hand marker at known positions)",
                       description=__doc__.split("\n\n")[0],
                       epilog="example: icub calibrate-eyes data/body_schema/right.npz "
                              "-o config/eye_calibration/my_robot.yaml",
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("dataset", type=Path, help="a babbling dataset (.npz of `icub babble`)")
    p.add_argument("-o", "--output", type=Path, default=None,
                   help="calibration file to write (default: data/eye_calibration.yaml)")
    p.add_argument("--holdout", type=float, default=1.0 / 3.0,
                   help="fraction of the observations kept out of the check fit (default 1/3)")
    p.add_argument("--seed", type=int, default=0, help="seed of the held-out split")
    p.add_argument("--json", action="store_true", help="print the figures as one JSON line")
    p.set_defaults(func=run)


def heldout_figures(obs, fit, holdout: float, seed: int = 0) -> dict[str, float]:
    """Fit on the observations outside a random ``holdout`` fraction and measure on it: the
    reprojection RMS [px] and the median distance [mm] of the triangulated marker from its
    kinematic position, nominal and calibrated."""
    from icub_pmp.vision.eye_calibration import EyeCalibration, MarkerObservations
    from icub_pmp.vision.stereo_triangulator import StereoTriangulator

    if not 0.0 < holdout < 1.0:
        raise InvalidInput(f"--holdout: expected in (0, 1), got {holdout}")
    n = len(obs.points)
    order = np.random.default_rng(seed).permutation(n)
    k = int(round(n * holdout))
    test, train = order[:k], order[k:]
    if k < 3:
        raise InvalidInput(f"eye calibration: {n} observations leave {k} held out; babble more")

    def part(rows: np.ndarray) -> MarkerObservations:
        return MarkerObservations(obs.points[rows], obs.T_left[rows], obs.T_right[rows],
                                  obs.pixels[rows])

    calib = fit.fit(part(train))
    held = part(test)
    out: dict[str, float] = {"train": float(len(train)), "heldout": float(k)}
    for name, c in (("nominal", EyeCalibration.nominal(fit.nominal)), ("calibrated", calib)):
        out[f"{name}_reproj_px"] = fit.reprojection_rms(c, held)
        left, right = c.intrinsics(fit.nominal)
        tri = StereoTriangulator(left, right)
        errs = []
        for i in range(k):
            try:
                p = tri.triangulate(tuple(held.pixels[i, :2]), tuple(held.pixels[i, 2:]),
                                    c.left.pose(held.T_left[i]),
                                    c.right.pose(held.T_right[i])).position
            except InvalidInput:
                continue
            errs.append(float(np.linalg.norm(p - held.points[i])))
        out[f"{name}_triangulation_mm_median"] = float(np.median(errs) * 1000) if errs \
            else float("nan")
    return out


def run(args: argparse.Namespace) -> int:
    """Load, check on held-out observations, fit on all, write."""
    from icub_pmp.body_schema.babbling import load_dataset
    from icub_pmp.config import repo_root
    from icub_pmp.vision.eye_calibration import EyeCalibrator, observations_from_babbling

    data = load_dataset(args.dataset)
    obs = observations_from_babbling(data.learner, data.meta)
    fit = EyeCalibrator()
    figures = heldout_figures(obs, fit, args.holdout, args.seed)
    calib = fit.fit(obs, source=str(args.dataset))
    out = args.output or repo_root() / "data" / "eye_calibration.yaml"
    path = calib.save(out)
    figures.update(samples=float(calib.samples), rms_px=calib.rms_px,
                   nominal_rms_px=calib.nominal_rms_px)
    if args.json:
        print(json.dumps({"calibration": str(path), **figures}))
    else:
        print(f"{len(obs.points)} marker observations, {calib.samples} kept; reprojection "
              f"{calib.nominal_rms_px:.2f} px nominal -> {calib.rms_px:.2f} px calibrated")
        print(f"held-out check ({int(figures['heldout'])} observations): marker triangulated "
              f"{figures['nominal_triangulation_mm_median']:.1f} mm (nominal) -> "
              f"{figures['calibrated_triangulation_mm_median']:.1f} mm (calibrated) from its "
              "kinematic position")
        for side in ("left", "right"):
            c = calib.camera(side)
            print(f"  {side}: focal x{c.focal_scale:.4f}, principal ({c.cx:.1f}, {c.cy:.1f}) px,"
                  f" rotation {np.degrees(np.linalg.norm(c.rotation)):.2f} deg")
        print(f"written: {path}")
    return 0
