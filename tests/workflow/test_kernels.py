"""The workflow's tables on two OpenBLAS kernels agree to the stated precision.

OpenBLAS picks its kernels per CPU; ``OPENBLAS_CORETYPE`` forces one, so one machine can
play two. docs/reports.md ("Byte-identical runs") states the contract this test checks:
across kernels every number of every table agrees within one unit of its last written
digit or ``RTOL`` of the largest magnitude in its column, whichever is larger; every
label, choice and count is equal.

The first kernel's run, of the default recommendation and compensation, also serves the
check that the default deploys the super learner with each fold's own weights (one cold
run fewer in the suite: that check had a run of four tiny runs of its own).
"""

from __future__ import annotations

import json
import math
import platform
import re
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from helpers.builders import write_dataset
from helpers.workflow import run_snakemake, snakemake_env, tiny_config, workflow_workdir

# Measured on the twin (the tables of `make results`, Haswell against SkylakeX): 1e-14 for
# the least-squares fits, 1e-10 for the Gaussian process's optimised hyper-parameters, 5e-8
# for SVR (its solver stops at SVR_TOL). Rounding scales with the operands of a sum, not
# with its result, so a value near 0 is held to its column's largest magnitude.
RTOL = 1e-6
NAME = "kernels"
RUNS = ("R1", "R2", "R3")


def _kernels() -> tuple[str, str] | None:
    """Haswell, and SkylakeX where the CPU has AVX-512 (Sandybridge otherwise); None where
    the CPU cannot run Haswell's kernel (not x86-64 with AVX2)."""
    cpuinfo = Path("/proc/cpuinfo")
    flags = set(re.findall(r"\w+", cpuinfo.read_text())) if cpuinfo.exists() else set()
    if platform.machine() not in ("x86_64", "AMD64") or "avx2" not in flags:
        return None
    return "Haswell", "SkylakeX" if "avx512f" in flags else "Sandybridge"


def _architectures(core: str) -> set[str]:
    """The kernels numpy's and scipy's OpenBLAS libraries load under ``OPENBLAS_CORETYPE``."""
    code = (
        "import json, numpy, scipy.linalg, threadpoolctl; print(json.dumps(sorted({"
        "i['architecture'] for i in threadpoolctl.threadpool_info() "
        "if i['internal_api'] == 'openblas'})))"
    )
    env = {**snakemake_env(), "OPENBLAS_CORETYPE": core}
    proc = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
    )
    return set(json.loads(proc.stdout))


def _curve(r, m, x):
    """A line that bends a little, so no model fits it exactly."""
    return (-10.0 + 0.5 * m + r) * (x - x[0]) / 1000.0 - 0.7 * m + 0.3 * np.sin(m + r + x / 60.0)


def _run(tmp: Path, dataset: Path, core: str | None) -> Path:
    """The workflow's fits and compensation with OpenBLAS's ``core`` kernel (None: the
    one OpenBLAS picks for this CPU)."""
    work = workflow_workdir(tmp)
    # The held-out models (MLR and SVR), the recommendation and the compensation of the
    # model it chooses: every table of the fits, the choice and the controller exports.
    config = tiny_config(work, dataset)
    out = f"results/{NAME}"
    targets = [
        f"{out}/tables/metrics.csv",
        f"{out}/tables/recommendation.csv",
        *(f"{out}/compensation/{t}.csv" for t in ("siemens_840d", "twincat", "residuals")),
        f"{out}/compensation/ThermalCompensation.st",
    ]
    env = snakemake_env() if core is None else {**snakemake_env(), "OPENBLAS_CORETYPE": core}
    run_snakemake(work, *targets, "--configfile", str(config), env=env)
    return work / out


@dataclass(frozen=True)
class Runs:
    dataset: Path
    kernels: tuple[str, str] | None  # None where OpenBLAS's kernels cannot be forced
    first: Path  # results/kernels of the first kernel's run (the CPU's own without kernels)


@pytest.fixture(scope="module")
def runs(tmp_path_factory) -> Runs:
    tmp = tmp_path_factory.mktemp("kernels")
    dataset = write_dataset(
        tmp / NAME,
        runs=RUNS,
        sensors=("S1", "S2", "S3", "S4"),
        curve=_curve,
        name=NAME,
        n_measurements=5,
    )
    kernels = _kernels()
    core = kernels[0] if kernels else None
    return Runs(dataset, kernels, _run(tmp / str(core), dataset, core))


def _last_digit(text: str) -> float:
    """One unit in the last digit ``text`` was written with (``1.25e-05``: 1e-07)."""
    mantissa, _, exponent = text.lower().lstrip("+-").partition("e")
    decimals = len(mantissa.partition(".")[2])
    return 10.0 ** (int(exponent or 0) - decimals)


def _differences(a: pd.DataFrame, b: pd.DataFrame) -> list[str]:
    """Where two readings of one table disagree beyond the stated precision."""
    if list(a.columns) != list(b.columns) or a.shape != b.shape:
        return [f"shape {a.shape} {list(a.columns)} vs {b.shape} {list(b.columns)}"]
    found = []
    for column in a.columns:
        x, y = a[column], b[column]
        numbers = pd.to_numeric(x, errors="coerce"), pd.to_numeric(y, errors="coerce")
        text = numbers[0].isna() | numbers[1].isna()
        if (x[text] != y[text]).any():
            row = int(np.flatnonzero(text & (x != y))[0])
            found.append(f"{column} row {row}: {x[row]!r} vs {y[row]!r}")
            continue
        u, v = (n[~text].to_numpy(dtype=float) for n in numbers)
        if u.size == 0:
            continue
        scale = max(np.abs(u).max(), np.abs(v).max())
        digit = np.maximum([_last_digit(t) for t in x[~text]], [_last_digit(t) for t in y[~text]])
        allowed = np.maximum(digit, RTOL * scale)
        worst = int(np.argmax(np.abs(u - v) - allowed))
        if abs(u[worst] - v[worst]) > allowed[worst]:
            found.append(
                f"{column}: {u[worst]:.17g} vs {v[worst]:.17g} (allowed {allowed[worst]:.3g})"
            )
    return found


def test_tables_agree_across_openblas_kernels(runs, tmp_path, record_property):
    kernels = runs.kernels
    if kernels is None:
        pytest.skip(
            f"OpenBLAS's Haswell kernel needs an x86-64 CPU with AVX2 ({platform.machine()})"
        )
    loaded = {core: _architectures(core) for core in kernels}
    # A kernel OpenBLAS does not load (an unknown name falls back to the CPU's own) would
    # compare a kernel with itself and prove nothing.
    assert all(loaded[core] == {core} for core in kernels), loaded
    record_property("openblas_kernels", " vs ".join(kernels))
    print(f"compared OpenBLAS kernels: {' vs '.join(kernels)}")

    first, second = runs.first, _run(tmp_path / kernels[1], runs.dataset, kernels[1])
    tables = sorted(p.relative_to(first) for p in first.rglob("*.csv"))
    assert tables == sorted(p.relative_to(second) for p in second.rglob("*.csv"))
    assert any(t.parts[0] == "compensation" for t in tables) and len(tables) >= 10, tables
    identical, mismatches = 0, {}
    for table in tables:
        a, b = (
            pd.read_csv(root / table, comment="#", dtype=str, keep_default_na=False)
            for root in (first, second)
        )
        identical += (first / table).read_bytes() == (second / table).read_bytes()
        if found := _differences(a, b):
            mismatches[str(table)] = found
    print(f"{len(tables)} tables, {identical} byte-identical, all within the stated precision")
    assert not mismatches, f"{' vs '.join(kernels)}: {mismatches}"


def test_the_default_deploys_the_super_learner_with_each_folds_weights(runs):
    out = runs.first
    choice = json.loads((out / "recommend" / "choice.json").read_text())
    model = json.loads((out / "compensation" / "model.json").read_text())
    assert (model["approach"], model["deployment"]["candidate"]) == ("combination", "super learner")

    def weights(record):
        return {m["candidate"]: m["weight"] for m in record["members"]}

    def positive(mapping):
        return {m: w for m, w in mapping.items() if w > 0}

    # One linear model with the final weights; each held-out run compensated by its own
    # fold's weights, on members fitted without it.
    assert weights(model) == positive(choice["final"]["weights"])
    assert model["trained_on"] == list(RUNS)
    assert {row["fold"] for row in model["held_out_accuracy"]} == set(RUNS)
    for fold in RUNS:
        fold_model = json.loads((out / "compensation" / "folds" / fold / "model.json").read_text())
        assert weights(fold_model) == positive(choice["folds"][fold])
        assert fold_model["trained_on"] == [r for r in RUNS if r != fold]
    table = pd.read_csv(out / "tables" / "recommendation.csv")
    assert set(table["chosen"]) == {"super learner"}
    for member, weight in choice["folds"]["R2"].items():
        assert table.set_index("fold").loc["R2", f"weight_{member}"] == pytest.approx(
            weight, abs=1e-6
        )


@pytest.mark.parametrize(
    ("text", "unit"),
    [("3.37", 0.01), ("-41.262", 0.001), ("1.25e-05", 1e-07), ("7", 1.0), ("2E+03", 1000.0)],
)
def test_last_digit_is_the_unit_the_number_was_written_in(text, unit):
    assert math.isclose(_last_digit(text), unit, rel_tol=1e-12)
