# Two commands for a newcomer (see README): `make run` and `make test`.
# Both create .venv and install the project into it first.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: run test setup clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e ".[test,all]"  # all: the optional engines (Drake, MJX)
	$(BIN)/python -m dalembert.adapters.pinocchio.native  # compile the Pinocchio stepper once (~2 min)
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

clean:
	rm -rf $(VENV) results
