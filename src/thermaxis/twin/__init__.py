"""Calibrated thermal twin of the paper's X axis: the embedded default dataset.

``python -m thermaxis.twin generate`` writes ``data/raw/twin`` (and the ground truth)
from the committed ``twin_params.json``; ``calibrate`` refits those parameters to the
paper's published fits (Table 5, Eq. 8, Eq. 9) and results (Tables 3, 4, 6, 7, 8);
``scale`` writes large benchmark datasets.  Modules:

* :mod:`~thermaxis.twin.network` -- the lumped thermal network and its exact integration;
* :mod:`~thermaxis.twin.conditions` -- the four experiments, timelines, workshop air;
* :mod:`~thermaxis.twin.model` -- free parameters, heat inputs, the error model;
* :mod:`~thermaxis.twin.observe` -- sensors and interferometer;
* :mod:`~thermaxis.twin.faults` -- the real-log faults seeded into the raw files;
* :mod:`~thermaxis.twin.results` -- the paper's results as calibration margins;
* :mod:`~thermaxis.twin.problem` -- the forward problem and the published targets;
* :mod:`~thermaxis.twin.stages`, :mod:`~thermaxis.twin.solver` -- the staged calibration
  (published fits, then results) and its least squares;
* :mod:`~thermaxis.twin.calibration` -- that calibration through the pipeline;
* :mod:`~thermaxis.twin.generate`, :mod:`~thermaxis.twin.documents` -- files and documents;
* :mod:`~thermaxis.twin.report` -- the calibration report;
* :mod:`~thermaxis.twin.scale` -- benchmark datasets.
"""

from .calibration import calibrate
from .generate import generate_dataset
from .model import TwinParams, load_params, save_params
from .report import pipeline_view
from .scale import ScaleSpec, generate_scale
from .solver import FitResult

__all__ = [
    "FitResult",
    "calibrate",
    "generate_dataset",
    "TwinParams",
    "load_params",
    "save_params",
    "pipeline_view",
    "ScaleSpec",
    "generate_scale",
]
