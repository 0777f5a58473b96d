"""The targets `make help` lists beside `make results` and `make test`, each run as the
Makefile spells it (issue 62: `make sweep` failed at once, and no test ran it).

``make -f <checkout>/Makefile`` runs in a scratch folder holding what the target reads
(symlinks into the checkout), with the test's interpreter (``VENV``; ``-o env``: the
environment is not rebuilt), so nothing in the checkout changes. `make results`, `report`,
`sweep` and `clean` share one cold run in test_make_results.py; `make help` is
test_makefile.py's; `make slurm-env` is tests/slurm's; `make env` and `make test` are what
`.ci/run` runs.
"""

from __future__ import annotations

import json
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from helpers import REPO
from helpers.workflow import snakemake_env

pytestmark = pytest.mark.skipif(shutil.which("make") is None, reason="make is not installed")

VENV = Path(sys.executable).parent.parent


def _scratch(root: Path, *names: str) -> Path:
    """A folder with the checkout's ``names`` (paths relative to it) as symlinks."""
    for name in names:
        (root / name).parent.mkdir(parents=True, exist_ok=True)
        (root / name).symlink_to(REPO / name)
    return root


def _make(target: str, cwd: Path, *variables: str, timeout=600) -> subprocess.CompletedProcess:
    proc = subprocess.run(
        ["make", "-f", str(REPO / "Makefile"), "-o", "env", target, f"VENV={VENV}", *variables],
        cwd=cwd, capture_output=True, text=True, env=snakemake_env(), timeout=timeout,
    )  # fmt: skip
    assert proc.returncode == 0, f"make {target}:\n{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}"
    return proc


def _files(root: Path) -> dict[str, bytes]:
    return {
        p.relative_to(root).as_posix(): p.read_bytes()
        for p in sorted(root.rglob("*"))
        if p.is_file()
    }


def test_make_import_rewrites_the_committed_dataset_byte_for_byte(tmp_path):
    """From the record in data/sources: `git status` stays clean after `make import`."""
    work = _scratch(tmp_path, "data/import", "data/sources")
    proc = _make("import", work)
    assert "fl_thermal: 6 runs in data/raw/fl_thermal" in proc.stdout
    want, got = _files(REPO / "data/raw/fl_thermal"), _files(work / "data/raw/fl_thermal")
    assert sorted(got) == sorted(want)
    assert [name for name in want if want[name] != got[name]] == []
    # The licence travels with the data.
    assert got["LICENSE"] == (REPO / "data/sources/fl_thermal/LICENSE").read_bytes()


def test_make_twin_regenerates_the_committed_twin(tmp_path):
    work = _scratch(tmp_path, "config")
    _make("twin", work)
    for folder in ("data/raw/twin", "data/twin_truth"):
        want, got = _files(REPO / folder), _files(work / folder)
        assert sorted(got) == sorted(want), folder
        # The calibration report prints numbers a last digit may change on another CPU's
        # kernels (test_twin.py checks it to its printed precision); the data are exact.
        changed = [n for n in want if want[n] != got[n] and n != "CALIBRATION.md"]
        assert changed == [], f"{folder}: {changed[:5]}"


def test_make_fmt_formats_the_rule_files_and_leaves_formatted_ones_alone(tmp_path):
    shutil.copy(REPO / "Snakefile", tmp_path / "Snakefile")
    shutil.copytree(REPO / "workflow" / "rules", tmp_path / "workflow" / "rules")
    before = _files(tmp_path)
    # A rule as someone might type it: single quotes, directives on one line each, no blank lines.
    extra = tmp_path / "workflow" / "rules" / "extra.smk"
    typed = (
        "rule extra:\n    input: 'a.txt'\n    output: 'b.txt'\n    shell: 'cp {input} {output}'\n"
    )
    extra.write_text(typed)
    _make("fmt", tmp_path)
    after = _files(tmp_path)
    assert {n: after[n] for n in before} == before  # committed files are formatted already
    formatted = extra.read_text()
    assert formatted != typed and '"a.txt"' in formatted and "'a.txt'" not in formatted
    check = subprocess.run(
        [str(VENV / "bin" / "snakefmt"), "--check", str(extra)], capture_output=True, text=True
    )
    assert check.returncode == 0, check.stderr


def test_make_lint_passes():
    """ruff over src, tools, workflow/scripts and tests; snakemake --lint; snakefmt --check."""
    proc = _make("lint", REPO)
    out = proc.stdout + proc.stderr
    assert "Congratulations, your workflow is in a good condition!" in out, out
    assert "All checks passed!" in out, out


def test_make_bench_measures_a_small_step(tmp_path):
    """The dry-run step: the twin's plan and the one-rule floor, best of two each here
    (``--repeats``; three by default), and their target line in bench.md. (The startup
    step would also time .venv-slurm, whose executor plugin waits about 10 s a start for
    an absent Slurm controller.)"""
    out = tmp_path / "bench"
    args = f"--steps dryrun --out {out} --workdir {tmp_path / 'work'} --cores 1 --repeats 2"
    _make("bench", REPO, f"BENCH_ARGS={args}")
    doc = json.loads((out / "bench.json").read_text())
    by_name = {m["name"]: m for m in doc["measurements"]}
    assert sorted(by_name) == ["dryrun_one_rule", "dryrun_twin"]
    assert all(m["ok"] and m["wall_s"] > 0 and m["cpu_s"] > 0 for m in by_name.values())
    report = (out / "bench.md").read_text()
    assert "dry run of the twin <= the one-rule dry run + 2 s CPU" in report
    # The step's logs: two runs of each command, the twin's a plan of the whole workflow.
    logs = sorted(p.name for p in (out / "logs").iterdir())
    assert logs == [f"{n}_{i}.log" for n in ("dryrun_one_rule", "dryrun_twin") for i in range(2)]
    assert "This was a dry-run" in (out / "logs" / "dryrun_twin_0.log").read_text()


@pytest.mark.parametrize("target", ["twin-calibrate", "twin-conflicts"])
def test_the_twin_fits_start_as_spelled(target):
    """Hours of optimisation each: the recipe's command line is checked against the
    twin's own parser (`make -n`), and its files exist; a real run is `make bench`'s
    twin_calibrate step."""
    from thermaxis.twin.__main__ import _parser

    proc = _make(target, REPO, "-n")
    (line,) = [line for line in proc.stdout.splitlines() if "thermaxis.twin" in line]
    words = shlex.split(line)
    args = _parser().parse_args(words[words.index("thermaxis.twin") + 1 :])
    for path in (getattr(args, "resume", None), getattr(args, "params", None)):
        if path is not None:
            assert (REPO / path).is_file(), path
