# The two set-up commands: `make run` and `make test`. Both create .venv when missing.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: run test check lint clean

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

clean:
	rm -rf $(VENV) runs .pytest_cache
