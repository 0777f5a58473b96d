"""The Gaussian process's kernel ``C * RBF(l) + White(n)`` as one scikit-learn kernel.

scikit-learn's composite ``ConstantKernel * RBF + WhiteKernel`` spends about half of a
GPR fit on Python bookkeeping: every evaluation of the log marginal likelihood in the
L-BFGS loop walks the Sum and Product trees, rebuilds each leaf's hyperparameter list
through ``dir()`` and sets ``theta`` through ``get_params``/``set_params``. This kernel
has the same three hyperparameters, bounds and starting point, and does the composite's
arithmetic in the composite's order (the constant's full matrix times the RBF's, plus
``noise * I``; the gradient stacked constant, length scale, noise), so a GPR fitted with
it has the composite's ``theta``, ``alpha_`` and predictions bit for bit
(tests/unit/test_models.py), in about half the time.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.distance import cdist, pdist, squareform
from sklearn.gaussian_process.kernels import Hyperparameter, Kernel, StationaryKernelMixin

__all__ = ["ScaledRBFWithNoise"]

_NAMES = ("constant_value", "length_scale", "noise_level")


class ScaledRBFWithNoise(StationaryKernelMixin, Kernel):
    """``constant_value * exp(-d^2 / (2 length_scale^2)) + noise_level * I``, isotropic.

    Parameters and bounds are those of scikit-learn's ``ConstantKernel``, ``RBF`` and
    ``WhiteKernel``; ``theta`` is their logarithms in that order, as the composite's.
    """

    def __init__(
        self,
        constant_value=1.0,
        constant_value_bounds=(1e-5, 1e5),
        length_scale=1.0,
        length_scale_bounds=(1e-5, 1e5),
        noise_level=1.0,
        noise_level_bounds=(1e-5, 1e5),
    ):
        self.constant_value = constant_value
        self.constant_value_bounds = constant_value_bounds
        self.length_scale = length_scale
        self.length_scale_bounds = length_scale_bounds
        self.noise_level = noise_level
        self.noise_level_bounds = noise_level_bounds

    @property
    def hyperparameters(self):
        return [Hyperparameter(name, "numeric", getattr(self, f"{name}_bounds")) for name in _NAMES]

    @property
    def n_dims(self):
        return len(_NAMES)

    # The composite takes each leaf's logarithm on its own and appends them; so does this.
    @property
    def theta(self):
        return np.hstack([np.log(np.hstack([getattr(self, name)])) for name in _NAMES])

    @theta.setter
    def theta(self, theta):
        for i, name in enumerate(_NAMES):
            setattr(self, name, np.exp(theta[i]))

    @property
    def bounds(self):
        # Every hyperparameter is free (theta has all three); a fit checks it here.
        fixed = [n for n in _NAMES if isinstance(getattr(self, f"{n}_bounds"), str)]
        if fixed:
            raise ValueError(
                f"ScaledRBFWithNoise: {', '.join(fixed)} fixed; expected (low, high) bounds for"
                " every hyperparameter (scikit-learn's composite kernel fixes them)"
            )
        return np.vstack([np.log(np.vstack([getattr(self, f"{n}_bounds")])) for n in _NAMES])

    def clone_with_theta(self, theta):
        cloned = ScaledRBFWithNoise(
            self.constant_value,
            self.constant_value_bounds,
            self.length_scale,
            self.length_scale_bounds,
            self.noise_level,
            self.noise_level_bounds,
        )
        cloned.theta = theta
        return cloned

    def __call__(self, X, Y=None, eval_gradient=False):
        X = np.atleast_2d(X)
        scale = np.squeeze(self.length_scale).astype(float)
        constant = np.full((X.shape[0], X.shape[0] if Y is None else len(Y)), self.constant_value)
        if Y is not None:
            if eval_gradient:
                raise ValueError("Gradient can only be evaluated when Y is None.")
            # The white noise is zero between distinct sets of points.
            return constant * np.exp(-0.5 * cdist(X / scale, Y / scale, metric="sqeuclidean"))
        dists = pdist(X / scale, metric="sqeuclidean")
        rbf = squareform(np.exp(-0.5 * dists))
        np.fill_diagonal(rbf, 1)
        white = self.noise_level * np.eye(X.shape[0])
        K = constant * rbf + white
        if not eval_gradient:
            return K
        gradient = np.dstack(
            (
                constant[:, :, np.newaxis] * rbf[:, :, np.newaxis],
                (rbf * squareform(dists))[:, :, np.newaxis] * constant[:, :, np.newaxis],
                white[:, :, np.newaxis],
            )
        )
        return K, gradient

    def diag(self, X):
        n = np.asarray(X).shape[0]
        return np.full(n, self.constant_value) * np.ones(n) + np.full(n, self.noise_level)

    def __repr__(self):  # the composite's
        return (
            f"{np.sqrt(self.constant_value):.3g}**2 * RBF(length_scale={self.length_scale:.3g})"
            f" + WhiteKernel(noise_level={self.noise_level:.3g})"
        )
