"""Benchmarks of the workflow (``make bench``): wall time, CPU time and peak memory.

``python -m tools.bench --out results/bench`` measures, each in a scratch work
folder (symlinks to the repository's Snakefile, config, workflow, notebooks and data,
so the repository's own ``results/`` are never touched):

* ``results_cold``: ``snakemake --cores N`` from nothing (the set-up, i.e. the
  virtual environment, already exists), the same as ``make results``;
* ``results_noop``: the same command again, with nothing to do;
* ``results_model_param``: after changing one model parameter (``models.ridge_alpha``);
* ``sweep_default``: ``snakemake sweep`` with the default grid (the assembled data exist);
* ``scale_<shape>_<n>``: the default configuration (every algorithm, every run held out
  once) end to end, every figure and report included, on twin-generated datasets of n runs shaped like a
  measured record (``python -m thermaxis.twin scale``: 24 sensors logged every 10 s,
  about 30 measurements per run, one every 10 min), with ONE target position
  (``one_position``) and, separately, 14 (``positions_14``).  Generating a dataset is
  timed separately (``scale_generate_<shape>_<n>``) and is not part of the fit;
* ``test_suite``: ``python -m pytest`` in the repository, as ``make test`` runs it once
  the environment exists;
* ``subsets``: the sweep's exhaustive search of every 3 of 22 sensors (1,540 subsets) on a
  generated dataset of 5 runs with one target position, point by point with MLR, every run
  held out once;
* ``records_<name>``: the recommendation of every embedded dataset and of the public
  FL_THERMAL record's channels 1-5 (:mod:`tools.bench.records`), with its mean held-out
  RMSE beside the plain nested ridge baseline's and the paper's configuration's;
* ``startup``: ``snakemake --version`` and the one-rule no-op in ``.venv`` and, when
  ``make slurm-env`` has made it, in ``.venv-slurm`` (the Slurm executor plugin
  installed; on a machine with the Slurm client and no controller its import waits for
  one, docs/slurm-plugin-startup.md);
* ``dryrun_twin`` beside ``dryrun_one_rule``: ``snakemake -n`` of the twin in an empty
  work folder (every job planned, nothing run: what parsing the workflow and building its
  DAG cost, which every Snakemake start pays, each Slurm job included) and of a one-rule
  workflow (the floor: Snakemake's own start-up); the best of three each (``--repeats``).

Each command runs in its own process group.  Wall time is measured around it; CPU time
(user + system) and the largest single process's peak RSS come from ``os.wait4``, which
reports the whole process tree once it has been reaped; the peak RSS of the tree (all
processes alive at the same time, summed) is sampled with psutil every 0.2 s when psutil
is installed.  Results: ``bench.json`` and ``bench.md`` in ``--out``.  The figures are
what this machine measured; the targets of the project are shown beside them, never
asserted.

The package, by concern: :mod:`~tools.bench.measure` (one timed command),
:mod:`~tools.bench.scaling` (growth with the number of runs), :mod:`~tools.bench.steps`
(what is measured), :mod:`~tools.bench.records` (the recommendation against the plain
baseline), :mod:`~tools.bench.report` (bench.json and bench.md) and
:mod:`~tools.bench.cli`.
"""

from tools.bench.cli import main
from tools.bench.measure import Measurement, measure
from tools.bench.report import bench_markdown, finish, render
from tools.bench.scaling import ScaleFit, fit_scaling
from tools.bench.steps import prepare_workdir, run_bench

__all__ = [
    "Measurement",
    "ScaleFit",
    "measure",
    "fit_scaling",
    "prepare_workdir",
    "run_bench",
    "finish",
    "render",
    "bench_markdown",
    "main",
]
