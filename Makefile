# The two set-up commands: `make run` and `make test`. Both create .venv when missing.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: run test test-containers check lint clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

$(STAMP): $(BIN)/python pyproject.toml
	$(BIN)/python -m pip install --quiet -e ".[test]"
	touch $(STAMP)

run: $(STAMP)
	$(BIN)/zendock demo

check: $(STAMP)
	$(BIN)/ruff check shared services deploy tests
	$(BIN)/mypy shared

test: $(STAMP) check
	$(BIN)/python -m pytest -q

# The container deployment for real (rootful podman, several minutes; outside `make test`): see README.
test-containers: $(STAMP)
	$(BIN)/python -m pip install --quiet 'podman-compose>=1.6'
	$(BIN)/python -m tests.containers.check

clean:
	rm -rf $(VENV) runs .pytest_cache
