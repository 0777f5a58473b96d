# Two commands: `make results` and `make test`. Both create .venv from the pinned
# envs/requirements.txt first when it is missing or the pins changed (hash stamp).
SHELL := /bin/bash
.SHELLFLAGS := -eu -o pipefail -c
PYTHON ?= $(shell command -v python3.11 || command -v python3)
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.thermaxis-env.sha256
CORES ?= all
# Quiet by default: the maintained logger plugin snakemake-logger-plugin-rich (a progress
# bar of jobs done of total and the rules running on a terminal; the job table and the
# outcome otherwise), and the rules' warnings; `make results V=1` prints Snakemake's own
# full output, every rule, reason and shell command. The full log is in .snakemake/log/
# either way. The Snakemake targets run through the `thermaxis` command (docs/cli.md), so
# `thermaxis run` prints what `make results` prints.
V ?= 0
THERMAXIS := $(BIN)/thermaxis
THERMAXIS_OPTIONS := --cores $(CORES)$(if $(filter 1,$(V)), --verbose)
export PATH := $(abspath $(BIN)):$(PATH)
export MPLBACKEND := Agg
export PYTHONHASHSEED := 0
# A make that runs inside another (make test's tests, a wrapper) would print 'Entering/Leaving
# directory' around its output and bury the answer line; the answer stays last.
MAKEFLAGS += --no-print-directory

.PHONY: env results import test lint fmt clean twin twin-calibrate twin-conflicts report sweep bench docs help

help:
	@echo "make help            this list"
	@echo "make env             create .venv from the pinned envs/requirements.txt (every target that needs it does this first)"
	@echo "make slurm-env       create .venv-slurm for cluster runs and tests/slurm: a layer on .venv with envs/requirements-slurm.txt"
	@echo "make results         set up .venv if needed, run the whole workflow on every embedded dataset (simulated twin, measured fl_thermal)"
	@echo "make import          re-import data/raw/fl_thermal from the public record with data/import/fl_thermal.yaml"
	@echo "make test            set up .venv if needed, run the test suite (PYTEST_WORKERS=2 pytest-xdist workers)"
	@echo "make lint            ruff check over src/, tools/, workflow/scripts/ and tests/, then snakemake --lint and snakefmt --check"
	@echo "make fmt             snakefmt over Snakefile and workflow/rules/"
	@echo "make twin            regenerate data/raw/twin (byte-identical) from the committed twin parameters"
	@echo "make twin-calibrate  refit src/thermaxis/twin_params.json to the paper's published targets, then regenerate data/raw/twin (RESUME= : from the priors)"
	@echo "make twin-conflicts  optimise each group of the paper's targets alone and in pairs: docs/twin-conflicts.md"
	@echo "make report          Snakemake report of every embedded dataset: results/<dataset>/report.zip"
	@echo "make sweep           sweep cluster counts x selection x algorithms x decoupling degree (first dataset)"
	@echo "make bench           benchmark; writes results/bench/bench.json and bench.md"
	@echo "make docs            rewrite the result blocks of README.md and docs/*.md from results/ (after make results)"
	@echo "make clean           remove results/, logs/, benchmarks/, .snakemake/"

# The stamp holds a hash of the pins and the package metadata; any change reinstalls.
env:
	@want="$$(cat envs/requirements.txt pyproject.toml | sha256sum | cut -d' ' -f1)"; \
	have="$$(cat $(STAMP) 2>/dev/null || true)"; \
	if [ ! -x "$(BIN)/python" ] || [ "$$want" != "$$have" ]; then \
		echo "setting up $(VENV) from envs/requirements.txt"; \
		rm -rf "$(VENV)"; \
		"$(PYTHON)" -m venv "$(VENV)"; \
		"$(BIN)/python" -m pip install --quiet --disable-pip-version-check -r envs/requirements.txt; \
		"$(BIN)/python" -m pip install --quiet --disable-pip-version-check --no-deps --no-build-isolation -e .; \
		"$(BIN)/python" -m pip check --disable-pip-version-check; \
		echo "$$want" > "$(STAMP)"; \
	fi
	@# The editable install's modules as bytecode: where PYTHONDONTWRITEBYTECODE is set, every
	@# job and test process would otherwise compile the thermaxis modules it imports again.
	@"$(BIN)/python" -m compileall -q src

# The Slurm executor plugin is not in .venv: Snakemake imports every installed executor
# plugin at each start, and plugin 2.8.0 then waits up to 10 s for an absent Slurm
# controller (docs/slurm-plugin-startup.md). Cluster runs (profiles/slurm) and tests/slurm
# use .venv-slurm instead: a venv layered on .venv, made by .venv's own Python so both run
# the same interpreter. A .pth adds .venv's site-packages, so every pinned package is
# .venv's own copy; on top come envs/requirements-slurm.txt and Snakemake again at its pin,
# for the `snakemake` command in .venv-slurm/bin. Installing all the pins a second time
# took 75 s; the layer takes seconds. Its hash stamp covers both files and pyproject.toml.
# Made only by this target, never by `env`.
SLURM_VENV := .venv-slurm
SLURM_STAMP := $(SLURM_VENV)/.thermaxis-env.sha256
.PHONY: slurm-env
slurm-env: env
	@want="$$(cat envs/requirements.txt envs/requirements-slurm.txt pyproject.toml | sha256sum | cut -d' ' -f1)"; \
	have="$$(cat $(SLURM_STAMP) 2>/dev/null || true)"; \
	if [ ! -x "$(SLURM_VENV)/bin/python" ] || [ "$$want" != "$$have" ]; then \
		echo "setting up $(SLURM_VENV) on $(VENV) with envs/requirements-slurm.txt"; \
		rm -rf "$(SLURM_VENV)"; \
		"$(BIN)/python" -m venv "$(SLURM_VENV)"; \
		echo '*' > "$(SLURM_VENV)/.gitignore"; \
		purelib='import sysconfig; print(sysconfig.get_path("purelib"))'; \
		base="$$(cd "$$("$(BIN)/python" -c "$$purelib")" && pwd -P)"; \
		layer="$$("$(SLURM_VENV)/bin/python" -c "$$purelib")"; \
		"$(BIN)/python" -c 'import sys; print("import site; site.addsitedir(%r)" % sys.argv[1])' "$$base" \
			> "$$layer/thermaxis-base-venv.pth"; \
		"$(SLURM_VENV)/bin/python" -m pip install --quiet --disable-pip-version-check -r envs/requirements-slurm.txt; \
		"$(SLURM_VENV)/bin/python" -m pip install --quiet --disable-pip-version-check --no-deps --force-reinstall \
			"$$(grep -E '^snakemake==' envs/requirements.txt)"; \
		"$(SLURM_VENV)/bin/python" -m pip check --disable-pip-version-check; \
		echo "$$want" > "$(SLURM_STAMP)"; \
	fi

# Every dataset of config `datasets` (config/config.yaml), one Snakemake run each, then the
# page across datasets and each dataset's answer, last (`thermaxis run`). After any
# interruption this completes the run: incomplete outputs are made again and a dead run's
# lock is cleared; a Snakemake still running here is left alone (README). First the
# published protocols of BENCHMARKS on their records (data/sources/; docs/benchmarks.md),
# so the answers end the output.
BENCHMARKS ?= data/benchmarks/fl_thermal.yaml
results: env
	@for spec in $(BENCHMARKS); do \
		$(BIN)/python -m thermaxis.benchmark "$$spec" --out "results/_benchmarks/$$(basename "$$spec" .yaml)"; \
	done
	@$(THERMAXIS) run $(THERMAXIS_OPTIONS) </dev/null

# Re-import the embedded measured dataset from its public record (data/sources/fl_thermal).
import: env
	$(THERMAXIS) import data/import/fl_thermal.yaml --out data/raw/fl_thermal

# Both tiers (tests/unit, tests/workflow) and tests/slurm (skipped without Slurm), on
# PYTEST_WORKERS pytest-xdist workers; the tests of one shared workflow run stay on one
# worker (tests/conftest.py). PYTEST_WORKERS=0 runs them in this process.
PYTEST_WORKERS ?= 2
test: env
	$(BIN)/python -m pytest -n $(PYTEST_WORKERS) --dist loadgroup --durations=25

# ruff's rules are in pyproject.toml ([tool.ruff]); the Snakemake rule files get Snakemake's
# own linter and snakefmt.
lint: env
	$(BIN)/ruff check src tools workflow/scripts tests
	$(BIN)/snakemake --lint
	$(BIN)/snakefmt --check Snakefile workflow/rules/

fmt: env
	$(BIN)/snakefmt Snakefile workflow/rules/

twin: env
	$(BIN)/python -m thermaxis.twin generate --out data/raw/twin --truth data/twin_truth

# By default only the last leg runs (the compass search on the faithfulness table), from
# the file the least-squares stages wrote (the committed twin's last resume point);
# RESUME= (empty) runs every stage from the priors, RESUME=src/thermaxis/twin_params.
# table3_restarts.json from the Table 3 restarts' end (docs/datasets.md).
RESUME ?= src/thermaxis/twin_params.heldout_restarts.json
twin-calibrate: env
	$(BIN)/python -m thermaxis.twin calibrate $(if $(RESUME),--resume "$(RESUME)")

twin-conflicts: env
	$(BIN)/python -m thermaxis.twin conflicts

report: results
	$(THERMAXIS) report --zip $(THERMAXIS_OPTIONS)

# The sweep of the first dataset of config `datasets`; its index is rebuilt after it, to
# link the sweep report (`thermaxis sweep`).
sweep: env
	$(THERMAXIS) sweep $(THERMAXIS_OPTIONS)

# Many minutes (cold run, sweep, scale series up to 50 runs); e.g. BENCH_ARGS="--runs 5 10".
bench: env
	$(BIN)/python -m tools.bench --out results/bench $(BENCH_ARGS)

# The README's and the guides' result figures come from results/, never by hand
# (thermaxis.reports.docblocks); RESULTS and DOCS for another tree or other files,
# DOCBLOCKS_ARGS=--check to list the stale blocks only.
RESULTS ?= results
DOCS ?= README.md $(wildcard docs/*.md)
docs: env
	$(BIN)/python -m thermaxis.reports.docblocks --results $(RESULTS) $(DOCBLOCKS_ARGS) $(DOCS)

clean:
	rm -rf results logs benchmarks .snakemake
