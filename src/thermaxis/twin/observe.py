"""What the instruments see: the 12 temperature sensors and the laser interferometer.

Sensors are NOT the network's nodes: each PT100 sits on a surface that mixes a node
with its neighbour or the air, reads it through its own first-order lag (magnetic
mount, air boundary layer) and adds a calibration offset (class B tolerance) and noise.
The interferometer reads the positioning error of :mod:`thermaxis.twin.model` relative
to its datum, with reversal error, per-reading noise and a per-measurement scale error
of the XL-80 class (+-0.5 um/m: air-compensation error).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.signal import lfilter

from . import conditions as cond
from .model import MOUNTING_DESIGN, RunState, mounting, positioning_error
from .network import NODES

__all__ = [
    "Sensor",
    "SENSORS",
    "calibrated_sensors",
    "SOURCES",
    "sensor_signal",
    "lagged",
    "INTERFEROMETER",
    "Readings",
    "interferometer_readings",
]


@dataclass(frozen=True)
class Sensor:
    """One PT100 of the paper's Table 2 and how it couples to the network."""

    id: str
    location: str
    source: str
    weights: dict[str, float]  # node (or "ambient") -> weight, summing to 1
    lag_s: float  # first-order time constant of the mounted sensor
    offset_c: float  # calibration offset (PT100 class B: +-0.3 degC at 0 degC)
    noise_c: float  # white noise of the acquisition chain (1 sigma)


def _designed(sensor_id: str, location: str, source: str, lag_s: float, noise_c: float) -> Sensor:
    weights, offset = MOUNTING_DESIGN[sensor_id]
    return Sensor(sensor_id, location, source, weights, lag_s, offset, noise_c)


SENSORS: tuple[Sensor, ...] = (
    # Every mounting is calibrated (model.MOUNTING_SURFACES): these entries hold the design
    # estimate, calibrated_sensors() the fitted one.  Lags: the sleeve's covers are thin
    # sheet on an air gap; the HMI reads the motor's own winding sensor, fast but coarse.
    _designed("T1", "screw sleeve, left", "box", 90.0, 0.008),
    _designed("T2", "screw sleeve, right", "box", 90.0, 0.008),
    _designed("T3", "screw sleeve, front", "box", 90.0, 0.008),
    _designed("T4", "left slider", "box", 60.0, 0.008),
    _designed("T5", "right slider", "box", 60.0, 0.008),
    _designed("T6", "bearing seat near motor", "box", 60.0, 0.008),
    _designed("T7", "motor shell, top", "box", 60.0, 0.008),
    _designed("T8", "bed, inner side", "box", 60.0, 0.008),
    _designed("T9", "bed, outer side", "box", 60.0, 0.008),
    _designed("T10", "ambient", "box", 120.0, 0.010),
    _designed("T11", "nut", "wireless", 45.0, 0.030),
    _designed("T12", "motor (internal)", "hmi", 20.0, 0.040),
)


def calibrated_sensors(values: dict[str, float]) -> tuple[Sensor, ...]:
    """The sensors with the fitted mountings and offsets of ``values`` in place of the design."""
    return tuple(
        replace(sensor, weights=weights, offset_c=offset)
        for sensor in SENSORS
        for weights, offset in [mounting(values, sensor.id)]
    )


#: The HMI's clock runs this many seconds behind the box (reference) clock.
HMI_CLOCK_OFFSET_S = 7.0
#: Acquisition sources: (name, clock note, clock offset in s to ADD to reach the box clock).
SOURCES: tuple[tuple[str, str, float], ...] = (
    ("box", "reference clock (acquisition box, synchronised with the interferometer PC)", 0.0),
    ("wireless", "gateway clock, synchronised with the box; irregular ~30 s packets", 0.0),
    (
        "hmi",
        f"CNC HMI clock, runs {HMI_CLOCK_OFFSET_S:g} s behind the box clock",
        HMI_CLOCK_OFFSET_S,
    ),
)
#: Wireless packets: nominal period and uniform jitter (s); HMI polling period (s).
WIRELESS_PERIOD_S = 30.0
WIRELESS_JITTER_S = 4.0
HMI_PERIOD_S = 60.0


def sensor_signal(sensor: Sensor, state: RunState) -> np.ndarray:
    """The temperature at the sensor's mounting surface on the run grid (no lag)."""
    out = np.zeros(state.grid_s.size)
    for name, w in sensor.weights.items():
        out += w * (state.ambient if name == "ambient" else state.nodes[:, NODES.index(name)])
    return out


def lagged(signal: np.ndarray, step_s: float, lag_s: float) -> np.ndarray:
    """Exact first-order lag of a piecewise-linear signal sampled every ``step_s`` (along axis 0).

    Starts in equilibrium with the first sample (the sensors were mounted long before).
    """
    a = np.exp(-step_s / lag_s)
    # y[n] = a y[n-1] + c0 x[n-1] + c1 x[n]: ramp-invariant discretisation.
    c1 = 1.0 - lag_s / step_s * (1.0 - a)
    c0 = (1.0 - a) - c1
    y = np.empty_like(signal)
    y[0] = signal[0]
    rest, _ = lfilter([c1, c0], [1.0, -a], signal[1:], axis=0, zi=((a + c0) * signal[0])[None])
    y[1:] = rest
    return y


@dataclass(frozen=True)
class InterferometerSpec:
    """Error-side instrument constants (documented, not calibrated)."""

    reading_noise_um: float = 0.03  # repeatability of one capture (vibration, dead path)
    # Per-measurement air-compensation error, 1 sigma, clipped at the XL-80 class bound.
    scale_error_um_per_m: float = 0.07
    scale_error_limit_um_per_m: float = 0.5
    reversal_um: float = -0.1  # lost motion of the preloaded nut: the backward pass reads lower


INTERFEROMETER = InterferometerSpec()


@dataclass(frozen=True)
class Readings:
    """One measurement's captures: forward then backward pass."""

    time_s: np.ndarray
    position_mm: np.ndarray
    direction: np.ndarray  # "+" or "-"
    error_um: np.ndarray  # as read (datum, reversal, noise)
    true_um: np.ndarray  # noise-free, reversal-free, relative to the same datum


def interferometer_readings(
    values: dict[str, float],
    state: RunState,
    start_s: float,
    datum_um: float,
    rng: np.random.Generator,
) -> Readings:
    """The 28 captures of one measurement starting at ``start_s``.

    ``datum_um`` is the error E(185, t_zero) the interferometer was zeroed at.
    """
    spec = INTERFEROMETER
    forward_t, backward_t = cond.reading_times(start_s)
    x = np.concatenate([cond.TARGETS_MM, cond.TARGETS_MM[::-1]])
    t = np.concatenate([forward_t, backward_t])
    direction = np.array(["+"] * forward_t.size + ["-"] * backward_t.size)
    true = positioning_error(values, state, x, t) - datum_um
    scale = float(
        np.clip(
            rng.normal(0.0, spec.scale_error_um_per_m),
            -spec.scale_error_limit_um_per_m,
            spec.scale_error_limit_um_per_m,
        )
    )
    noise = rng.normal(0.0, spec.reading_noise_um, x.size)
    read = (
        true
        + scale * (x - cond.FIRST_TARGET_MM) / 1000.0
        + noise
        + np.where(direction == "-", spec.reversal_um, 0.0)
    )
    return Readings(time_s=t, position_mm=x, direction=direction, error_um=read, true_um=true)
