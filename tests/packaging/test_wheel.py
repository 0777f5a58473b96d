"""The package is self-contained: a wheel of the project, installed non-editable into a
scratch folder and imported from outside the checkout, reads its schemas and the paper's
values from package data.

The wheel is built from a scratch copy of what the build reads (pyproject.toml, the
readme, src/), so the build leaves nothing in the checkout and no stale ``build/`` folder
of an earlier build can fill in a file the package data lists leave out. The installed
copy runs in ``python -I -S``: no PYTHONPATH, no site hooks, so neither the checkout's
``src`` nor the venv's editable install of thermaxis (a ``.pth`` file) can shadow it; the
venv's site-packages are added by hand after the scratch folder, for the dependencies.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
import sysconfig
import textwrap
import tomllib
import zipfile
from fnmatch import fnmatch
from pathlib import Path

import pytest

from helpers import DEFAULTS, REPO
from helpers.builders import hand_model

# Files of src/thermaxis that are not meant to be in the wheel.
NOT_SHIPPED = ("__pycache__", "*.pyc", "*.pyo", "*.egg-info")


def _pip(*args: str, cwd: Path) -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "pip", "--disable-pip-version-check", *args],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, (
        f"pip {args[0]} failed:\n{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}"
    )


def _source_files() -> set[str]:
    """Every file of src/thermaxis the wheel must hold, modules and data, as wheel paths."""
    root = REPO / "src"
    files = set()
    for path in (root / "thermaxis").rglob("*"):
        parts = path.relative_to(root).parts
        if path.is_file() and not any(fnmatch(part, p) for part in parts for p in NOT_SHIPPED):
            files.add("/".join(parts))
    return files


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    tmp = tmp_path_factory.mktemp("wheel")
    project = tmp / "project"
    project.mkdir()
    meta = tomllib.loads((REPO / "pyproject.toml").read_text(encoding="utf-8"))
    readme = meta["project"].get("readme")
    readme = readme.get("file") if isinstance(readme, dict) else readme
    for name in ("pyproject.toml", readme, "setup.cfg", "setup.py", "MANIFEST.in"):
        if name and (REPO / name).is_file():
            shutil.copy2(REPO / name, project / name)
    shutil.copytree(REPO / "src", project / "src", ignore=shutil.ignore_patterns(*NOT_SHIPPED))
    dist = tmp / "dist"
    _pip(
        "wheel",
        "--no-deps",
        "--no-build-isolation",
        "--no-index",
        "-w",
        str(dist),
        ".",
        cwd=project,
    )
    (built,) = dist.glob("thermaxis-*.whl")
    return built


@pytest.fixture(scope="module")
def installed(wheel, tmp_path_factory) -> Path:
    target = tmp_path_factory.mktemp("site")
    _pip("install", "--no-deps", "--no-index", "--target", str(target), str(wheel), cwd=target)
    return target


def test_wheel_holds_every_module_and_data_file(wheel):
    with zipfile.ZipFile(wheel) as archive:
        names = set(archive.namelist())
    missing = sorted(_source_files() - names)
    assert not missing, f"{wheel.name} lacks {len(missing)} file(s) of src/thermaxis: {missing}"
    top = {name.split("/", 1)[0] for name in names}
    assert top == {"thermaxis", wheel.name.split("-py")[0] + ".dist-info"}, top


# Runs in the installed copy; prints one JSON object.
CHILD = textwrap.dedent(
    """
    import json, sys
    sys.path[:0] = json.loads(sys.argv[1])
    record = json.loads(sys.argv[2])

    import thermaxis
    from thermaxis.config import Settings
    from thermaxis.paper.published import load_table, published_values
    from thermaxis.compensation.model import validate_model

    settings = Settings.from_config({})
    table5 = load_table("table5")
    values = published_values()
    validate_model(record)
    broken = {key: value for key, value in record.items() if key != "fallback"}
    try:
        validate_model(broken)
        refused = None
    except ValueError as exc:
        refused = str(exc)
    files = sorted({m.__file__ for m in list(sys.modules.values())
                    if m.__name__.split(".")[0] == "thermaxis" and getattr(m, "__file__", None)})
    print(json.dumps({
        "file": thermaxis.__file__,
        "module_files": files,
        "sys_path": sys.path,
        "settings": repr(settings),
        "table5_rows": len(table5),
        "values": values.to_csv(index=False),
        "refused": refused,
    }))
    """
)


@pytest.fixture(scope="module")
def child(installed, tmp_path_factory) -> dict:
    """What the installed copy reads, run from a folder outside the checkout."""
    outside = tmp_path_factory.mktemp("outside")
    paths = [str(installed)] + list(
        dict.fromkeys(sysconfig.get_paths()[k] for k in ("purelib", "platlib"))
    )
    proc = subprocess.run(
        [sys.executable, "-I", "-S", "-c", CHILD, json.dumps(paths), json.dumps(hand_model())],
        cwd=outside,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr[-5000:]
    return json.loads(proc.stdout)


def test_installed_copy_is_the_one_imported(child, installed):
    assert Path(child["file"]).is_relative_to(installed), child["file"]
    strays = [f for f in child["module_files"] if not Path(f).is_relative_to(installed)]
    assert not strays, strays
    # The checkout itself and its src/ (the venv may live inside the checkout: .venv).
    source = REPO / "src"
    checkout = [
        p
        for p in child["sys_path"]
        if Path(p).resolve() == REPO or Path(p).resolve().is_relative_to(source)
    ]
    assert not checkout, checkout
    assert "" not in child["sys_path"]  # no current folder either


def test_settings_from_an_empty_config_use_the_packaged_schema(child):
    assert child["settings"] == repr(DEFAULTS)


def test_paper_values_are_packaged(child):
    from thermaxis.paper.published import published_values

    # Table 5 lists k and b for 4 experiments x 8 measurements.
    assert child["table5_rows"] == 32
    assert child["values"] == published_values().to_csv(index=False)


def test_model_schema_is_packaged(child):
    assert child["refused"] is not None and "fallback" in child["refused"], child["refused"]


# The installed console script, run as the installed copy sees it (its package first on the path).
SCRIPT = textwrap.dedent(
    """
    import json, runpy, sys
    sys.path[:0] = json.loads(sys.argv[1])
    script, sys.argv = sys.argv[2], [sys.argv[2], *sys.argv[3:]]
    runpy.run_path(script, run_name="__main__")
    """
)
SUBCOMMANDS = ("run", "check", "import", "compensate", "sweep", "report")


def test_the_wheel_declares_the_thermaxis_command(wheel):
    with zipfile.ZipFile(wheel) as archive:
        (entry_points,) = [n for n in archive.namelist() if n.endswith("entry_points.txt")]
        text = archive.read(entry_points).decode()
    assert "[console_scripts]" in text and "thermaxis = thermaxis.cli:main" in text


@pytest.mark.parametrize("subcommand", ("", *SUBCOMMANDS))
def test_the_installed_command_and_each_subcommand_have_help(subcommand, installed, tmp_path):
    script = installed / "bin" / "thermaxis"
    assert script.is_file(), f"pip installed no console script into {installed / 'bin'}"
    paths = [str(installed)] + list(
        dict.fromkeys(sysconfig.get_paths()[k] for k in ("purelib", "platlib"))
    )
    proc = subprocess.run(
        [sys.executable, "-I", "-S", "-c", SCRIPT, json.dumps(paths), str(script),
         *([subcommand] if subcommand else []), "--help"],
        cwd=tmp_path, capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr[-3000:]
    usage = f"usage: thermaxis {subcommand}".rstrip()
    assert proc.stdout.startswith(usage) and "examples:" in proc.stdout, proc.stdout[:500]
    if not subcommand:
        assert all(name in proc.stdout for name in SUBCOMMANDS)
