"""The Slurm executor plugin lives only in envs/requirements-slurm.txt (.venv-slurm), not
in the main environment: Snakemake imports every installed executor plugin at each start,
and plugin 2.8.0 then waits up to 10 s for an absent Slurm controller
(docs/slurm-plugin-startup.md). No cluster needed: these run everywhere.
"""

from __future__ import annotations

import pkgutil
import re

from packaging.utils import canonicalize_name

from helpers import REPO

ENVS = REPO / "envs"
PLUGIN_PREFIX = "snakemake_executor_plugin_"


def _pins(name: str) -> dict[str, str]:
    pins = {}
    for line in (ENVS / name).read_text().splitlines():
        line = line.split("#", 1)[0].strip()
        if line:
            package, version = re.fullmatch(r"([A-Za-z0-9_.\-]+)==(\S+)", line).groups()
            pins[canonicalize_name(package)] = version
    return pins


def test_the_main_pins_have_no_executor_plugin_and_the_slurm_pins_add_only_the_plugin():
    main, slurm = _pins("requirements.txt"), _pins("requirements-slurm.txt")
    assert [p for p in main if p.startswith("snakemake-executor-plugin-")] == []
    assert set(slurm) == {
        "snakemake-executor-plugin-slurm",
        "snakemake-executor-plugin-slurm-jobstep",
    }
    assert set(main) & set(slurm) == set()  # installed together: one pin per package


def test_the_conda_environment_takes_the_main_pins_only():
    text = (ENVS / "thermaxis.yaml").read_text()
    assert "-r requirements.txt" in text
    assert "requirements-slurm" not in text.split("dependencies:", 1)[1]


def test_this_environment_has_no_executor_plugin_for_snakemake_to_import():
    found = sorted(m.name for m in pkgutil.iter_modules() if m.name.startswith(PLUGIN_PREFIX))
    assert found == [], (
        f"executor plugins in the main environment (belong in envs/requirements-slurm.txt): {found}"
    )
