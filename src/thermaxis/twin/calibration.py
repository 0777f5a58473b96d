"""``make twin-calibrate``: the staged calibration of :mod:`thermaxis.twin.solver`, through the pipeline.

The later stages correct the noise-free model towards what the pipeline's own cleaning,
assembly and decoupling make of the twin's raw files; this module writes those files
and runs the pipeline on them, so that the fit itself needs neither.
"""

from __future__ import annotations

import tempfile
import warnings
from pathlib import Path

import pandas as pd

from . import conditions as cond
from . import model as mdl
from . import solver
from .generate import simulate_records, write_runs
from .polish import polish
from .problem import RunObservables
from .report import PipelineView, faithfulness_table, pipeline_view

__all__ = ["pipeline_observables", "faithfulness_of", "calibrate"]


def _pipeline_view_of(params: mdl.TwinParams) -> PipelineView:
    """The pipeline's view of the raw files of ``params`` (noise, faults, clocks and all),
    written to a temporary folder and cleaned, assembled and decoupled by its own code."""
    with tempfile.TemporaryDirectory(prefix="thermaxis-twin-") as tmp, warnings.catch_warnings():
        # The pipeline's notes on the seeded faults are the dataset's, reported by the workflow.
        warnings.simplefilter("ignore")
        write_runs(Path(tmp), simulate_records(params))
        return pipeline_view(Path(tmp))


def pipeline_observables(params: mdl.TwinParams) -> dict[str, RunObservables]:
    """What the pipeline makes of the twin's raw files: k, b, curves and window means."""
    return _pipeline_view_of(params).observables()


def faithfulness_of(params: mdl.TwinParams) -> pd.DataFrame:
    """The workflow's faithfulness table, with margins, of the twin's raw files of ``params``."""
    return faithfulness_table(_pipeline_view_of(params), margins=True)


def calibrate(
    step_s: float = cond.STEP_S,
    workers: int = 2,
    resume: tuple[mdl.TwinParams, str] | None = None,
) -> solver.FitResult:
    """The staged fit (:data:`thermaxis.twin.stages.STAGES`) with the pipeline's correction,
    then the compass search on the faithfulness table (:mod:`thermaxis.twin.polish`)."""
    return solver.calibrate(
        pipeline_observables,
        step_s,
        workers,
        resume,
        polish=lambda params: polish(params, faithfulness_of, workers),
    )
