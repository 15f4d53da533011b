# Two commands for a newcomer (see README): `make run` and `make test`; `make setup` only installs.
# Each creates .venv and installs the project into it first, at the versions in constraints.txt
# (the ones the suite was last run green with; `make lock` regenerates it, `make drift` shows and
# tests what the newest resolution would change).
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
CONSTRAINTS := constraints.txt

.PHONY: run test setup lock drift clean

$(STAMP): pyproject.toml $(CONSTRAINTS)
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip -c $(CONSTRAINTS)
	$(BIN)/python -m pip install --quiet -e ".[test,all]" -c $(CONSTRAINTS)  # all: the optional engines (Drake, MJX)
	$(BIN)/python -m dalembert.adapters.pinocchio.native  # compile the Pinocchio stepper once (~2 min)
# bytecode for the checkout's sources, as pip writes it for every package it installs (an editable install gets
# none): where PYTHONDONTWRITEBYTECODE is set, every interpreter would otherwise compile dalembert again
	$(BIN)/python -m compileall -q $(CURDIR)/dalembert $(CURDIR)/reference $(CURDIR)/adapters $(CURDIR)/cases $(CURDIR)/reports
	touch $(STAMP)

setup: $(STAMP)

# The main job: the default matrix (every case, installed engine, integrator,
# dt/tolerance sweep) into a fresh results/<time> directory, then its report.
# Runs that fail, diverge or time out are findings in the report, not errors of
# `make run` (`dalembert run --strict` exits 1 on them, for engine CI).
run: $(STAMP)
	@out=results/$$(date -u +%Y%m%dT%H%M%SZ); \
	$(BIN)/dalembert run --out $$out; status=$$?; \
	$(BIN)/dalembert report $$out && ln -sfn $$(basename $$out) results/latest && \
	echo "report: $$out/report.md (results/latest)"; exit $$status

test: $(STAMP)
	$(BIN)/python -P -m pytest -n 2 -q  # -P: the checkout is not on sys.path, only the installed package

# constraints.txt anew from the newest resolution of pyproject.toml (run the suite after it: what
# it pins is what every newcomer gets).
lock:
	bash .ci/resolve lock

# The newest resolution against constraints.txt: the packages that would change and, where any
# would, the suite run on the newest (in .venv-newest); exits non-zero when that suite fails.
drift:
	bash .ci/resolve drift

clean:
	rm -rf $(VENV) .venv-newest .venv-lock results
