# naoloc: two commands set everything up.
#   make demo   install .[sim] into .venv, then survey -> build map -> localize in the default simulated room
#   make test   install into .venv, then the whole test suite (what .ci/run calls)
#   make test-fast  the unit and integration layers without slow tests, in under a minute
SHELL := /bin/bash
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
export MUJOCO_GL ?= egl
export PYOPENGL_PLATFORM ?= egl

.PHONY: demo test test-fast lint typecheck venv sysdeps clean bench wheel check-wheel

# Editable (setuptools' meta path finder: only naoloc.* is importable). PYTHONWARNINGS hides exactly setuptools' notice that an editable install is one;
# a real packaging warning still shows (and tools/check_wheel.sh fails on one).
$(STAMP): pyproject.toml setup.py constraints.txt
	@tools/check_python.sh $(PYTHON)
	@test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --disable-pip-version-check --upgrade pip
	PYTHONWARNINGS="ignore:Editable installation" $(PY) -m pip install --quiet \
		--disable-pip-version-check -c constraints.txt -e ".[sim,naoqi,dev,ray]"
	@touch $(STAMP)

venv: sysdeps $(STAMP)

# The demo needs only the simulator: `.[sim]` into .venv, its own stamp (no test, lint or
# cluster tools); a later `make test` adds the rest.
DEMO_STAMP := $(VENV)/.installed-demo
$(DEMO_STAMP): pyproject.toml setup.py constraints.txt
	@tools/check_python.sh $(PYTHON)
	@test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --disable-pip-version-check --upgrade pip
	PYTHONWARNINGS="ignore:Editable installation" $(PY) -m pip install --quiet \
		--disable-pip-version-check -c constraints.txt -e ".[sim]"
	@touch $(DEMO_STAMP)

# Headless OpenGL (EGL through Mesa) for MuJoCo rendering: installed when root, named otherwise.
sysdeps:
	@tools/sysdeps.sh

demo: sysdeps $(DEMO_STAMP)
	$(VENV)/bin/naoloc demo -o runs/demo

lint: venv
	$(VENV)/bin/ruff check naoloc tests tools setup.py
	$(VENV)/bin/ruff format --check naoloc tests tools setup.py

typecheck: venv
	$(VENV)/bin/mypy naoloc

# Every layer: tests/unit (pure), tests/integration (fake backend, CLI processes),
# tests/sim (MuJoCo), tests/net (servers on loopback), tests/conformance (every backend).
test: venv lint typecheck
	$(PY) -m pytest -q -p no:cacheprovider tests

# While working: the pure and fake-backend layers without the tests marked slow (< 1 min).
test-fast: venv
	$(PY) -m pytest -q -p no:cacheprovider -m "not slow" tests/unit tests/integration

bench: venv
	$(PY) tools/bench_map.py
	$(PY) tools/bench_sim.py
	$(PY) tools/bench_net.py

# The wheel, installed in a fresh venv outside the checkout beside dm_control (what CI runs).
wheel: venv
	$(PY) -m build --wheel --outdir dist . >/dev/null

check-wheel: venv
	tools/check_wheel.sh

clean:
	rm -rf $(VENV) runs dist build .pytest_cache .mypy_cache .ruff_cache
