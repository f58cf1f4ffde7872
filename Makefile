# naoloc: two commands set everything up.
#   make demo   install into .venv, then survey -> build map -> localize in the default simulated room
#   make test   install into .venv, then the whole test suite (what .ci/run calls)
SHELL := /bin/bash
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
export MUJOCO_GL ?= egl
export PYOPENGL_PLATFORM ?= egl

.PHONY: demo test lint typecheck venv sysdeps clean bench

$(STAMP): pyproject.toml
	@tools/check_python.sh $(PYTHON)
	@test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --disable-pip-version-check --upgrade pip
	$(PY) -m pip install --quiet --disable-pip-version-check -e ".[sim,naoqi,dev]"
	@touch $(STAMP)

venv: sysdeps $(STAMP)

# Headless OpenGL (EGL through Mesa) for MuJoCo rendering: installed when root, named otherwise.
sysdeps:
	@tools/sysdeps.sh

demo: venv
	$(VENV)/bin/naoloc demo -o runs/demo

lint: venv
	$(VENV)/bin/ruff check naoloc backends tests tools
	$(VENV)/bin/ruff format --check naoloc backends tests tools

typecheck: venv
	$(VENV)/bin/mypy naoloc backends

test: venv lint typecheck
	$(PY) -m pytest -q -p no:cacheprovider tests

bench: venv
	$(PY) tools/bench_map.py
	$(PY) tools/bench_sim.py
	$(PY) tools/bench_net.py

clean:
	rm -rf $(VENV) runs .pytest_cache .mypy_cache .ruff_cache
