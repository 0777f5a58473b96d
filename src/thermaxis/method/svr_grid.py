"""An SVR search grid scored on one hold-out through scikit-learn's own libsvm binding.

A grid search fits one ``SVR`` per grid point on the same standardised arrays. On the
runs of a thermal record (tens of rows, a few sensors) libsvm solves each in about
0.2 ms, while ``SVR.fit`` and ``SVR.predict`` spend about 1 ms more re-validating the
same arrays (scikit-learn 1.9 routes every array through narwhals' dataframe checks).
:func:`svr_grid_predictions` checks the arrays once and calls the solver ``SVR`` calls,
``sklearn.svm._libsvm``, with the arguments ``SVR`` passes it, so its predictions are
``SVR(**params).fit(X_train, y_train).predict(X_test)`` bit for bit
(tests/unit/test_models.py checks kernels and gammas against the estimator).
The refit on all rows with the chosen parameters is the public ``SVR``.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence

import numpy as np
from sklearn.exceptions import ConvergenceWarning
from sklearn.svm import SVR, _libsvm

__all__ = ["svr_grid_predictions"]

# scikit-learn's LIBSVM_IMPL order: c_svc, nu_svc, one_class, epsilon_svr, nu_svr.
_EPSILON_SVR = 3


def _gamma(estimator: SVR, X: np.ndarray) -> float:
    """The kernel coefficient ``SVR.fit`` derives from ``gamma`` on its training rows."""
    if estimator.gamma == "scale":
        variance = X.var()
        return 1.0 / (X.shape[1] * variance) if variance != 0 else 1.0
    if estimator.gamma == "auto":
        return 1.0 / X.shape[1]
    return float(estimator.gamma)


def _fit_predict(estimator: SVR, X_train, y_train, X_test) -> np.ndarray:
    gamma = _gamma(estimator, X_train)
    kernel = dict(
        kernel=estimator.kernel,
        degree=estimator.degree,
        coef0=estimator.coef0,
        gamma=gamma,
        cache_size=estimator.cache_size,
    )
    support, vectors, n_support, dual_coef, intercept, prob_a, prob_b, status, _iters = _libsvm.fit(
        X_train,
        y_train,
        svm_type=_EPSILON_SVR,
        sample_weight=np.empty(0),
        class_weight=np.empty(0),
        C=estimator.C,
        nu=estimator.nu,
        probability=False,
        shrinking=estimator.shrinking,
        tol=estimator.tol,
        epsilon=estimator.epsilon,
        max_iter=estimator.max_iter,
        # libsvm reads the seed only for probability estimates, which an SVR never makes.
        random_seed=0,
        **kernel,
    )
    # SVR.fit's own warning and refusal, so a grid point fails here as it would there.
    if status == 1:
        warnings.warn(
            f"Solver terminated early (max_iter={estimator.max_iter}).  Consider "
            "pre-processing your data with StandardScaler or MinMaxScaler.",
            ConvergenceWarning,
            stacklevel=3,
        )
    if not (np.isfinite(intercept).all() and np.isfinite(dual_coef).all()):
        raise ValueError(
            "The dual coefficients or intercepts are not finite. The input data may contain "
            "large values and need to be preprocessed."
        )
    return _libsvm.predict(
        X_test,
        support,
        vectors,
        n_support,
        dual_coef,
        intercept,
        prob_a,
        prob_b,
        svm_type=_EPSILON_SVR,
        **kernel,
    )


def svr_grid_predictions(X_train, y_train, X_test, estimators: Sequence[SVR]) -> list[np.ndarray]:
    """Each unfitted ``SVR`` of ``estimators`` (a grid's points) fitted on
    ``(X_train, y_train)``, predicting ``X_test``; the estimators are left unfitted.

    Their parameters must already be checked (the search checks them once).
    """
    X_train = np.ascontiguousarray(X_train, dtype=np.float64)
    X_test = np.ascontiguousarray(X_test, dtype=np.float64)
    y_train = np.ascontiguousarray(np.ravel(y_train), dtype=np.float64)
    if X_train.shape[0] != y_train.shape[0]:
        raise ValueError(f"{X_train.shape[0]} training rows but {y_train.shape[0]} targets")
    for name, values in (("X", X_train), ("y", y_train), ("X", X_test)):
        if not np.isfinite(values).all():
            # What SVR's input check says; libsvm itself would fit the NaN silently.
            raise ValueError(f"Input {name} contains NaN or infinity.")
    # libsvm's printing is process-wide and on until an SVR turns it off; as SVR.fit does.
    _libsvm.set_verbosity_wrap(0)
    out = []
    for estimator in estimators:
        if callable(estimator.kernel) or estimator.kernel == "precomputed":
            raise ValueError(f"svr_grid_predictions takes a named kernel, got {estimator.kernel!r}")
        out.append(_fit_predict(estimator, X_train, y_train, X_test))
    return out
