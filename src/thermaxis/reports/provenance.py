"""Provenance of a result: which code, configuration, data and software made it.

:func:`collect` gathers one record (a plain, JSON-ready dict):

``git``
    commit of the repository and whether its tracked files had uncommitted changes;
``config`` / ``config_sha256`` / ``config_sections_sha256``
    the effective configuration, the SHA-256 of its canonical JSON, and one hash per
    top-level section so a report that depends on a few sections can be matched
    against the full record;
``data``
    the dataset root, the SHA-256 of every file below it (the manifest) and one hash
    of the whole manifest;
``packages`` / ``python`` / ``platform``
    versions of the scientific stack, the interpreter and the machine;
``run_time``
    when the record was made, in UTC -- the only field that differs between two runs
    on the same inputs.  ``SOURCE_DATE_EPOCH`` (the reproducible-builds convention)
    fixes it, so two builds can be compared byte for byte.
"""

from __future__ import annotations

import hashlib
import json
import os
import platform
import subprocess
import sys
from datetime import UTC, datetime
from importlib import metadata
from pathlib import Path

__all__ = [
    "PACKAGES",
    "REQUIRED_KEYS",
    "sha256_file",
    "data_manifest",
    "manifest_sha256",
    "manifest_text",
    "config_sha256",
    "config_sections_sha256",
    "git_state",
    "package_versions",
    "run_time",
    "collect",
    "to_json",
]

# The packages whose versions can change a number, a figure or a report.
PACKAGES = (
    "thermaxis",
    "numpy",
    "pandas",
    "scipy",
    "scikit-learn",
    "matplotlib",
    "pyarrow",
    "pyyaml",
    "jsonschema",
    "snakemake",
    "papermill",
    "nbconvert",
    "ipykernel",
)

REQUIRED_KEYS = (
    "config",
    "config_sha256",
    "config_sections_sha256",
    "data",
    "git",
    "packages",
    "platform",
    "python",
    "run_time",
)

_CHUNK = 1 << 20


def sha256_file(path) -> str:
    """SHA-256 of a file's bytes, as 64 lowercase hex digits."""
    digest = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(_CHUNK), b""):
            digest.update(chunk)
    return digest.hexdigest()


def data_manifest(dataset_root) -> dict[str, str]:
    """SHA-256 of every file below ``dataset_root``, keyed by its POSIX path relative to the root.

    Parameters
    ----------
    dataset_root : str or os.PathLike
        Folder of a dataset (``data/raw/<name>``).

    Returns
    -------
    dict
        ``{relative path: sha256}``, sorted by path.
    """
    root = Path(dataset_root)
    if not root.is_dir():
        raise ValueError(
            f"{root}: dataset folder not found; expected the folder holding dataset.yaml"
        )
    files = sorted(p for p in root.rglob("*") if p.is_file())
    return {p.relative_to(root).as_posix(): sha256_file(p) for p in files}


def manifest_text(manifest: dict[str, str]) -> str:
    """A manifest as ``sha256sum`` writes it, sorted by path: ``"<sha256>  <path>\\n"`` lines,
    which ``sha256sum -c`` checks from the dataset's folder."""
    return "".join(f"{digest}  {path}\n" for path, digest in sorted(manifest.items()))


def manifest_sha256(manifest: dict[str, str]) -> str:
    """One hash of a manifest: the SHA-256 of its :func:`manifest_text`, so the hash can be
    checked with ``sha256sum`` output of the same files."""
    return hashlib.sha256(manifest_text(manifest).encode("utf-8")).hexdigest()


def _canonical(value) -> bytes:
    # Sorted keys and no whitespace: the same mapping always gives the same bytes,
    # whatever order the YAML file or the command line listed its keys in.
    return json.dumps(value, sort_keys=True, separators=(",", ":"), ensure_ascii=False).encode(
        "utf-8"
    )


def config_sha256(config) -> str:
    """SHA-256 of the canonical JSON of a configuration mapping."""
    return hashlib.sha256(_canonical(config)).hexdigest()


def config_sections_sha256(config) -> dict[str, str]:
    """One :func:`config_sha256` per top-level key of ``config``."""
    return {key: config_sha256(value) for key, value in sorted(config.items())}


def _git(path: Path, *args: str) -> str | None:
    try:
        proc = subprocess.run(
            ["git", "-C", str(path), *args], capture_output=True, text=True, timeout=30, check=False
        )
    except (OSError, subprocess.SubprocessError):
        return None
    return proc.stdout if proc.returncode == 0 else None


def git_state(path) -> dict:
    """Commit and dirty flag of the git repository that contains ``path``.

    Dirty means a tracked file differs from the commit; untracked files are ignored,
    as ``git describe --dirty`` does, so caches that tools drop into the tree (test
    runs, editors) do not flip the flag between two runs.  ``path`` may be a symbolic
    link into the repository (the test work folders are): git resolves it.  Outside a
    repository, or without git, both values are ``None``.

    Returns
    -------
    dict
        ``{"commit": str | None, "dirty": bool | None}``
    """
    commit = _git(Path(path), "rev-parse", "HEAD")
    if commit is None:
        return {"commit": None, "dirty": None}
    status = _git(Path(path), "status", "--porcelain", "--untracked-files=no")
    return {"commit": commit.strip(), "dirty": None if status is None else bool(status.strip())}


def package_versions(names=PACKAGES) -> dict[str, str | None]:
    """Installed version of each distribution (``None`` when it is not installed)."""
    versions = {}
    for name in names:
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            versions[name] = None
    return dict(sorted(versions.items()))


def run_time(now: datetime | None = None) -> str:
    """UTC time stamp ``YYYY-MM-DDTHH:MM:SSZ``.

    ``now`` wins; otherwise ``SOURCE_DATE_EPOCH`` (seconds since 1970) when it is set,
    otherwise the current time.
    """
    if now is None:
        epoch = os.environ.get("SOURCE_DATE_EPOCH", "").strip()
        if epoch:
            try:
                now = datetime.fromtimestamp(int(epoch), tz=UTC)
            except ValueError:
                raise ValueError(
                    f"SOURCE_DATE_EPOCH: expected whole seconds since 1970, got {epoch!r}"
                ) from None
        else:
            now = datetime.now(UTC)
    if now.tzinfo is None:
        raise ValueError(f"run time {now.isoformat()} has no time zone; expected an aware datetime")
    return now.astimezone(UTC).strftime("%Y-%m-%dT%H:%M:%SZ")


def collect(
    repo_root, config, dataset_root, *, now: datetime | None = None, git: dict | None = None
) -> dict:
    """The provenance record of a result.

    Parameters
    ----------
    repo_root : str or os.PathLike
        Any path inside the git repository of the code (a symlink into it works).
    config : mapping
        The effective configuration (after schema defaults), or the sections of it a
        report depends on.
    dataset_root : str or os.PathLike
        Folder of the raw dataset; every file below it is hashed.
    now : datetime, optional
        Aware datetime for ``run_time`` (see :func:`run_time`).
    git : dict, optional
        A :func:`git_state` already taken (the workflow takes it when it is parsed).

    Returns
    -------
    dict
        JSON-ready; keys :data:`REQUIRED_KEYS`.
    """
    config = json.loads(_canonical(dict(config)))  # plain JSON types, sorted keys
    manifest = data_manifest(dataset_root)
    return {
        "config": config,
        "config_sha256": config_sha256(config),
        "config_sections_sha256": config_sections_sha256(config),
        "data": {
            "root": str(dataset_root),
            "files": manifest,
            "n_files": len(manifest),
            "manifest_sha256": manifest_sha256(manifest),
        },
        "git": dict(git) if git is not None else git_state(repo_root),
        "packages": package_versions(),
        "platform": {
            "system": platform.system(),
            "release": platform.release(),
            "machine": platform.machine(),
        },
        "python": {"version": platform.python_version(), "implementation": sys.implementation.name},
        "run_time": run_time(now),
    }


def to_json(record: dict) -> str:
    """The record as indented JSON with sorted keys and a final newline."""
    return json.dumps(record, indent=1, sort_keys=True, ensure_ascii=False) + "\n"
