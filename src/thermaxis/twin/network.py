"""The lumped thermal network of the X axis and its exact integration.

Eight nodes exchange heat with each other and with the workshop air (a boundary, not
a state).  With piecewise-constant inputs on a fixed step the linear system
``C dT/dt = -L T + g_a T_a + q`` integrates exactly through one matrix exponential
(zero-order hold), which makes a three-hour run a few thousand matrix-vector products.

Capacities and conductances are documented estimates (order of magnitude from the
parts' masses and convective areas); the calibration multiplies
some of them by bounded factors (:mod:`thermaxis.twin.model`), beside the heat inputs, the
expansion/drift gains, the sensor mountings and the initial temperatures.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import expm

__all__ = [
    "NODES",
    "CAPACITY_J_PER_K",
    "CONDUCTANCE_W_PER_K",
    "Discretised",
    "capacities",
    "conductances",
    "discretise",
    "simulate",
]

#: State nodes.  ``screw_core`` is the hidden driver of the expansion: no sensor sees it.
NODES: tuple[str, ...] = (
    "screw_core",
    "nut",
    "bearing_seat",
    "sliders",
    "motor",
    "bed_inner",
    "bed_outer",
    "sleeve",
)

#: Heat capacities [J/K] (steel/cast iron, c = 460 J/kg/K).  Several are EFFECTIVE
#: capacities: a lumped node also stands for the mass that shares its temperature, so
#: its value is larger than the bare part's.  The calibration multiplies some of them
#: by a fitted factor (``log_capacity_<node>`` in :mod:`thermaxis.twin.model`).
CAPACITY_J_PER_K: dict[str, float] = {
    # Mean temperature over the threaded length of a dia. 40 mm screw (bare: 16 kg,
    # 7 kJ/K) with the nut bracket and support ends that follow it; heat spreads along
    # the screw slowly, which is what makes its mean temperature slow.
    "screw_core": 6.5e4,
    "nut": 1.6e3,  # nut and flange, ~3.5 kg
    "bearing_seat": 3.9e4,  # fixed-end housing with the bed's end block it is bolted to
    "sliders": 1.5e4,  # four carriages and the table skirt above them, ~30 kg
    "motor": 2.6e4,  # servo motor with its flange, ~55 kg
    "bed_inner": 6.0e5,  # the bed's core around the guideways, ~1.3 t
    "bed_outer": 1.0e5,  # the bed's outer walls (the skin that follows the air), ~0.2 t
    "sleeve": 3.0e3,  # telescopic screw sleeve (cover), ~6 kg
}

#: Thermal conductances [W/K]; ``ambient`` is the workshop air.
CONDUCTANCE_W_PER_K: dict[tuple[str, str], float] = {
    ("screw_core", "nut"): 1.0,  # through the balls, only along the nut's short stroke
    ("screw_core", "bearing_seat"): 0.6,  # along the screw shank into the fixed end
    ("screw_core", "sleeve"): 1.5,  # radiation and still air under the close-fitting cover
    ("screw_core", "ambient"): 0.3,  # the covered screw barely sees the air
    ("nut", "sliders"): 2.0,  # through the table
    ("nut", "ambient"): 0.8,
    ("bearing_seat", "motor"): 2.5,  # motor flange and coupling
    ("bearing_seat", "bed_inner"): 4.0,  # bolted joint
    ("bearing_seat", "ambient"): 1.0,
    ("sliders", "bed_inner"): 3.0,  # guideway contact
    ("sliders", "ambient"): 1.5,
    ("motor", "ambient"): 4.0,  # fan-less motor, natural convection + radiation
    ("bed_inner", "bed_outer"): 20.0,
    ("bed_inner", "ambient"): 5.0,  # through chip channels and openings
    ("bed_outer", "ambient"): 40.0,  # large painted walls
    ("sleeve", "bed_inner"): 1.0,
    ("sleeve", "ambient"): 1.0,  # the sleeve's outer face, sheltered under the table
}


@dataclass(frozen=True)
class Discretised:
    """Exact zero-order-hold step ``T[n+1] = Ad T[n] + Bd u[n]``.

    ``u = [T_ambient, q_node_1, ..., q_node_n]`` (degC, then W per node).
    """

    step_s: float
    Ad: np.ndarray
    Bd: np.ndarray


def _continuous(
    capacity: dict[str, float], conductance: dict[tuple[str, str], float]
) -> tuple[np.ndarray, np.ndarray]:
    n = len(NODES)
    index = {name: i for i, name in enumerate(NODES)}
    laplacian = np.zeros((n, n))
    to_ambient = np.zeros(n)
    for (a, b), g in conductance.items():
        if b == "ambient":
            laplacian[index[a], index[a]] += g
            to_ambient[index[a]] += g
            continue
        i, j = index[a], index[b]
        laplacian[i, i] += g
        laplacian[j, j] += g
        laplacian[i, j] -= g
        laplacian[j, i] -= g
    inv_c = 1.0 / np.array([capacity[name] for name in NODES])
    A = -inv_c[:, None] * laplacian
    B = np.column_stack([inv_c * to_ambient, np.diag(inv_c)])
    return A, B


def capacities(scale: dict[str, float] | None = None) -> dict[str, float]:
    """Heat capacities with calibrated multiplicative factors applied."""
    scale = scale or {}
    unknown = set(scale) - set(NODES)
    if unknown:
        raise ValueError(
            f"capacity scale for unknown node(s) {sorted(unknown)}; expected some of {NODES}"
        )
    return {name: CAPACITY_J_PER_K[name] * scale.get(name, 1.0) for name in NODES}


def conductances(
    scale: dict[tuple[str, str], float] | None = None,
) -> dict[tuple[str, str], float]:
    """Conductances with calibrated multiplicative factors applied."""
    scale = scale or {}
    unknown = set(scale) - set(CONDUCTANCE_W_PER_K)
    if unknown:
        raise ValueError(
            f"conductance scale for unknown link(s) {sorted(unknown)}; expected links of CONDUCTANCE_W_PER_K"
        )
    return {link: g * scale.get(link, 1.0) for link, g in CONDUCTANCE_W_PER_K.items()}


def discretise(
    step_s: float,
    capacity_scale: dict[str, float] | None = None,
    conductance_scale: dict[tuple[str, str], float] | None = None,
) -> Discretised:
    """Exact discretisation of the network for a fixed step (seconds).

    ``capacity_scale`` and ``conductance_scale`` multiply the documented capacities of
    some nodes and conductances of some links (the calibrated ones, see
    :mod:`thermaxis.twin.model`).
    """
    if not step_s > 0:
        raise ValueError(f"step_s must be positive, got {step_s}")
    A, B = _continuous(capacities(capacity_scale), conductances(conductance_scale))
    n, m = B.shape
    block = np.zeros((n + m, n + m))
    block[:n, :n] = A * step_s
    block[:n, n:] = B * step_s
    exp_block = expm(block)
    return Discretised(step_s=step_s, Ad=exp_block[:n, :n], Bd=exp_block[:n, n:])


def simulate(disc: Discretised, initial: np.ndarray, inputs: np.ndarray) -> np.ndarray:
    """Node temperatures at the step boundaries.

    Parameters
    ----------
    disc
        The discretised network.
    initial
        Node temperatures at the first boundary, shape (n_nodes,).
    inputs
        Step inputs, shape (n_steps, 1 + n_nodes): ambient (mean over the step) and
        heat per node (mean over the step, W).

    Returns
    -------
    numpy.ndarray
        Shape (n_steps + 1, n_nodes).
    """
    forced = inputs @ disc.Bd.T
    out = np.empty((inputs.shape[0] + 1, disc.Ad.shape[0]))
    out[0] = initial
    Ad = disc.Ad
    state = np.asarray(initial, dtype=float)
    for i in range(inputs.shape[0]):
        state = Ad @ state + forced[i]
        out[i + 1] = state
    return out
