# The two set-up commands: `make run` and `make test`. Both create .venv when missing.
# `make docs` builds the documentation site (mkdocs-material, warnings are errors) into build/site;
# `make docs-serve` serves it with live reload on http://127.0.0.1:8000.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
#: The test and docs tools on top of the runtime: `make run` does not need them.
TEST_STAMP := $(VENV)/.installed-test

.PHONY: run test test-containers check lint docs docs-serve clean

$(BIN)/python:
	@echo "creating $(VENV) and upgrading pip"
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --disable-pip-version-check --upgrade pip

# `make run` installs the runtime only; the test and docs tools come on top for `make test`.
$(STAMP): $(BIN)/python pyproject.toml
	@echo "installing zendock and its dependencies (about a minute the first time)"
	$(BIN)/python -m pip install --disable-pip-version-check --progress-bar on -e .
	touch $(STAMP)

$(TEST_STAMP): $(STAMP)
	@echo "installing the test and docs tools (the [test,docs] extras)"
	$(BIN)/python -m pip install --disable-pip-version-check --progress-bar on -e ".[test,docs]"
	touch $(TEST_STAMP)

run: $(STAMP)
	$(BIN)/zendock demo

check: $(TEST_STAMP)
	$(BIN)/ruff check shared services deploy tests
	$(BIN)/mypy shared

test: $(TEST_STAMP) check docs
	$(BIN)/python -m pytest -q

# The CLI reference (docs/cli.md) is generated from deploy/cli.py's parsers while the site builds
# (deploy/docs_site.py, a mkdocs hook); docs/measurements.md is rendered from docs/measurements/*.json.
docs: $(TEST_STAMP)
	NO_MKDOCS_2_WARNING=1 $(BIN)/mkdocs build --strict --quiet

docs-serve: $(TEST_STAMP)
	NO_MKDOCS_2_WARNING=1 $(BIN)/mkdocs serve

# The container deployment for real (rootful podman, several minutes; outside `make test`): see README.
test-containers: $(TEST_STAMP)
	$(BIN)/python -m pip install --quiet 'podman-compose>=1.6'
	$(BIN)/python -m tests.containers.check

clean:
	rm -rf $(VENV) runs .pytest_cache
