"""The regressors of the models: one factory, and what a fitted one says in the paper's units.

Every regressor is wrapped so that inputs AND target are standardised (see
:func:`make_regressor`); :func:`linear_terms` converts any affine fit back to the paper's
units, per degree C. The group search over their hyper-parameters is
:mod:`thermaxis.method.search`; the Eq. 8 and Eq. 9 estimators fitting them,
:mod:`thermaxis.method.estimators`.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager

import numpy as np
from sklearn import config_context
from sklearn.compose import TransformedTargetRegressor
from sklearn.cross_decomposition import PLSRegression
from sklearn.gaussian_process import GaussianProcessRegressor
from sklearn.linear_model import BayesianRidge, LassoLars, LinearRegression, Ridge
from sklearn.pipeline import Pipeline
from sklearn.preprocessing import StandardScaler
from sklearn.svm import SVR

from thermaxis.method.gp_kernel import ScaledRBFWithNoise
from thermaxis.vocabulary import ALGORITHMS

__all__ = [
    "SVR_TOL",
    "check_algorithm",
    "check_params",
    "base_regressor",
    "make_regressor",
    "pls_fits",
    "checked_once",
    "linear_terms",
    "predict_with_std",
]


# libsvm stops once the dual's largest KKT violation is below ``tol`` (targets standardised).
# At scikit-learn's 1e-3 the solver stops wherever its path first gets there: last-bit
# differences in the inputs (OpenBLAS kernels differ between CPUs) moved the twin's held-out
# SVR results by up to 0.1 um (3 %). At 1e-9 two kernels agree to about 1e-8 um; the
# solver runs longer (the twin's held-out SVRs of four folds: 1.6 CPU-s instead of 0.8;
# 300 rows at C 100: 51 ms instead of 19) (docs/reports.md, "Byte-identical runs").
SVR_TOL = 1e-9


_ALLOWED_PARAMS = {
    "mlr": set(),
    "ridge": {"alpha"},
    "lasso": {"alpha"},
    "pls": {"n_components"},
    "svr": {"C", "epsilon", "gamma", "kernel"},
    "gpr": {"length_scale", "noise_level", "n_restarts_optimizer"},
    "bayesridge": set(),
}


def check_algorithm(algorithm: str) -> None:
    if algorithm not in ALGORITHMS:
        raise ValueError(
            f"unknown algorithm {algorithm!r}; expected one of {', '.join(ALGORITHMS)}"
        )


def check_params(algorithm: str, params: Mapping | None) -> dict:
    params = dict(params or {})
    unknown = sorted(set(params) - _ALLOWED_PARAMS[algorithm])
    if unknown:
        allowed = ", ".join(sorted(_ALLOWED_PARAMS[algorithm])) or "none"
        raise ValueError(f"unknown parameter(s) {unknown} for {algorithm}; allowed: {allowed}")
    return params


def pls_fits(n_components: int, n_rows: int, n_features: int) -> bool:
    """Whether PLS can fit ``n_components`` on ``n_rows`` rows of ``n_features`` inputs.

    make_regressor caps the components at the inputs; scikit-learn bounds them by the rows
    as well (``min(n, p)``).  A search's grid point past the rows of one of its inner
    splits scores NaN there, as GridSearchCV scores a failed fit, so it ranks last.
    """
    return min(int(n_components), n_features) <= n_rows


def base_regressor(algorithm: str, params: dict, random_state: int, n_features: int | None):
    if algorithm == "mlr":
        return LinearRegression()
    if algorithm == "bayesridge":
        # The ridge strength (the ratio of the noise's precision to the weights') that
        # maximises the evidence of the training rows (MacKay 1992; Tipping 2001): no
        # inner search, so no training run is spent on choosing it.
        return BayesianRidge()
    # A hyper-parameter left out keeps scikit-learn's default: the workflow's come from config.
    if algorithm == "ridge":
        return Ridge(**{name: float(value) for name, value in params.items()})
    if algorithm == "lasso":
        # The lasso's exact optimum by LARS (the same objective as coordinate descent's
        # Lasso): weak penalties on many correlated temperatures left coordinate descent
        # short of its optimum after 100,000 iterations, at 0.15 s a fit on 60 sensors,
        # where LARS reaches it in a few steps (docs/performance.md).  Deterministic.
        return LassoLars(**{name: float(value) for name, value in params.items()})
    if algorithm == "pls":
        # Inputs and target are already standardised by the pipeline.
        pls = PLSRegression(scale=False, **{name: int(value) for name, value in params.items()})
        if n_features is not None:
            pls.set_params(n_components=min(pls.n_components, n_features))
        return pls
    if algorithm == "svr":
        numbers = {name: float(params[name]) for name in ("C", "epsilon") if name in params}
        return SVR(tol=SVR_TOL, **{**params, **numbers})
    # gpr: bounds are in standardised units.  A nearly linear response drives the RBF
    # towards long length scales and large amplitudes, hence the wide upper bounds; a
    # noise floor of 1e-6 keeps exact (noise-free) training data well posed.
    kernel = ScaledRBFWithNoise(
        1.0,
        (1e-3, 1e5),
        float(params.get("length_scale", 1.0)),
        (1e-2, 1e4),
        float(params.get("noise_level", 0.1)),
        (1e-6, 1e1),
    )
    return GaussianProcessRegressor(
        kernel=kernel,
        normalize_y=False,
        n_restarts_optimizer=int(params.get("n_restarts_optimizer", 0)),
        random_state=random_state,
    )


def make_regressor(
    algorithm: str,
    params: Mapping | None = None,
    *,
    random_state: int,
    n_features: int | None = None,
) -> Pipeline:
    """An unfitted regressor with standardised inputs and standardised target.

    Parameters
    ----------
    algorithm : {"mlr", "svr", "ridge", "lasso", "pls", "gpr", "bayesridge"}
        Multiple linear regression, support-vector regression, ridge, lasso, partial least
        squares, Gaussian-process regression, evidence-maximising ridge.
    params : mapping, optional
        Hyper-parameters: ridge ``alpha``; pls ``n_components``; svr ``C``, ``epsilon`` (in
        standardised target units), ``gamma``, ``kernel`` (the workflow sets them from config
        ``models``; one left out keeps scikit-learn's default); gpr ``length_scale`` (1.0),
        ``noise_level`` (0.1), ``n_restarts_optimizer`` (0), the starting point of this
        module's kernel.  Unknown keys raise ``ValueError``.
    random_state : int
        Seed of the GPR optimiser restarts (config ``models.random_state``; the other
        algorithms are deterministic).
    n_features : int, optional
        Number of inputs; caps PLS ``n_components`` (PLS cannot use more components than
        inputs).

    Returns
    -------
    sklearn.pipeline.Pipeline
        ``StandardScaler`` followed by ``TransformedTargetRegressor(regressor,
        transformer=StandardScaler())``; GPR kernel ``Constant * RBF + White``.
    """
    check_algorithm(algorithm)
    params = check_params(algorithm, params)
    regressor = base_regressor(algorithm, params, random_state, n_features)
    return Pipeline(
        [
            ("standardise", StandardScaler()),
            (
                "regress",
                TransformedTargetRegressor(regressor=regressor, transformer=StandardScaler()),
            ),
        ]
    )


@contextmanager
def checked_once(regressors: Sequence, X: np.ndarray, y: np.ndarray) -> Iterator[None]:
    """Check ``regressors``' parameters and the finiteness of ``X`` and ``y`` once, then fit
    and predict inside with scikit-learn's own checks of both off: each of a
    :func:`make_regressor` pipeline's five estimators makes them again, and on tens of rows
    they cost several times the arithmetic (the same numbers either way)."""
    for regressor in regressors:
        regressor._validate_params()
    finite = bool(np.isfinite(X).all() and np.isfinite(y).all())
    with config_context(assume_finite=finite, skip_parameter_validation=True):
        yield


def _final_regressor(fitted):
    return fitted.named_steps["regress"].regressor_


def linear_terms(fitted_estimator, feature_names: Sequence[str]) -> dict[str, float] | None:
    """Constant and per-feature coefficients of an affine fit, in the inputs' own units.

    The pipeline standardises inputs and target internally; since every step is affine
    for mlr, ridge, lasso, pls and the evidence ridge, probing the prediction at the origin and at unit vectors
    gives the constant and the slopes in original units (per degree C).

    Parameters
    ----------
    fitted_estimator : Pipeline
        A fitted :func:`make_regressor` pipeline.
    feature_names : sequence of str
        Names of the inputs, in column order.

    Returns
    -------
    dict or None
        ``{"const": c, name: slope, ...}``; ``None`` for svr and gpr, which are not affine.
    """
    if not isinstance(
        _final_regressor(fitted_estimator),
        (LinearRegression, Ridge, LassoLars, PLSRegression, BayesianRidge),
    ):
        return None
    names = list(feature_names)
    n_inputs = fitted_estimator.named_steps["standardise"].n_features_in_
    if len(names) != n_inputs:
        raise ValueError(f"got {len(names)} feature names for a model with {n_inputs} inputs")
    probes = np.vstack([np.zeros(len(names)), np.eye(len(names))])
    values = np.asarray(fitted_estimator.predict(probes), dtype=float).ravel()
    const = float(values[0])
    terms = {"const": const}
    terms.update({name: float(v - const) for name, v in zip(names, values[1:], strict=False)})
    return terms


def predict_with_std(fitted_estimator, X) -> tuple[np.ndarray, np.ndarray]:
    """Predictive mean and standard deviation of a fitted GPR pipeline, original units.

    Raises
    ------
    NotImplementedError
        If the pipeline does not end in a Gaussian-process regressor.
    """
    gpr = _final_regressor(fitted_estimator)
    if not isinstance(gpr, GaussianProcessRegressor):
        raise NotImplementedError("prediction intervals are only available for algorithm 'gpr'")
    scaled = fitted_estimator.named_steps["standardise"].transform(np.asarray(X, dtype=float))
    mean_s, std_s = gpr.predict(scaled, return_std=True)
    target_scaler = fitted_estimator.named_steps["regress"].transformer_
    scale = float(target_scaler.scale_[0])
    offset = float(target_scaler.mean_[0])
    return np.asarray(mean_s).ravel() * scale + offset, np.asarray(std_s).ravel() * scale
