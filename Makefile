# The two set-up commands: `make run` and `make test`. Both create .venv when missing.
# `make docs` builds the documentation site (mkdocs-material, warnings are errors) into build/site;
# `make docs-serve` serves it with live reload on http://127.0.0.1:8000.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
#: The test and docs tools on top of the runtime: `make run` does not need them.
TEST_STAMP := $(VENV)/.installed-test
#: pytest's workers (pytest-xdist): one a core, at most two, each taking whole test files so a file's
#: module fixtures start once. `make test TEST_WORKERS=0` runs the suite in one process.
TEST_WORKERS ?= auto

.PHONY: run test test-containers check lint docs docs-serve docs-check browser bytecode clean

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

# zendock's own bytecode. Python writes a module's cache on its first import unless PYTHONDONTWRITEBYTECODE
# is set; with it set and no cache, every service start compiles all it imports (what that costs:
# docs/measurements, 107). compileall writes only what is missing or older than its source.
# The DDS face runs with -OO (deploy/stack.yaml), which reads its own cache files (.opt-2.pyc).
bytecode: $(STAMP)
	$(BIN)/python -m compileall -q -j 0 shared services deploy
	$(BIN)/python -OO -m compileall -q -j 0 shared services

run: $(STAMP) bytecode
	$(BIN)/zendock demo

check: $(TEST_STAMP)
	$(BIN)/ruff check shared services deploy tests
	$(BIN)/ruff format --check shared services deploy tests
	$(BIN)/mypy shared services deploy

test: $(TEST_STAMP) bytecode ros2 browser check docs
	$(BIN)/python -m pytest -q --durations=25 --numprocesses $(TEST_WORKERS) --maxprocesses 2 --dist loadfile

# Debian's Chromium and its driver, for the docs site's search test in a real browser (tests/docs).
browser:
	@command -v chromium >/dev/null && command -v chromedriver >/dev/null || \
		{ echo "installing Debian's chromium and chromium-driver"; apt-get update -qq && \
		  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium chromium-driver; }

# The site builds without warnings, and its search finds the contracts page in headless Chromium.
docs-check: $(TEST_STAMP) browser docs
	$(BIN)/python -m pytest -q tests/docs

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

# `make ros2`: .venv-ros2, real ROS 2 Jazzy rclpy (Fast DDS) from PyPI wheels with zendock installed editable
# (`pip install -e ".[ros2]"`) and nav2_msgs / tf2_msgs built by colcon into it, for services.ros2_dds and
# tests/integration/test_ros2_dds.py (skipped without it). About 5 minutes the first time, seconds after; `make test`
# runs it, so the suite meets real ROS 2.
ROS2_VENV := .venv-ros2
.PHONY: ros2
ros2: $(ROS2_VENV)/.ros2-ready

$(ROS2_VENV)/.ros2-ready: tools/setup_ros2.sh pyproject.toml $(wildcard shared/ros2/definitions/*/*/*.*)
	bash tools/setup_ros2.sh $(ROS2_VENV)
	touch $@

# `make pictures` regenerates every shipped picture under docs/ from the current code:
# - `make picture-demo`: docs/demo_seed_room.png, one demo run in seed_room (about 2 minutes);
# - `make picture-fleet`: docs/fleet.png, the six-robot hour of the fleet measurements (about 45 minutes).
.PHONY: pictures picture-demo picture-fleet
pictures: picture-demo picture-fleet

picture-demo: $(STAMP)
	mkdir -p runs
	$(BIN)/zendock demo --world deploy/worlds/seed_room.yaml --detector synthetic --rtf 8 --json > runs/pictures-demo.json
	$(BIN)/python -c 'import json, shutil; r = json.load(open("runs/pictures-demo.json")); \
		shutil.copyfile(r["run_dir"] + "/trajectory.png", "docs/demo_seed_room.png"); \
		print("docs/demo_seed_room.png from", r["run_dir"])'

picture-fleet: $(STAMP)
	rm -rf runs/pictures-fleet && mkdir -p runs/pictures-fleet
	$(BIN)/zendock fleet --world deploy/worlds/fleet/depot.yaml --duration 3600 --rtf 3 --seed 1 \
		--runs-dir runs/pictures-fleet --json > runs/pictures-fleet.json
	cp runs/pictures-fleet/fleet-*/fleet.png docs/fleet.png
	@echo "docs/fleet.png from" runs/pictures-fleet/fleet-*
