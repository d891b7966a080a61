"""The growing neural gas of the peripersonal-space paper (Bhat and Mohan 2018, steps a-g):
each test states a property of the learned map."""

from __future__ import annotations

import numpy as np
import pytest

from icub_pmp.errors import ConfigError, InvalidInput, ModelError
from icub_pmp.peripersonal import (
    GrowingNeuralGas,
    GrowingNeuralGasConfig,
    MapNotTrained,
    analytic_babbling,
)

RING = (0.10, 0.20)  # inner and outer radius of the test distribution [m]


def ring(n: int, seed: int) -> np.ndarray:
    """Uniform samples (n, 3) of a flat annulus (z = 0) [m]."""
    rng = np.random.default_rng(seed)
    r = np.sqrt(rng.uniform(RING[0] ** 2, RING[1] ** 2, n))
    a = rng.uniform(0.0, 2 * np.pi, n)
    return np.column_stack([r * np.cos(a), r * np.sin(a), np.zeros(n)])


@pytest.fixture(scope="module")
def ring_map():
    gng = GrowingNeuralGas(GrowingNeuralGasConfig(length_scale=0.012, max_epochs=6), "ring")
    gng.fit(ring(4000, seed=1))
    return gng


def test_grows_on_a_2d_distribution_and_covers_it(ring_map):
    """From one neuron the map grows over a flat ring: held-out points of the ring are within
    2 cm of a neuron, no neuron sits in the hole or outside, and lateral connections join
    near neighbours only (the topology of the ring)."""
    gng = ring_map
    assert gng.size > 50
    assert gng.coverage(ring(2000, seed=2), 0.02) >= 0.98
    assert gng.quantisation_error(ring(2000, seed=2)) < 0.012
    r = np.linalg.norm(gng.neurons[:, :2], axis=1)
    assert r.min() > RING[0] - 0.01 and r.max() < RING[1] + 0.01
    assert np.abs(gng.neurons[:, 2]).max() < 1e-9  # never leaves the plane of the data
    lengths = np.linalg.norm(gng.neurons[gng.edges[:, 0]] - gng.neurons[gng.edges[:, 1]], axis=1)
    assert len(gng.edges) >= gng.size - 1 and lengths.max() < 0.06
    assert np.all(gng.edge_ages <= gng.config.age_max)


def test_vigilance_sets_the_resolution():
    """A finer kernel unit (smaller length_scale) means growth at smaller errors: more
    neurons and a smaller quantisation error on the same data."""
    data, test = ring(3000, 3), ring(1000, 4)
    coarse = GrowingNeuralGas(GrowingNeuralGasConfig(length_scale=0.03, max_epochs=4))
    fine = GrowingNeuralGas(GrowingNeuralGasConfig(length_scale=0.012, max_epochs=4))
    coarse.fit(data)
    fine.fit(data)
    assert fine.size > 2 * coarse.size
    assert fine.quantisation_error(test) < coarse.quantisation_error(test)


def test_separate_clusters_lose_their_connections():
    """Two tight clusters far apart: neurons grow in both, and the connections between them
    age out (age_max) so the map splits into two parts; no neuron is left without one."""
    rng = np.random.default_rng(5)
    a = rng.normal([0, 0, 0], 0.01, (1500, 3))
    b = rng.normal([0.5, 0, 0], 0.01, (1500, 3))
    gng = GrowingNeuralGas(GrowingNeuralGasConfig(length_scale=0.01, max_epochs=3))
    gng.fit(np.vstack([a, b]))
    near_a = np.linalg.norm(gng.neurons, axis=1) < 0.1
    near_b = np.linalg.norm(gng.neurons - [0.5, 0, 0], axis=1) < 0.1
    assert near_a.sum() >= 2 and near_b.sum() >= 2 and np.all(near_a | near_b)
    crossing = near_a[gng.edges[:, 0]] != near_a[gng.edges[:, 1]]
    assert not crossing.any()
    connected = np.zeros(gng.size, dtype=bool)
    connected[gng.edges.ravel()] = True
    assert connected.all()


def test_is_seeded():
    """The same seed and data give the same map."""
    data = ring(1500, 6)
    cfg = GrowingNeuralGasConfig(length_scale=0.02, max_epochs=2, seed=3)
    m1, m2 = GrowingNeuralGas(cfg), GrowingNeuralGas(cfg)
    m1.fit(data)
    m2.fit(data)
    np.testing.assert_array_equal(m1.neurons, m2.neurons)
    np.testing.assert_array_equal(m1.edges, m2.edges)


def test_save_and_load(tmp_path, ring_map):
    """A saved map loads back identical (neurons, connections, ages, errors, config)."""
    path = ring_map.save(tmp_path / "maps" / "ring")
    assert path.suffix == ".npz"
    back = GrowingNeuralGas.load(path)
    np.testing.assert_array_equal(back.neurons, ring_map.neurons)
    np.testing.assert_array_equal(back.edges, ring_map.edges)
    np.testing.assert_array_equal(back.edge_ages, ring_map.edge_ages)
    np.testing.assert_array_equal(back.errors, ring_map.errors)
    assert back.config == ring_map.config and back.label == "ring"
    assert back.report == ring_map.report
    with pytest.raises(ModelError, match="cannot load"):
        GrowingNeuralGas.load(tmp_path / "missing.npz")
    np.savez(tmp_path / "other.npz", x=np.zeros(3))
    with pytest.raises(ModelError, match="other.npz"):
        GrowingNeuralGas.load(tmp_path / "other.npz")


def test_bad_inputs_and_no_model():
    """NaN or wrongly shaped points are refused naming the rows; an untrained map says so."""
    gng = GrowingNeuralGas(label="left")
    with pytest.raises(MapNotTrained, match="left.*train it"):
        gng.nearest([0.0, 0.0, 0.0])
    bad = ring(10, 7)
    bad[3, 1] = np.nan
    with pytest.raises(InvalidInput, match=r"row\(s\) \[3\]"):
        gng.fit(bad)
    with pytest.raises(InvalidInput, match=r"shape \(m, 3\)"):
        gng.fit(np.zeros((5, 2)))
    with pytest.raises(InvalidInput, match="at least 2"):
        gng.fit(np.zeros((1, 3)))
    with pytest.raises(ConfigError, match="vigilance"):
        GrowingNeuralGasConfig(vigilance=1.5)
    with pytest.raises(ConfigError, match="unknown parameter"):
        GrowingNeuralGasConfig.from_dict({"tau": 3.0})


def test_arm_babbling_lies_in_the_arm_workspace():
    """Analytic babbling: the hand positions are the forward kinematics of postures within
    the arm's joint limits, on the arm's side of the body (the left hand mostly at y < 0)."""
    b = analytic_babbling("left", 200, seed=0)
    assert b.q.shape == (200, 7) and b.hand.shape == (200, 3)
    assert np.mean(b.hand[:, 1] < 0) > 0.8
    with pytest.raises(InvalidInput):
        analytic_babbling("left", 0, seed=0)
