"""The learned body schema's cores: each test states a claim of the body-schema paper (eqs 1-2)
or of the force paper (eq 12) that the implementation must meet."""

from __future__ import annotations

import numpy as np
import pytest

from icub_pmp.body_schema import (
    BodyNetwork,
    EyeHandMap,
    LearnedJacobianProvider,
    LmTrainer,
    LmTrainerConfig,
    TanhMlp,
)
from icub_pmp.errors import ConfigError, InvalidInput, ModelError
from icub_pmp.kinematics import RobotSpec
from icub_pmp.kinematics.eye_kinematics import CameraIntrinsics, EyeKinematics, project_point
from icub_pmp.peripersonal import analytic_babbling
from icub_pmp.pmp import (
    BranchNetwork,
    ForceField,
    PmpNetwork,
    PmpPlanner,
    ReachGoal,
    Relaxation,
    RelaxationSettings,
)
from icub_pmp.pmp.pinocchio_provider import PinocchioJacobianProvider

MM = 1e-3
L1, L2 = 0.30, 0.25  # the planar 2-link arm [m]


def planar_fk(q: np.ndarray) -> np.ndarray:
    """Tip positions (n, 3) of the planar 2-link arm (z = 0)."""
    q = np.atleast_2d(q)
    return np.c_[L1 * np.cos(q[:, 0]) + L2 * np.cos(q[:, 0] + q[:, 1]),
                 L1 * np.sin(q[:, 0]) + L2 * np.sin(q[:, 0] + q[:, 1]), np.zeros(len(q))]


@pytest.fixture(scope="module")
def planar():
    """A body network of the 2-link arm trained by MINPACK LM on 400 babbles."""
    rng = np.random.default_rng(0)
    q = rng.uniform(-1.4, 1.4, (400, 2))
    trainer = LmTrainer(LmTrainerConfig(method="lm", max_evaluations=150))
    net, report = BodyNetwork.train("right", ("j1", "j2"), q, planar_fk(q), [-1.4, -1.4],
                                    [1.4, 1.4], "tip", hidden=(10, 10), trainer=trainer)
    return net, report


@pytest.fixture(scope="module")
def icub_right():
    """A body network of the iCub right arm trained on pinocchio FK babbles (training data 3000,
    held-out 1000), with the paper's hidden sizes and 60 LM evaluations (about 7 mm RMSE)."""
    b = analytic_babbling("right", 4000, seed=3)
    spec = RobotSpec.load()
    provider = PinocchioJacobianProvider()
    idx = [provider.joint_names.index(j) for j in b.joint_names]
    trainer = LmTrainer(LmTrainerConfig(method="trf-lsmr", max_evaluations=60))
    net, _ = BodyNetwork.train("right", b.joint_names, b.q[:3000], b.hand[:3000],
                               provider.lower[idx], provider.upper[idx],
                               spec.hand_frame("right"), trainer=trainer)
    return net, b, provider, idx


def test_input_jacobian_matches_finite_differences():
    """Eq 2 (the chain rule through the weights) equals central differences of the network, with
    normalisation, for one and two hidden layers."""
    rng = np.random.default_rng(1)
    for sizes in [(7, 32, 41, 3), (7, 50, 3)]:
        n = sizes[0]
        net = TanhMlp(sizes, x_mean=rng.normal(size=n), x_scale=rng.uniform(0.5, 2, n),
                      y_mean=rng.normal(size=3), y_scale=rng.uniform(0.1, 1, 3), seed=2)
        x = rng.normal(size=(6, sizes[0]))
        _, jac = net.input_jacobian(x)
        eps = 1e-6
        fd = np.stack([(net.predict(x + eps * e) - net.predict(x - eps * e)) / (2 * eps)
                       for e in np.eye(sizes[0])], axis=-1)
        assert np.max(np.abs(jac - fd)) < 1e-7 * max(1.0, np.max(np.abs(jac)))


def test_weight_jacobian_matches_finite_differences_and_products():
    """The residual Jacobian LM uses equals finite differences in the weights, and the
    matrix-free products (forward / back propagation) equal J v and J^T u."""
    net = TanhMlp((3, 5, 4, 3), seed=4)
    rng = np.random.default_rng(5)
    xn = rng.normal(size=(7, 3))
    theta = net.params()
    jac = net.weight_jacobian(xn)
    eps = 1e-6
    fd = np.stack([(net.with_params(theta + eps * e).predict_normalised(xn)
                    - net.with_params(theta - eps * e).predict_normalised(xn)).ravel() / (2 * eps)
                   for e in np.eye(net.n_params)], axis=1)
    assert np.max(np.abs(jac - fd)) < 1e-7
    v, u = rng.normal(size=net.n_params), rng.normal(size=jac.shape[0])
    assert np.allclose(net.weight_jvp(xn, v), jac @ v, atol=1e-12)
    assert np.allclose(net.weight_vjp(xn, u), jac.T @ u, atol=1e-12)


def test_lm_learns_the_planar_arm(planar):
    """Levenberg-Marquardt fits the 2-link arm's forward kinematics to sub-millimetre accuracy
    on postures it never saw (links 0.30 + 0.25 m)."""
    net, report = planar
    rng = np.random.default_rng(9)
    q = rng.uniform(-1.4, 1.4, (500, 2))
    err = np.linalg.norm(net.position(q) - planar_fk(q), axis=1)
    assert report.rmse < 0.5 * MM
    assert np.sqrt(np.mean(err ** 2)) < 1.0 * MM


def test_learned_provider_drives_pmp_on_the_planar_arm(planar):
    """PMP relaxing on the learned Jacobian (eqs 1-5 of the body-schema paper) brings the true
    tip of the 2-link arm to a reachable target."""
    net, _ = planar
    provider = LearnedJacobianProvider([net], joint_names=("j1", "j2"))
    target = planar_fk(np.array([0.9, -0.7]))[0]
    branches = BranchNetwork((), {"right": ("j1", "j2")}, [], {"right": [1.0, 1.0]})
    q0 = np.array([-0.3, 0.8])
    network = PmpNetwork(provider, branches, {"right": "tip"}, q0,
                         {"right": ForceField(target, 1000.0)})
    trace = Relaxation(RelaxationSettings(max_steps=400)).run(network)
    q_final = network.q_full(trace.z[-1])
    assert np.linalg.norm(planar_fk(q_final)[0] - target) < 2 * MM


def test_icub_body_network_matches_pinocchio(icub_right):
    """On held-out babbles of the iCub right arm, the learned hand position is within a
    centimetre of pinocchio's and the learned Jacobian (eq 2) points like pinocchio's (median
    relative error below 0.25)."""
    net, b, provider, idx = icub_right
    q_test, hand_test = b.q[3000:], b.hand[3000:]
    err = np.linalg.norm(net.position(q_test) - hand_test, axis=1)
    assert np.sqrt(np.mean(err ** 2)) < 10 * MM
    pred = net.jacobian(q_test[:200])
    q_full = provider.icub.posture("rest")
    rel = []
    for k in range(200):
        q_full[idx] = q_test[k]
        j_true = provider.kinematics(q_full, [net.frame]).jacobians[0, :3][:, idx]
        rel.append(np.linalg.norm(pred.jacobians[k] - j_true) / np.linalg.norm(j_true))
    assert np.median(rel) < 0.25


def test_pmp_planner_reaches_with_the_learned_icub_arm(icub_right):
    """The PMP planner on the learned provider (right arm, no torso) ends with the true hand
    (pinocchio FK of the planned posture) within 15 mm of targets the arm can reach."""
    net, b, provider, idx = icub_right
    learned = LearnedJacobianProvider([net])
    planner = PmpPlanner(provider=learned)
    rest = planner.start_configuration(None)
    errors = []
    for k in range(3):
        target = b.hand[3500 + k]
        plan = planner.plan(ReachGoal(targets={"right": target}, use_torso=False), rest)
        q_true = provider.icub.posture("rest")
        for j, name in enumerate(learned.joint_names):
            q_true[provider.joint_names.index(name)] = plan.q_final[j]
        errors.append(np.linalg.norm(provider.positions(q_true, [net.frame])[0] - target))
    assert np.median(errors) < 15 * MM, errors


def _stereo_samples(n: int, seed: int, cx_shift: float = 0.0):
    """Eye-hand inputs (u_l, v_l, u_r, v_r, tilt, version, vergence) of random points in view
    of both iCub eye cameras, and the points (n, 3) in the head frame."""
    eyes = EyeKinematics(np.eye(4))
    cam = CameraIntrinsics(cx=160.0 + cx_shift)
    rng = np.random.default_rng(seed)
    inputs, points = [], []
    while len(points) < n:
        tilt, version, verg = rng.uniform(-0.3, 0.3), rng.uniform(-0.3, 0.3), rng.uniform(0.05, 0.4)
        T_l = eyes.T_head_camera("left", tilt, version, verg)
        T_r = eyes.T_head_camera("right", tilt, version, verg)
        z = rng.uniform(0.25, 0.6)
        p = T_l[:3, :3] @ np.array([rng.uniform(-0.2, 0.2) * z, rng.uniform(-0.15, 0.15) * z,
                                    z]) + T_l[:3, 3]
        try:
            uv_l, uv_r = project_point(T_l, p, cam), project_point(T_r, p, cam)
        except InvalidInput:
            continue
        if np.all((uv_l >= 0) & (uv_l < [320, 240]) & (uv_r >= 0) & (uv_r < [320, 240])):
            inputs.append(np.r_[uv_l, uv_r, tilt, version, verg])
            points.append(p)
    return np.array(inputs), np.array(points)


def test_eye_hand_map_learns_stereo_geometry(tmp_path):
    """Eq 12 of the force paper: the 7-50-3 map trained on 1500 stereo samples locates held-out
    hands within a centimetre (RMSE), and survives a save/load round trip."""
    x, p = _stereo_samples(1800, seed=11)
    trainer = LmTrainer(LmTrainerConfig(method="trf-lsmr", max_evaluations=80))
    m, _ = EyeHandMap.train(x[:1500], p[:1500], "head", trainer=trainer)
    err = np.linalg.norm(m.locate(x[1500:]) - p[1500:], axis=1)
    assert np.sqrt(np.mean(err ** 2)) < 10 * MM
    again = EyeHandMap.load(m.save(tmp_path / "eye_hand"))
    assert np.allclose(again.locate(x[1500:]), m.locate(x[1500:]))


def test_save_load_round_trip_and_wrong_arm(planar, tmp_path):
    """A saved body model predicts the same after loading, keeps its metadata, and loading it
    as the other arm's model is a clear error naming both arms."""
    net, _ = planar
    path = net.save(tmp_path / "right_model")
    again = BodyNetwork.load(path, arm="right")
    q = np.array([[0.2, 0.3], [-1.0, 1.0]])
    assert np.allclose(again.position(q), net.position(q))
    assert again.joint_names == ("j1", "j2") and again.hidden == (10, 10)
    assert again.info["samples"] == 400
    with pytest.raises(ModelError, match="right arm, not of the left arm"):
        BodyNetwork.load(path, arm="left")
    with pytest.raises(ModelError, match="eye_hand_map"):
        EyeHandMap.load(path)


def test_missing_model_file(tmp_path):
    """A missing model file is a ModelError naming the path."""
    with pytest.raises(ModelError, match="no body_network model file.*at .*nothing.npz"):
        BodyNetwork.load(tmp_path / "nothing.npz")


def test_bad_datasets_are_rejected():
    """An empty dataset, NaN samples, mismatched lengths and a wrong input width answer with a
    clear error before any training."""
    args = ("right", ("j1", "j2"))
    lim = ([-1, -1], [1, 1], "tip")
    with pytest.raises(InvalidInput, match="empty"):
        BodyNetwork.train(*args, np.empty((0, 2)), np.empty((0, 3)), *lim)
    q = np.zeros((5, 2))
    hand = np.zeros((5, 3))
    hand[3, 1] = np.nan
    with pytest.raises(InvalidInput, match="1 sample.*NaN.*row 3"):
        BodyNetwork.train(*args, q, hand, *lim)
    with pytest.raises(InvalidInput, match="5 inputs but 4 targets"):
        BodyNetwork.train(*args, q, np.zeros((4, 3)), *lim)
    with pytest.raises(InvalidInput, match=r"\(n, 2\)"):
        BodyNetwork.train(*args, np.zeros((5, 3)), np.zeros((5, 3)), *lim)
    with pytest.raises(ConfigError, match="method"):
        LmTrainerConfig(method="adam")
    with pytest.raises(InvalidInput, match="needs at least as many residuals"):
        LmTrainer(LmTrainerConfig(method="lm")).fit((10, 10), np.zeros((3, 2)), np.ones((3, 3)))


def test_learned_provider_rejects_unknown_frames(planar):
    """Asking the learned provider for a frame no model learned names the frames it has."""
    net, _ = planar
    provider = LearnedJacobianProvider([net], joint_names=("j1", "j2"))
    with pytest.raises(InvalidInput, match="unknown frame of the learned body model 'l_hand"):
        provider.kinematics(np.zeros(2), ["l_hand_dh_frame"])


def test_babbling_targets_samples_and_dataset(tmp_path):
    """Babbling targets stay within the limits less the margin; dropped postures are counted
    by reason; the saved dataset gives the learner's fields and the ground truth apart."""
    from icub_pmp.body_schema import LEARNER_FIELDS, BabblingSample, MotorBabbling, load_dataset

    lower, upper = -np.ones(7), np.ones(7) * 2
    b = MotorBabbling([f"j{i}" for i in range(7)], lower, upper, "right", seed=1,
                      limit_margin=0.1)
    targets = np.array([b.next_target() for _ in range(500)])
    assert np.all(targets >= lower + 0.3) and np.all(targets <= upper - 0.3)
    for k in range(3):
        b.record(BabblingSample(float(k), targets[k], np.zeros(6), np.array([1, 2, 3, 4.0]),
                                np.array([0.1, 0, k]), np.array([0.1, 0, k + 0.01])))
    b.drop("marker not seen in both images")
    assert (b.attempts, b.dropped) == (4, 1) and b.visible_fraction == 0.75
    with pytest.raises(InvalidInput, match="hand_seen"):
        b.record(BabblingSample(0.0, targets[0], np.zeros(6), np.zeros(4),
                                np.array([np.nan, 0, 0]), np.zeros(3)))
    data = load_dataset(b.save(tmp_path / "d", {"note": "x"}))
    assert set(data.learner) == set(LEARNER_FIELDS)
    assert np.allclose(data.learner["q"], targets[:3]) and data.ground_truth.shape == (3, 3)
    assert data.meta["drop_reasons"] == {"marker not seen in both images": 1}
    with pytest.raises(ModelError, match="no babbling dataset"):
        load_dataset(tmp_path / "missing.npz")


def test_marker_detector_finds_the_green_marker():
    """The HSV threshold finds a green disc's centroid within a tenth of a pixel and ignores
    the red and blue objects; an image without the marker gives found=False."""
    import cv2

    from icub_pmp.body_schema import MarkerDetector

    img = np.full((240, 320, 3), 90, np.uint8)
    cv2.circle(img, (200, 60), 20, (217, 25, 25), -1)  # red box colour
    cv2.circle(img, (50, 200), 15, (25, 76, 217), -1)  # blue cylinder colour
    clean = img.copy()
    cv2.circle(img, (123, 87), 6, (25, 230, 25), -1)
    d = MarkerDetector().detect(img)
    assert d.found and abs(d.u - 123) < 0.1 and abs(d.v - 87) < 0.1 and d.area > 50
    assert not MarkerDetector().detect(clean).found
    with pytest.raises(InvalidInput, match="RGB"):
        MarkerDetector().detect(np.zeros((10, 10), np.uint8))


def test_min_jerk_move_respects_the_rate_limits():
    """A babbling move reaches its target at rest and stays within 70 % of the velocity limit;
    a short move takes the minimum time."""
    from icub_pmp.body_schema import min_jerk_move

    t, q, qd = min_jerk_move(np.zeros(2), np.array([2.0, -0.5]), np.array([1.0, 1.0]),
                             np.array([10.0, 10.0]), 0.5)
    assert np.allclose(q[-1], [2.0, -0.5]) and np.allclose(qd[[0, -1]], 0)
    assert np.max(np.abs(qd)) <= 0.7 + 1e-9 and t[-1] > 0.5
    t2, _, _ = min_jerk_move(np.zeros(2), np.full(2, 0.01), np.ones(2), np.ones(2) * 10, 0.5)
    assert t2[-1] == pytest.approx(0.5)


def test_jacobian_source_config(planar, tmp_path):
    """jacobian_source: an unknown source or 'learned' without model files is a ConfigError;
    a model file of the other arm is refused naming both arms; 'analytic' is the URDF."""
    from icub_pmp.body_schema import JacobianSourceConfig, make_provider

    with pytest.raises(ConfigError, match="jacobian_source"):
        JacobianSourceConfig(jacobian_source="neural")
    with pytest.raises(ConfigError, match="needs learned_model_right"):
        JacobianSourceConfig(jacobian_source="learned")
    path = planar[0].save(tmp_path / "right.npz")
    with pytest.raises(ConfigError, match="right arm, not of the left arm"):
        make_provider(JacobianSourceConfig(jacobian_source="learned",
                                           learned_model_left=str(path)))
    assert isinstance(make_provider(JacobianSourceConfig()), PinocchioJacobianProvider)
