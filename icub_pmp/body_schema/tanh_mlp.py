"""TanhMlp: a feed-forward network with tanh hidden layers and a linear output layer.

The body model of the body-schema paper (eq 1: two tanh hidden layers, linear outputs) and the
eye-hand map of the force paper (eq 12: one tanh hidden layer of 50) are both this network.
Inputs and outputs are normalised (``x_n = (x - x_mean) / x_scale``, likewise for y) and the
normalisation belongs to the network, so a saved network maps raw units to raw units.

Three derivatives, all vectorised over samples:

- :meth:`TanhMlp.input_jacobian`: dy/dx by the chain rule through the layers (eq 2 of the
  body-schema paper: ``J = W diag(g'(p)) O diag(g'(h)) Omega``), the Jacobian PMP uses;
- :meth:`TanhMlp.weight_jacobian`: d(normalised outputs)/d(weights), the Jacobian of the
  training residuals that Levenberg-Marquardt needs (:mod:`lm_trainer`);
- :meth:`TanhMlp.weight_jvp` / :meth:`weight_vjp`: the same Jacobian applied to a vector
  without forming it (forward- and back-propagation), for large datasets.

Parameters are one flat vector ``theta``: for each layer its weight matrix (out, in) row-major
then its bias (out,).
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from icub_pmp.errors import InvalidInput

__all__ = ["TanhMlp"]


class TanhMlp:
    """tanh MLP ``x (n_in) -> y (n_out)`` with normalisation (module doc).

    Args:
        sizes: layer sizes ``(n_in, h_1, ..., h_k, n_out)``, at least one hidden layer.
        theta: flat parameters (:attr:`n_params`,); default a seeded Nguyen-Widrow-like draw.
        x_mean, x_scale: input normalisation (n_in,); default 0 and 1.
        y_mean, y_scale: output normalisation (n_out,); default 0 and 1.
        seed: seed of the initial weights when ``theta`` is None.
    """

    def __init__(self, sizes: Sequence[int], theta: np.ndarray | None = None,
                 x_mean: np.ndarray | None = None, x_scale: np.ndarray | None = None,
                 y_mean: np.ndarray | None = None, y_scale: np.ndarray | None = None,
                 seed: int = 0):
        sizes = tuple(int(s) for s in sizes)
        if len(sizes) < 3 or min(sizes) < 1:
            raise InvalidInput(f"sizes: expected (n_in, hidden..., n_out) with at least one "
                               f"hidden layer and positive sizes, got {sizes}")
        self.sizes = sizes
        self._shapes = [(sizes[i + 1], sizes[i]) for i in range(len(sizes) - 1)]
        self.n_params = sum(o * i + o for o, i in self._shapes)
        self.x_mean = self._vec("x_mean", x_mean, sizes[0], 0.0)
        self.x_scale = self._vec("x_scale", x_scale, sizes[0], 1.0)
        self.y_mean = self._vec("y_mean", y_mean, sizes[-1], 0.0)
        self.y_scale = self._vec("y_scale", y_scale, sizes[-1], 1.0)
        if np.any(self.x_scale <= 0) or np.any(self.y_scale <= 0):
            raise InvalidInput("x_scale, y_scale: expected positive scales")
        if theta is None:
            theta = self._initial(seed)
        self.set_params(theta)

    @staticmethod
    def _vec(name: str, v, n: int, default: float) -> np.ndarray:
        out = np.full(n, default) if v is None else np.array(v, dtype=float).reshape(-1)
        if out.shape != (n,) or not np.all(np.isfinite(out)):
            raise InvalidInput(f"{name}: expected {n} finite values, got {np.shape(v)}")
        out.setflags(write=False)
        return out

    def _initial(self, seed: int) -> np.ndarray:
        """Uniform weights scaled by 1/sqrt(fan-in) (inputs normalised to unit spread), small
        biases spread over the tanh's active range."""
        rng = np.random.default_rng(seed)
        parts = []
        for o, i in self._shapes:
            parts.append(rng.uniform(-1, 1, (o, i)).ravel() * np.sqrt(3.0 / i))
            parts.append(rng.uniform(-0.5, 0.5, o))
        return np.concatenate(parts)

    # ------------------------------------------------------------------ parameters
    @property
    def n_in(self) -> int:
        """Number of inputs."""
        return self.sizes[0]

    @property
    def n_out(self) -> int:
        """Number of outputs."""
        return self.sizes[-1]

    @property
    def hidden(self) -> tuple[int, ...]:
        """Hidden layer sizes."""
        return self.sizes[1:-1]

    def params(self) -> np.ndarray:
        """A copy of the flat parameter vector (:attr:`n_params`,)."""
        return np.concatenate([np.r_[w.ravel(), b] for w, b in zip(self.weights, self.biases)])

    def set_params(self, theta: np.ndarray) -> None:
        """Set the weights and biases from a flat vector (copied)."""
        theta = np.array(theta, dtype=float).reshape(-1)
        if theta.shape != (self.n_params,) or not np.all(np.isfinite(theta)):
            raise InvalidInput(f"theta: expected {self.n_params} finite parameters, "
                               f"got {theta.size}")
        self.weights: list[np.ndarray] = []
        self.biases: list[np.ndarray] = []
        k = 0
        for o, i in self._shapes:
            self.weights.append(theta[k:k + o * i].reshape(o, i))
            k += o * i
            self.biases.append(theta[k:k + o])
            k += o

    def with_params(self, theta: np.ndarray) -> "TanhMlp":
        """A network of the same sizes and normalisation with parameters ``theta``."""
        return TanhMlp(self.sizes, theta, self.x_mean, self.x_scale, self.y_mean, self.y_scale)

    # ------------------------------------------------------------------ evaluation
    def _x(self, x: np.ndarray) -> tuple[np.ndarray, bool]:
        x = np.asarray(x, dtype=float)
        single = x.ndim == 1
        x2 = x[None] if single else x
        if x2.ndim != 2 or x2.shape[1] != self.n_in:
            raise InvalidInput(f"x: expected (n, {self.n_in}) or ({self.n_in},), got {x.shape}")
        return x2, single

    def _forward(self, xn: np.ndarray) -> list[np.ndarray]:
        """Activations of every layer: [x_n, a_1, ..., a_k, y_n] (the last one linear)."""
        acts = [xn]
        a = xn
        last = len(self.weights) - 1
        for li, (w, b) in enumerate(zip(self.weights, self.biases)):
            z = a @ w.T + b
            a = z if li == last else np.tanh(z)
            acts.append(a)
        return acts

    def normalise_x(self, x: np.ndarray) -> np.ndarray:
        """Normalised inputs ``(x - x_mean) / x_scale``."""
        return (np.asarray(x, dtype=float) - self.x_mean) / self.x_scale

    def normalise_y(self, y: np.ndarray) -> np.ndarray:
        """Normalised outputs ``(y - y_mean) / y_scale``."""
        return (np.asarray(y, dtype=float) - self.y_mean) / self.y_scale

    def predict(self, x: np.ndarray) -> np.ndarray:
        """Outputs (n, n_out) for inputs (n, n_in), or (n_out,) for one input (n_in,)."""
        x2, single = self._x(x)
        y = self._forward(self.normalise_x(x2))[-1] * self.y_scale + self.y_mean
        return y[0] if single else y

    def predict_normalised(self, xn: np.ndarray) -> np.ndarray:
        """Normalised outputs (n, n_out) of normalised inputs (n, n_in)."""
        return self._forward(np.asarray(xn, dtype=float))[-1]

    def input_jacobian(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Outputs (n, n_out) and dy/dx (n, n_out, n_in) in raw units (eq 2 of the body-schema
        paper, the chain rule through every layer); one input (n_in,) gives (n_out,) and
        (n_out, n_in)."""
        x2, single = self._x(x)
        acts = self._forward(self.normalise_x(x2))
        # back from the linear output: D = W_last, then D <- (D * g'(z_l)) @ W_l
        d = np.broadcast_to(self.weights[-1], (len(x2),) + self.weights[-1].shape)
        for li in range(len(self.weights) - 2, -1, -1):
            gp = 1.0 - acts[li + 1] ** 2  # tanh' of layer li's output
            d = (d * gp[:, None, :]) @ self.weights[li]
        jac = d * (self.y_scale[:, None] / self.x_scale[None, :])
        y = acts[-1] * self.y_scale + self.y_mean
        return (y[0], jac[0]) if single else (y, jac)

    # ------------------------------------------------------------------ training derivatives
    def weight_jacobian(self, xn: np.ndarray, dtype: type | np.dtype = float) -> np.ndarray:
        """d y_n / d theta (n * n_out, n_params) for normalised inputs (n, n_in): rows ordered
        sample-major (the order of ``(Y_pred - Y).ravel()``), vectorised backpropagation.
        Each layer's block is written in place into one C-ordered array of ``dtype`` (float32
        halves the memory and the cost of J^T J, :mod:`normal_equations_lm`)."""
        xn = np.asarray(xn, dtype=float)
        n = len(xn)
        acts = self._forward(xn)
        nl = len(self.weights)
        out = np.empty((n, self.n_out, self.n_params), dtype=dtype)
        starts = np.cumsum([0] + [o * i + o for o, i in self._shapes])
        # delta: d y_n / d z_l  (n, n_out, size_l), starting at the linear output (identity)
        delta = np.broadcast_to(np.eye(self.n_out), (n, self.n_out, self.n_out))
        for li in range(nl - 1, -1, -1):
            o, i = self._shapes[li]
            k = starts[li]
            dw = out[:, :, k:k + o * i].reshape(n, self.n_out, o, i)
            if not np.shares_memory(dw, out):  # pragma: no cover - numpy always gives a view
                raise RuntimeError("weight_jacobian: block is not a view")
            np.multiply(delta[:, :, :, None], acts[li][:, None, None, :], out=dw)
            out[:, :, k + o * i:k + o * i + o] = delta
            if li > 0:
                gp = 1.0 - acts[li] ** 2
                delta = (delta @ self.weights[li]) * gp[:, None, :]
        return out.reshape(n * self.n_out, self.n_params)

    def weight_jvp(self, xn: np.ndarray, v: np.ndarray, acts: list[np.ndarray] | None = None
                   ) -> np.ndarray:
        """(d y_n / d theta) @ v, (n * n_out,), by forward propagation of the tangent ``v``."""
        acts = acts if acts is not None else self._forward(np.asarray(xn, dtype=float))
        tmp = self.with_params(v)
        nl = len(self.weights)
        dz = None
        da = np.zeros_like(acts[0])
        for li in range(nl):
            dz = acts[li] @ tmp.weights[li].T + tmp.biases[li] + da @ self.weights[li].T
            if li < nl - 1:
                da = dz * (1.0 - acts[li + 1] ** 2)
        assert dz is not None
        return dz.ravel()

    def weight_vjp(self, xn: np.ndarray, u: np.ndarray, acts: list[np.ndarray] | None = None
                   ) -> np.ndarray:
        """(d y_n / d theta)^T @ u, (n_params,), by backpropagation of ``u`` (n * n_out,)."""
        acts = acts if acts is not None else self._forward(np.asarray(xn, dtype=float))
        g = np.asarray(u, dtype=float).reshape(len(acts[0]), self.n_out)
        parts: list[np.ndarray] = []
        for li in range(len(self.weights) - 1, -1, -1):
            parts.append(g.sum(axis=0))
            parts.append((g.T @ acts[li]).ravel())
            if li > 0:
                g = (g @ self.weights[li]) * (1.0 - acts[li] ** 2)
        return np.concatenate(parts[::-1])
