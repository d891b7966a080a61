"""Benchmark of the learned body schema (body network + PMP on its Jacobian) and of the learned
eye-hand map against geometric triangulation.

    scripts/env.sh python bench/body_schema.py --quick          # < 2 min, pinocchio FK babbles
    scripts/env.sh python bench/body_schema.py                  # 10k babbles, curves
    scripts/env.sh python bench/body_schema.py --dataset data/body_schema/babble_right_X.npz
                                                                # + rates of a ROS babbling run
    scripts/env.sh python bench/body_schema.py --quick --plot   # + PNGs in bench/out/
    scripts/env.sh python bench/body_schema.py --quick --save-models data/body_schema
                                                                # + the learned models (.npz)
    scripts/env.sh python bench/body_schema.py --eye-hand-only --rendered --quick \
        --save-models data/body_schema      # the eye-hand map from the icub cameras' renders

Data: babbles of the right arm (7 joints uniform within the URDF limits, torso and left arm at
rest) with the hand (``r_hand_dh_frame``) from pinocchio forward kinematics, held-out test set
from another seed. A ROS babbling dataset (``icub babble``) given with ``--dataset`` adds its
measured rates (``babble_samples_per_s`` per wall second, ``_sim`` per simulated second),
``visible_fraction`` and the triangulation error of its samples; without one these keys are
null (the quick run does not start the graph).

- Body network (eqs 1-2 of the body-schema paper): trained by Levenberg-Marquardt on the normal
  equations (``lm-normal``: J^T J accumulated over batches of 3,000 random babbles per
  iteration, Cholesky, Marquardt's adaptive damping, 10 % validation split; decision 0042)
  within a budget of CPU time (30 s quick, 60 s full; ``body_train_s`` is the wall time, which
  the machine's load inflates); ``body_rmse_mm`` on the held-out set; the previous trainer
  (scipy ``least_squares`` trf + LSMR, decision 0040) on the same data with the same budget
  gives ``body_rmse_mm_trf_lsmr``; ``--curve`` adds the error vs babbles (1k-30k) and vs hidden
  sizes (``CURVE``), each within the same budget; ``jacobian_err_rel`` median of ||J_learned -
  J_pinocchio||_F / ||J_pinocchio||_F at held-out postures.
- PMP: the same reachable targets (FK of held-out postures) planned from rest with the learned
  provider and with the analytic one (right arm, no torso); the error is the URDF hand at the
  planned final posture vs the target; success = within 5 mm.
- Eye-hand map (force paper eq 12): 7-50-3 learned from gaze samples of babbled hands (both
  arms with the trunk, uniform within the limits, half of them directed over the table region
  ``TABLE_REGION``; the gaze controller follows each hand with the neck and the eyes, lagging
  up to ``GAZE_LAG`` behind it, so the hand is seen anywhere around the image centre), plus
  half as many samples of the eyes alone fixating other babbles with the head at rest (as when
  the gaze controller keeps its neck); the cameras of the simulator's eye kinematics, 0.3 px
  pixel noise (decision 0070). Trained and tested on the cameras as they are; triangulation
  assumes the nominal cameras. Nominal: the real cameras are nominal. Perturbed: principal
  points shifted
  (+3, -2) px and (-2, +3) px, left camera rotated 1 deg about its y axis. Errors in the
  head-centred frame (``head``) on held-out data: ``eyehand_err_mm_mean``/``_std``/
  ``_rmse_mm_perturbed`` on right-hand babbles fixated with the head at rest (the protocol of
  the earlier figures), ``eyehand_rmse_mm_gaze`` on other babbles with the same gaze,
  ``eyehand_err_mm_table_*`` on points of the table region of bench/vision_reach.py seen with
  the gaze on the table near them (where the map is used to reach the seen object).
- Adaptation (tool): the marker moves 12 cm along the hand frame's x axis; babbling goes on
  and the model learns online: after each batch of new babbles (``ADAPT_POOL``: 400 ... 25,600,
  ``--quick`` 200 ... 3,200) training continues from the current model (``lm-normal``, warm
  start) on all the tool babbles so far, within ``ADAPT_BUDGET`` s of CPU per batch (90 s, 10 s
  ``--quick``; the small batches stop on validation long before; ``adapt_cpu_s`` the total);
  ``adapt_samples`` is the fewest new babbles that bring the held-out error back within the
  error goal (``adapt_goal_mm``: 2 mm, or 1.25x the model's own error when that is above
  1.6 mm; decision 0054).
- Rendered (``--eye-hand-only --rendered``, decision 0071): the map learned from what the
  eyes of the simulator's ``--realism`` cameras (default ``icub``: focal, principal point and
  mounting off camera_info's) see of a marker, the table taken away while babbling: half the
  samples of the hand marker (the babbles above, down to 4 cm below the table top, plus half
  as many over the table's far half ``FAR_TABLE_REGION``), half of a marker on a held 30 cm
  stick (``TOOL_MARKER``, over ``TOOL_REGION``: the far table is farther from the eyes than the
  hand reaches); the gaze following the marker, both eyes rendered and the marker detected
  (``rendered_gaze_samples``), eye angles and the marker's position from the encoders and the
  nominal forward kinematics. Held out: ``eyehand_table_*`` (the hand marker over the table)
  and ``eyehand_far_*`` (the stick over the far table): median, p95, far half x <= ``FAR_X``,
  bias [mm] against the marker's true position, beside triangulation (calibrated and
  nominal), the 0070 map (nominal cameras, projected pixels) and a map from the same babbles'
  projected pixels; ``renders_per_s``, ``render_samples_per_s``.
Ends with one JSON line. Paper figures are printed beside ours.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import sys
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from icub_pmp.body_schema import (  # noqa: E402
    DEFAULT_HIDDEN,
    BodyNetwork,
    EyeHandMap,
    LearnedJacobianProvider,
    LmTrainer,
    LmTrainerConfig,
    StereoSamples,
    babbled_hands,
    gaze_samples,
    load_dataset,
    perturbed_cameras,
    stereo_samples,
)
from icub_pmp.gaze.gaze_controller import GazeController  # noqa: E402
from icub_pmp.kinematics import RobotSpec  # noqa: E402
from icub_pmp.kinematics.eye_kinematics import CameraIntrinsics, EyeKinematics  # noqa: E402
from icub_pmp.peripersonal import analytic_babbling  # noqa: E402
from icub_pmp.pmp import PmpConfig, PmpPlanner, ReachGoal  # noqa: E402
from icub_pmp.pmp.pinocchio_provider import PinocchioJacobianProvider  # noqa: E402
from icub_pmp.vision.stereo_triangulator import StereoTriangulator  # noqa: E402

OUT = Path(__file__).resolve().parent / "out"
SUCCESS = 5e-3  # [m]
METHOD = "lm-normal"  # the body network's trainer (decision 0042)
GOAL_MM = 2.0  # the goal for body_rmse_mm
CURVATURE_SAMPLES = 3000  # lm-normal builds J^T J from this many random babbles per iteration
#: the training curve: (babbles, hidden sizes), each trained within the same CPU budget
CURVE = ((1000, (32, 41)), (3000, (32, 41)), (10000, (32, 41)), (30000, (32, 41)),
         (10000, (16, 16)), (10000, (24, 24)), (10000, (48, 48)))
#: new babbles with the tool after which the model has learned online (full, --quick), and the CPU
#: budget [s] of each of those training runs
ADAPT_POOL = (400, 800, 1600, 3200, 6400, 12800, 25600)
ADAPT_POOL_QUICK = (200, 400, 800, 1600, 3200)
ADAPT_BUDGET, ADAPT_BUDGET_QUICK = 90.0, 10.0
#: the eye-hand map's gaze samples (train, test) and LM evaluations with --quick (decision 0070)
EH_QUICK = (2000, 300)
EH_EVALS_QUICK = 300
#: the gaze lags the babbling hand by up to this [m] (the hand seen around the image centre)
GAZE_LAG = 0.2
#: samples of the eyes alone following the hand (head at rest), per gaze sample
EYES_ONLY_FRACTION = 0.5
#: the table region of bench/vision_reach.py's cylinder (x, y, z lower, upper) [m, root_link]:
#: the cylinder's placements with 4 cm around, from the table top (-0.09) to its top (+0.03);
#: half the babbles are directed there (the hand over the table where the robot acts)
TABLE_REGION = ((-0.50, -0.22, -0.09), (-0.26, 0.18, 0.03))
#: the map learned from rendered views of the hand (--rendered, decision 0071): gaze samples
#: to learn from and held-out ones (full, --quick)
EH_RENDERED, EH_RENDERED_QUICK = (5000, 600), (1000, 300)
#: the babbles of the rendered map over the table: TABLE_REGION down to 4 cm below the table
#: top (the table is taken away while the robot babbles, so the table's own points are inside
#: what the map learned, not at its edge) [m, root_link]
RENDER_TABLE_REGION = ((-0.50, -0.22, -0.13), (-0.26, 0.18, 0.03))
#: its far half, from the far placements of bench/vision_reach.py (x -0.46 m) with 4 cm: half as
#: many babbles again directed there (the 0070 map was 8-18 mm too high there)
FAR_TABLE_REGION = ((-0.50, -0.22, -0.13), (-0.38, 0.18, 0.03))
FAR_X = -0.40  # [m] the held-out points beyond this are the figures' far half
#: the marker on a stick the robot holds (30 cm along the hand frame's x axis from the hand
#: marker): the hand's own marker is never more than 0.52 m from the head, while the table at
#: x -0.46 is 0.55 m from the head at rest and 0.63 m with the trunk leaning back as in
#: bench/vision_reach.py (-20 deg), its far edge 0.77 m; the robot knows the stick's length
#: (its body schema)
TOOL_MARKER = (0.28, -0.02, 0.04)
#: where the stick's marker babbles over the table (3/4 of its babbles) [m, root_link]
TOOL_REGION = ((-0.70, -0.25, -0.13), (-0.36, 0.20, 0.03))
#: the held-out far table for the stick's marker: beyond the hand's reach from the eyes
FAR_TEST_REGION = ((-0.56, -0.22, -0.09), (-0.40, 0.18, 0.03))
#: the eye calibration of each realism preset (decision 0057), for triangulation beside the map
EYE_CALIBRATION = {"icub": "config/eye_calibration/icub_seed0.yaml"}
PAPER = {"body_rmse_mm": "0.04 (6-DoF industrial arm, seed 002)",
         "eyehand_err_mm_mean": "0.31 (x, y; force paper Sect. 4)",
         "eyehand_err_mm_std": "5.5 x/y, about 11 z"}


def trainer_config(method: str, budget: float, **kw) -> LmTrainerConfig:
    """The bench's trainer: ``method`` within ``budget`` [s] of this process's CPU time (the
    shared machine's load does not shrink it; single-threaded BLAS, so it is the wall time of
    an idle machine); ``lm-normal`` with float32 curvature from ``CURVATURE_SAMPLES`` random
    babbles per iteration (subsampled Gauss-Newton) and a 10 % validation split."""
    extra = ({"curvature_dtype": "float32", "curvature_samples": CURVATURE_SAMPLES}
             if method == "lm-normal" else {})
    return LmTrainerConfig(method=method, max_evaluations=100000, time_budget=budget,
                           budget_clock="cpu", **{**extra, **kw})


def tool_hand(provider, q_arm, idx, frame, offset) -> np.ndarray:
    """Marker positions (n, 3): the hand frame's origin + R @ offset at each arm posture."""
    q = provider.icub.posture("rest")
    out = np.empty((len(q_arm), 3))
    for k, qa in enumerate(q_arm):
        q[idx] = qa
        kin = provider.kinematics(q, [frame])
        out[k] = kin.positions[0] + kin.rotations[0] @ offset
    return out


def jacobian_error(net, provider, q_arm, idx) -> float:
    """Median relative Frobenius error of the learned Jacobian vs pinocchio's."""
    q = provider.icub.posture("rest")
    pred = net.jacobian(q_arm)
    rel = []
    for k, qa in enumerate(q_arm):
        q[idx] = qa
        j = provider.kinematics(q, [net.frame]).jacobians[0, :3][:, idx]
        rel.append(np.linalg.norm(pred.jacobians[k] - j) / np.linalg.norm(j))
    return float(np.median(rel))


def pmp_errors(planner: PmpPlanner, truth, targets, frame) -> np.ndarray:
    """True hand errors [m] of PMP plans (right arm, from rest) toward ``targets``."""
    rest = planner.start_configuration(None)
    names = planner.provider.joint_names
    out = []
    for t in targets:
        plan = planner.plan(ReachGoal(targets={"right": t}, use_torso=False), rest)
        q = truth.icub.q_from_dict(dict(zip(names, plan.q_final)))
        out.append(np.linalg.norm(truth.positions(q, [frame])[0] - t))
    return np.array(out)


def _errors_mm(m: EyeHandMap, s, tri: StereoTriangulator) -> tuple[np.ndarray, np.ndarray]:
    """Errors (n, 3) [mm] in each sample's head frame of the map and of triangulation."""
    truth = s.hands_in_head()
    tri_p = np.array([tri.triangulate(tuple(x[:2]), tuple(x[2:4]), T[0], T[1]).position
                      for x, T in zip(s.inputs, s.poses)])
    tri_s = s._replace(hands=tri_p)
    return (m.locate(s.inputs) - truth) * 1e3, (tri_s.hands_in_head() - truth) * 1e3


def table_points(n: int, seed: int) -> np.ndarray:
    """``n`` points (n, 3) [m] uniform over the table region where bench/vision_reach.py moves
    the cylinder (with a margin), from the table top to the cylinder's top."""
    rng = np.random.default_rng(seed)
    return rng.uniform(TABLE_REGION[0], TABLE_REGION[1], size=(n, 3))


def camera_setup(cam: CameraIntrinsics) -> dict[str, float]:
    """The camera setup a map names (what the segmenter checks when it loads it)."""
    return {"width": cam.width, "height": cam.height, "fx": cam.fx, "fy": cam.fy}


def projected_eye_hand_map(n_train: int, evals: int, provider: PinocchioJacobianProvider,
                           cams, rot: np.ndarray) -> EyeHandMap:
    """The eye-hand map of decision 0070: learned from ``n_train`` gaze samples of babbled
    hands (both arms and the trunk, half over ``TABLE_REGION``) projected into the cameras
    ``cams`` (left rotation ``rot``), plus ``EYES_ONLY_FRACTION`` as many of the eyes alone
    fixating other babbles with the head at rest; ``evals`` LM evaluations at most."""
    model = provider.icub
    eyes = EyeKinematics.from_model(model)
    gaze = GazeController(model=model)
    rest = RobotSpec.load().posture("rest")
    hands, postures = babbled_hands(n_train, 300, provider, region=TABLE_REGION)
    moving = gaze_samples(n_train, 1, eyes, gaze, hands, postures, cams, rot, 0.3, GAZE_LAG)
    # and the eyes alone following the hand, the head still (the gaze controller keeps the
    # neck while the target stays within its activation angle): other babbles, head at rest
    T_root_head = model.frame_pose(model.posture("rest"), "head").homogeneous
    q_head, _ = gaze.configuration(rest)
    n_fix = int(round(EYES_ONLY_FRACTION * n_train))
    still = stereo_samples(n_fix, 4, eyes, T_root_head, babbled_hands(
        n_fix, 301, provider, trunk=False)[0], cams, rot, 0.3, gaze, q_head)
    train = StereoSamples(*(np.concatenate(f) for f in zip(moving, still)))
    m, _ = EyeHandMap.train(train.inputs, train.hands_in_head(), "head",
                            trainer=LmTrainer(LmTrainerConfig(max_evaluations=evals)),
                            camera=camera_setup(CameraIntrinsics()))
    return m


def eye_hand_vs_triangulation(n_train: int, n_test: int, perturbed: bool, evals: int,
                              provider: PinocchioJacobianProvider, fixation_hands: np.ndarray,
                              save: str = "") -> dict:
    """The eye-hand map learned from ``n_train`` gaze samples of babbled hands (both arms and
    the trunk, the gaze following each hand, :func:`gaze_samples`) and its errors [mm] vs
    triangulation's, in the head frame, on held-out samples: ``gaze`` (other babbles, the same
    gaze), ``fixation`` (the hands ``fixation_hands`` fixated with the head at rest, the
    protocol of the earlier figures) and ``table`` (points on the table seen with the gaze on
    the table near them); ``save``: write the map there (.npz)."""
    model = provider.icub
    eyes = EyeKinematics.from_model(model)
    nominal = CameraIntrinsics()
    if perturbed:
        cams, rot = perturbed_cameras()
    else:
        cams, rot = {"left": nominal, "right": nominal}, np.eye(3)
    gaze = GazeController(model=model)
    rest = RobotSpec.load().posture("rest")
    T_root_head = model.frame_pose(model.posture("rest"), "head").homogeneous
    q_head, _ = gaze.configuration(rest)
    m = projected_eye_hand_map(n_train, evals, provider, cams, rot)
    if save:
        m.save(save)
    h_test, p_test = babbled_hands(n_test, 400, provider, region=TABLE_REGION)
    table = table_points(n_test, 500)
    tests = {
        "gaze": gaze_samples(n_test, 2, eyes, gaze, h_test, p_test, cams, rot, 0.3, GAZE_LAG),
        "fixation": stereo_samples(len(fixation_hands), 2, eyes, T_root_head, fixation_hands,
                                   cams, rot, 0.3, gaze, q_head),
        "table": gaze_samples(n_test, 3, eyes, gaze, table, [rest] * len(table), cams, rot,
                              0.3, GAZE_LAG)}
    tri = StereoTriangulator(nominal, nominal)
    out: dict = {}
    for name, s in tests.items():
        err_map, err_tri = _errors_mm(m, s, tri)
        norm_map, norm_tri = np.linalg.norm(err_map, axis=1), np.linalg.norm(err_tri, axis=1)
        out[name] = {"eyehand_mean": np.abs(err_map.mean(axis=0)).round(2).tolist(),
                     "eyehand_std": err_map.std(axis=0).round(2).tolist(),
                     "eyehand_rmse": float(np.sqrt(np.mean(norm_map ** 2))),
                     "eyehand_median": float(np.median(norm_map)),
                     "eyehand_p95": float(np.percentile(norm_map, 95)),
                     "tri_mean": np.abs(err_tri.mean(axis=0)).round(2).tolist(),
                     "tri_std": err_tri.std(axis=0).round(2).tolist(),
                     "tri_rmse": float(np.sqrt(np.mean(norm_tri ** 2))),
                     "tri_median": float(np.median(norm_tri))}
    return out


def rendered_babbles(n: int, seed: int, provider: PinocchioJacobianProvider,
                     arms: tuple[str, ...] = ("right", "left")
                     ) -> tuple[list[dict[str, float]], list[str]]:
    """Babbled postures to render and each one's babbling arm: ``n`` babbles of both arms and
    the trunk, half over ``RENDER_TABLE_REGION`` (decision 0070), and ``n // 2`` more over
    ``FAR_TABLE_REGION``."""
    _, near = babbled_hands(n, seed, provider, arms, region=RENDER_TABLE_REGION)
    _, far = babbled_hands(n // 2, seed + 1, provider, arms, region=FAR_TABLE_REGION,
                           region_fraction=1.0)
    return near + far, [arms[k % len(arms)] for k in range(n)] + [
        arms[k % len(arms)] for k in range(n // 2)]


def _stats_mm(points: np.ndarray, truth: np.ndarray, far: np.ndarray) -> dict:
    """Median, p95 and far-half median [mm] of the distances between ``points`` and
    ``truth`` (n, 3) [m]; the mean error vector [mm] too (a bias)."""
    d = points - truth
    e = np.linalg.norm(d, axis=1) * 1e3
    return {"median": round(float(np.median(e)), 2), "p95": round(float(np.percentile(e, 95)), 2),
            "far_median": round(float(np.median(e[far])), 2) if far.any() else None,
            "bias": (d.mean(axis=0) * 1e3).round(2).tolist(),
            "far_bias": (d[far].mean(axis=0) * 1e3).round(2).tolist() if far.any() else None}


def rendered_eye_hand_figures(quick: bool, realism: str, provider: PinocchioJacobianProvider,
                              save_models: str = "", calibration: str = "") -> dict:
    """The eye-hand map learned from what the eyes see of a marker on the simulator's
    ``realism`` cameras (rendered, detected: :func:`rendered_gaze_samples`): half the samples
    of the hand marker (:func:`rendered_babbles`), half of a marker on a held stick
    (``TOOL_MARKER``, babbles directed over ``TOOL_REGION``: the far table is beyond the
    hand's reach from the eyes). Held-out errors [mm] in root_link against the marker's true
    position: ``table`` (the hand marker over ``TABLE_REGION``, far half x <= ``FAR_X``) and
    ``far`` (the stick's marker over ``FAR_TEST_REGION``), beside: triangulation with the eye
    calibration ``calibration`` (a file; '' = none) and with the nominal cameras, the map of
    decision 0070 (nominal cameras, projected pixels) and a map learned from the same rendered
    babbles with the nominal projection's pixels instead of the detected ones.
    ``save_models``: write ``eye_hand_rendered_<realism>.npz`` and ``eye_hand_nominal.npz``
    there."""
    from icub_pmp.vision.eye_calibration import EyeCalibration
    from icub_pmp.vision.head_cameras import CameraPoses
    from icub_sim_bridge.harness.marker_views import rendered_gaze_samples
    from icub_sim_bridge.harness.table_scene import TableScene
    from icub_sim_bridge.realism_config import RealismConfig
    from icub_sim_bridge.sim_config import SimConfig

    n_train, n_test = EH_RENDERED_QUICK if quick else EH_RENDERED
    evals = EH_EVALS_QUICK if quick else 300
    arms = ("right", "left")
    n_hand = n_train // 2
    tool_cfg = dataclasses.replace(SimConfig(), hand_marker_offset=TOOL_MARKER)
    runs = {}
    for name, cfg in (("hand", None), ("tool", tool_cfg)):
        scene = TableScene(RealismConfig(preset=realism), cfg)
        nominal = scene.camera
        try:
            if name == "hand":
                postures, which = rendered_babbles(n_hand, 310, provider)
                _, test_p = babbled_hands(n_test, 410, provider, region=TABLE_REGION,
                                          region_fraction=1.0)
            else:
                _, postures = babbled_hands(n_train - n_hand, 320, provider, region=TOOL_REGION,
                                            region_fraction=0.75, offset=TOOL_MARKER)
                which = [arms[k % 2] for k in range(len(postures))]
                _, test_p = babbled_hands(n_test, 420, provider, region=FAR_TEST_REGION,
                                          region_fraction=1.0, offset=TOOL_MARKER)
            n = n_hand if name == "hand" else n_train - n_hand
            train = rendered_gaze_samples(scene, n, 11, postures, which, GAZE_LAG)
            test = rendered_gaze_samples(scene, n_test, 12, test_p,
                                         [arms[k % 2] for k in range(n_test)], GAZE_LAG)
        finally:
            scene.close()
        runs[name] = (train, test)
        print(f"rendered {realism}, {name} marker: {len(train.samples.inputs)} samples of "
              f"{train.renders} stereo renders in {train.seconds:.0f} s "
              f"({train.renders / train.seconds:.1f} renders/s, "
              f"{len(train.samples.inputs) / train.seconds:.1f} samples/s, load "
              f"{os.getloadavg()[0]:.1f}); held out {len(test.samples.inputs)}", file=sys.stderr)
    renders = sum(r[0].renders for r in runs.values())
    seconds = sum(r[0].seconds for r in runs.values())
    s = StereoSamples(*(np.concatenate(f) for f in zip(*(r[0].samples for r in runs.values()))))
    trainer = LmTrainer(LmTrainerConfig(max_evaluations=evals))
    rendered, report = EyeHandMap.train(s.inputs, s.hands_in_head(), "head", trainer=trainer,
                                        camera=camera_setup(nominal))
    rendered.info.update({"source": "rendered marker views, hand and stick (decision 0071)",
                          "realism": realism, "renders": renders})
    same, _ = EyeHandMap.train(s.projected(nominal).inputs, s.hands_in_head(), "head",
                               trainer=trainer, camera=camera_setup(nominal))
    n_0070 = EH_QUICK[0]  # the map vision_reach ran with in decision 0070 (its --quick)
    cams = {"left": nominal, "right": nominal}
    m0070 = projected_eye_hand_map(n_0070, evals, provider, cams, np.eye(3))
    if save_models:
        rendered.save(Path(save_models) / f"eye_hand_rendered_{realism}.npz")
        m0070.save(Path(save_models) / "eye_hand_nominal.npz")
    tri_nominal = StereoTriangulator(nominal, nominal)
    calib = EyeCalibration.load(calibration) if calibration else EyeCalibration.nominal(nominal)
    tri_calib = StereoTriangulator(*calib.intrinsics(nominal))
    out = {"realism": realism, "eye_calibration": calibration or None,
           "render_samples": len(s.inputs), "renders": renders,
           "renders_per_s": round(renders / seconds, 2),
           "render_samples_per_s": round(len(s.inputs) / seconds, 2),
           "map_train_rmse_mm": round(report.rmse * 1e3, 2), "map_0070_samples": n_0070}
    for test_name, (_, test) in zip(("table", "far"), runs.values()):
        t = test.samples
        far = test.truth[:, 0] <= FAR_X

        def triangulated(tri: StereoTriangulator, cal: EyeCalibration, t=t) -> np.ndarray:
            res = []
            for x, T in zip(t.inputs, t.poses):
                poses = cal.poses(CameraPoses(T[0], T[1]))
                res.append(tri.triangulate(tuple(x[:2]), tuple(x[2:4]), poses.T_root_left,
                                           poses.T_root_right).position)
            return np.array(res)

        figures = {
            "map_rendered": _stats_mm(t.head_to_root(rendered.locate(t.inputs)), test.truth,
                                      far),
            "map_same_babbles_projected": _stats_mm(t.head_to_root(same.locate(t.inputs)),
                                                    test.truth, far),
            "map_0070": _stats_mm(t.head_to_root(m0070.locate(t.inputs)), test.truth, far),
            "triangulation_calibrated": _stats_mm(triangulated(tri_calib, calib), test.truth,
                                                  far),
            "triangulation_nominal": _stats_mm(triangulated(
                tri_nominal, EyeCalibration.nominal(nominal)), test.truth, far),
            "fk_marker": _stats_mm(t.hands, test.truth, far),
        }
        dist = np.linalg.norm(t.hands - t.heads[:, :3, 3], axis=1)
        for name, f in figures.items():
            print(f"  {test_name}, {realism} cameras, held out ({len(t.inputs)}, "
                  f"{int(far.sum())} x <= {FAR_X}, {dist.min():.2f}-{dist.max():.2f} m from "
                  f"the head): {name} median {f['median']} mm, p95 {f['p95']}, far half "
                  f"{f['far_median']} (bias {f['bias']}, far {f['far_bias']})", file=sys.stderr)
        out.update({f"eyehand_{test_name}_{k}": v for k, v in figures.items()})
        out[f"eyehand_{test_name}_samples"] = len(t.inputs)
    return out


def eye_hand_figures(quick: bool, truth: PinocchioJacobianProvider, test_hand: np.ndarray,
                     save_models: str = "") -> dict:
    """The eye-hand map's figures (nominal and perturbed cameras; module doc), keyed as in the
    JSON line; ``test_hand``: the held-out right-hand babbles (the fixation protocol's hands
    with --quick); ``save_models``: write the maps to that directory."""
    eh: dict = {}
    n_eh = (EH_QUICK if quick else (15000, 5000))
    fixation_hands = test_hand[:n_eh[1]] if quick else analytic_babbling("right", n_eh[1], 400,
                                                                     truth).hand
    for name, pert in (("nominal", False), ("perturbed", True)):
        eh[name] = eye_hand_vs_triangulation(
            n_eh[0], n_eh[1], pert, EH_EVALS_QUICK if quick else 300, truth, fixation_hands,
            str(Path(save_models) / f"eye_hand_{name}.npz") if save_models else "")
        for test_name, r in eh[name].items():
            print(f"eye-hand {name}, {test_name}: map RMSE {r['eyehand_rmse']:.1f} mm (median "
                  f"{r['eyehand_median']:.1f}) vs triangulation {r['tri_rmse']:.1f} mm (median "
                  f"{r['tri_median']:.1f})", file=sys.stderr)
        print(f"  paper {PAPER['eyehand_err_mm_mean']} mean, {PAPER['eyehand_err_mm_std']} std",
              file=sys.stderr)
    return {
        "eyehand_err_mm_mean": eh["nominal"]["fixation"]["eyehand_mean"],
        "eyehand_err_mm_std": eh["nominal"]["fixation"]["eyehand_std"],
        "triangulation_err_mm_mean": eh["nominal"]["fixation"]["tri_mean"],
        "triangulation_err_mm_std": eh["nominal"]["fixation"]["tri_std"],
        "eyehand_err_mm_mean_perturbed": eh["perturbed"]["fixation"]["eyehand_mean"],
        "eyehand_err_mm_std_perturbed": eh["perturbed"]["fixation"]["eyehand_std"],
        "triangulation_err_mm_mean_perturbed": eh["perturbed"]["fixation"]["tri_mean"],
        "triangulation_err_mm_std_perturbed": eh["perturbed"]["fixation"]["tri_std"],
        "eyehand_rmse_mm_perturbed": round(eh["perturbed"]["fixation"]["eyehand_rmse"], 2),
        "triangulation_rmse_mm_perturbed": round(eh["perturbed"]["fixation"]["tri_rmse"], 2),
        "eyehand_beats_triangulation_perturbed": bool(
            eh["perturbed"]["fixation"]["eyehand_rmse"]
            < eh["perturbed"]["fixation"]["tri_rmse"]),
        "eyehand_rmse_mm_gaze": round(eh["nominal"]["gaze"]["eyehand_rmse"], 2),
        "triangulation_rmse_mm_gaze": round(eh["nominal"]["gaze"]["tri_rmse"], 2),
        "eyehand_err_mm_table_median": round(eh["nominal"]["table"]["eyehand_median"], 2),
        "eyehand_err_mm_table_p95": round(eh["nominal"]["table"]["eyehand_p95"], 2),
        "triangulation_err_mm_table_median": round(eh["nominal"]["table"]["tri_median"], 2),
        "eyehand_err_mm_table_median_perturbed": round(
            eh["perturbed"]["table"]["eyehand_median"], 2),
        "triangulation_err_mm_table_median_perturbed": round(
            eh["perturbed"]["table"]["tri_median"], 2),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="small dataset, < 2 min")
    ap.add_argument("--dataset", default="", help="a ROS babbling dataset (.npz) to report")
    ap.add_argument("--plot", action="store_true", help="write PNGs to bench/out/")
    ap.add_argument("--save-models", default="", metavar="DIR",
                    help="write the body model (body_right.npz) and the eye-hand maps "
                         "(eye_hand_nominal.npz, eye_hand_perturbed.npz) to DIR")
    ap.add_argument("--curve", action="store_true",
                    help="+ error vs samples and hidden sizes (each trained within the budget)")
    ap.add_argument("--eye-hand-only", action="store_true",
                    help="only the eye-hand map's figures (and models with --save-models)")
    ap.add_argument("--rendered", action="store_true",
                    help="with --eye-hand-only: learn the map from the hand marker rendered and "
                         "detected in both eyes on the --realism cameras (decision 0071); "
                         "--save-models writes DIR/eye_hand_rendered_<realism>.npz")
    ap.add_argument("--realism", choices=("ideal", "icub"), default="icub",
                    help="the simulator's cameras for --rendered (default icub, the shipped "
                         "robot)")
    ap.add_argument("--eye-calibration", default=None, metavar="FILE",
                    help="the eye calibration triangulation uses beside the --rendered map "
                         "(default: the preset's, config/eye_calibration/)")
    args = ap.parse_args()
    q = args.quick
    if args.rendered and not args.eye_hand_only:
        ap.error("--rendered goes with --eye-hand-only")
    if args.rendered:
        calib = (args.eye_calibration if args.eye_calibration is not None
                 else EYE_CALIBRATION.get(args.realism, ""))
        if calib and not Path(calib).is_file():
            ap.error(f"--eye-calibration: no file {calib}")
        if args.save_models:
            Path(args.save_models).mkdir(parents=True, exist_ok=True)
        load_start = os.getloadavg()
        out = rendered_eye_hand_figures(q, args.realism, PinocchioJacobianProvider(),
                                        args.save_models, calib)
        print(json.dumps({**out, "load_avg": [round(load_start[0], 1),
                                              round(os.getloadavg()[0], 1)]}))
        return
    if args.eye_hand_only:
        truth = PinocchioJacobianProvider()
        load_start = os.getloadavg()
        test_hand = analytic_babbling("right", 500 if q else 2000, 200, truth).hand
        out = eye_hand_figures(q, truth, test_hand, args.save_models)
        print(json.dumps({**out, "paper": PAPER, "load_avg": [
            round(load_start[0], 1), round(os.getloadavg()[0], 1)]}))
        return
    n_train, n_test = (3000, 500) if q else (10000, 2000)
    budget = 30.0 if q else 60.0  # [s] of CPU time (BUDGET_CLOCK)
    hidden = DEFAULT_HIDDEN
    n_pmp = 10 if q else 100
    spec = RobotSpec.load()
    truth = PinocchioJacobianProvider()
    idx = truth.icub.indices(spec.right_arm_joints)
    frame = spec.hand_frame("right")
    train = analytic_babbling("right", n_train, seed=100, provider=truth)
    test = analytic_babbling("right", n_test, seed=200, provider=truth)
    load_start = os.getloadavg()

    def train_body(method: str, n: int, hidden=DEFAULT_HIDDEN, data=train):
        """Train on the first n babbles within the CPU budget; (net, report, test errors [m])."""
        trainer = LmTrainer(trainer_config(method, budget))
        m, r = BodyNetwork.train("right", data.joint_names, data.q[:n], data.hand[:n],
                                 truth.lower[idx], truth.upper[idx], frame, hidden=hidden,
                                 trainer=trainer)
        return m, r, np.linalg.norm(m.position(test.q) - test.hand, axis=1)

    def rmse_mm(e: np.ndarray) -> float:
        return float(np.sqrt(np.mean(e ** 2)) * 1e3)

    net, report, err = train_body(METHOD, n_train, hidden)
    body_rmse = rmse_mm(err)
    jac_err = jacobian_error(net, truth, test.q[:200], idx)
    if args.save_models:
        net.save(Path(args.save_models) / "body_right.npz")
    print(f"body network 7-{'-'.join(map(str, hidden))}-3 ({METHOD}): {n_train} babbles, "
          f"{report.iterations} iterations ({report.evaluations} evaluations) in "
          f"{report.cpu_seconds:.1f} s CPU / {report.seconds:.1f} s wall (load "
          f"{load_start[0]:.1f}); held-out RMSE {body_rmse:.2f} mm (median "
          f"{np.median(err) * 1e3:.2f}, p95 {np.percentile(err, 95) * 1e3:.2f}); stopped: "
          f"{report.message}; paper {PAPER['body_rmse_mm']}", file=sys.stderr)
    _, report_old, err_old = train_body("trf-lsmr", n_train, hidden)
    print(f"  same data, same {budget:.0f} s CPU budget, trf-lsmr (decision 0040): "
          f"{report_old.evaluations} evaluations, held-out RMSE {rmse_mm(err_old):.2f} mm",
          file=sys.stderr)

    cfg = PmpConfig(posture_memory_size=1000 if q else 5000)
    learned = PmpPlanner(cfg, provider=LearnedJacobianProvider([net]))
    analytic = PmpPlanner(cfg, provider=truth)
    targets = test.hand[-n_pmp:]
    e_learned = pmp_errors(learned, truth, targets, frame)
    e_analytic = pmp_errors(analytic, truth, targets, frame)
    print(f"PMP on {n_pmp} targets: learned success {np.mean(e_learned <= SUCCESS):.2f} "
          f"(median {np.median(e_learned) * 1e3:.1f} mm), analytic "
          f"{np.mean(e_analytic <= SUCCESS):.2f} (median {np.median(e_analytic) * 1e3:.2f} mm)",
          file=sys.stderr)

    eh_keys = eye_hand_figures(q, truth, test.hand, args.save_models)

    # adaptation: a 12 cm tool along the hand's x axis; babbling goes on with the tool and the
    # model learns online: after each batch of new babbles, training continues from the current
    # model (warm start, lm-normal) on all the tool babbles so far (decision 0054)
    offset = np.array([0.12, 0.0, 0.0])
    tool_test = tool_hand(truth, test.q, idx, frame, offset)
    pool = ADAPT_POOL_QUICK if q else ADAPT_POOL
    tool_pool = analytic_babbling("right", pool[-1], seed=500, provider=truth)
    tool_train = tool_hand(truth, tool_pool.q, idx, frame, offset)
    before = float(np.sqrt(np.mean(np.sum((net.position(test.q) - tool_test) ** 2, 1))) * 1e3)
    goal = max(GOAL_MM, 1.25 * body_rmse)
    adapt_budget = ADAPT_BUDGET_QUICK if q else ADAPT_BUDGET  # [s] CPU per batch of babbles
    adapt = None
    curve = {}
    adapt_cpu = 0.0
    current = net
    for n_new in pool:
        current, rep = BodyNetwork.train(
            "right", train.joint_names, tool_pool.q[:n_new], tool_train[:n_new], net.lower,
            net.upper, frame, initial=current,
            trainer=LmTrainer(trainer_config(METHOD, adapt_budget)))
        adapt_cpu += rep.cpu_seconds
        e = float(np.sqrt(np.mean(np.sum((current.position(test.q) - tool_test) ** 2, 1))) * 1e3)
        curve[n_new] = round(e, 2)
        print(f"  tool: {n_new} babbles, held-out {e:.2f} mm (train {rep.rmse * 1e3:.2f}, "
              f"validation {rep.validation_rmse * 1e3:.2f} mm; {rep.iterations} iterations, "
              f"{rep.cpu_seconds:.1f} s CPU, stopped: {rep.message})", file=sys.stderr)
        if e <= goal:
            adapt = n_new
            break
    verdict = f"met with {adapt}" if adapt else f"not met within {pool[-1]}"
    print(f"tool 12 cm: error {before:.0f} mm right after the change; after n new babbles "
          f"(learning online from the model, <= {adapt_budget:.0f} s CPU per batch, "
          f"{adapt_cpu:.0f} s in all) {curve} mm (goal {goal:.1f} mm: {verdict})",
          file=sys.stderr)

    samples_curve: dict[str, float] = {}
    if args.curve:
        big = analytic_babbling("right", 30000, seed=600, provider=truth)
        for n, hid in CURVE:
            _, r, e = train_body(METHOD, n, hid, data=big if n > n_train else train)
            samples_curve[f"{n}x{'-'.join(map(str, hid))}"] = round(rmse_mm(e), 2)
            print(f"  curve {n} babbles, hidden {hid}: {rmse_mm(e):.2f} mm, "
                  f"{r.iterations} iterations, {r.cpu_seconds:.0f} s CPU", file=sys.stderr)
        print(f"error vs samples x hidden sizes [mm]: {samples_curve}", file=sys.stderr)

    ros = {"babble_samples_per_s": None, "babble_samples_per_s_sim": None,
           "visible_fraction": None, "babble_triangulation_err_mm_median": None}
    if args.dataset:
        d = load_dataset(args.dataset)
        m = d.meta
        ros = {"babble_samples_per_s": round(m["samples"] / m["wall_s"], 4),
               "babble_samples_per_s_sim": round(m["samples"] / m["sim_s"], 4),
               "visible_fraction": round(m["samples"] / max(m["attempts"], 1), 3),
               "babble_triangulation_err_mm_median": round(float(np.median(np.linalg.norm(
                   d.learner["hand_seen"] - d.ground_truth, axis=1))) * 1e3, 2)}

    if args.plot:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        OUT.mkdir(exist_ok=True)
        fig = plt.figure(figsize=(5, 4))
        ax = fig.add_subplot(projection="3d")
        ax.scatter(*train.hand[:2000].T, s=1)
        ax.set_title("babbled workspace, right hand [m]")
        fig.savefig(OUT / "body_schema_workspace.png", dpi=120)
        fig = plt.figure(figsize=(5, 3.5))
        xs = sorted(curve)
        plt.plot(xs, [curve[x] for x in xs], "o-")
        plt.xlabel("new babbles with the tool")
        plt.ylabel("held-out RMSE [mm]")
        plt.xscale("log")
        fig.savefig(OUT / "body_schema_adaptation.png", dpi=120, bbox_inches="tight")

    out = {
        **ros,
        "body_rmse_mm": round(body_rmse, 2),
        "body_err_mm_p95": round(float(np.percentile(err, 95)) * 1e3, 2),
        "body_train_s": round(report.seconds, 1),
        "body_train_cpu_s": round(report.cpu_seconds, 1),
        "body_train_iterations": report.iterations,
        "body_train_samples": n_train,
        "body_hidden": list(hidden),
        "body_method": METHOD,
        "body_rmse_mm_trf_lsmr": round(rmse_mm(err_old), 2),
        "body_train_cpu_s_trf_lsmr": round(report_old.cpu_seconds, 1),
        "jacobian_err_rel": round(jac_err, 3),
        "pmp_targets": n_pmp,
        "pmp_learned_success": round(float(np.mean(e_learned <= SUCCESS)), 3),
        "pmp_learned_err_mm_median": round(float(np.median(e_learned)) * 1e3, 2),
        "pmp_analytic_success": round(float(np.mean(e_analytic <= SUCCESS)), 3),
        "pmp_analytic_err_mm_median": round(float(np.median(e_analytic)) * 1e3, 3),
        **eh_keys,
        "adapt_samples": adapt,
        "adapt_goal_mm": round(goal, 2),
        "adapt_err_mm_before": round(before, 1),
        "adapt_curve_mm": curve,
        "adapt_cpu_s": round(adapt_cpu, 1),
        "error_vs_samples_hidden_mm": samples_curve,
        "paper": PAPER,
        "load_avg": [round(load_start[0], 1), round(os.getloadavg()[0], 1)],
    }
    print(json.dumps(out))


if __name__ == "__main__":
    main()
