#!/usr/bin/env bash
# The wheel as a new user gets it: build it, install it in a fresh venv OUTSIDE the checkout
# next to dm_control (which depends on the `mujoco` distribution too), then from a folder
# outside the checkout: pip check, one mujoco installed once, dm_control renders, naoloc demo,
# naoloc survey -c paper_room, and a smoke subset of the tests against the installed package.
#
#   tools/check_wheel.sh              # what .ci/run calls after `make test` (MuJoCo 3.x)
#   EXTRA= tools/check_wheel.sh       # exactly `pip install <wheel>[sim] dm_control` (MuJoCo 4)
#
# EXTRA defaults to "mujoco<4": dm_control 1.0.50 allows mujoco 4.0.0 in its metadata but its
# physics fails on it (MjModel has no flex_vertedge), so beside dm_control a user wants 3.x;
# `make test` covers naoloc on 4.x. With EXTRA= dm_control's own failure on 4.x is reported,
# not counted against naoloc.
#
# Prints one line per step with its wall time; exits non-zero on the first failure.
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
py=${PYTHON:-python3}
[ -x "$repo/.venv/bin/python" ] && py="$repo/.venv/bin/python"
work=$(mktemp -d "${TMPDIR:-/tmp}/naoloc-wheel.XXXXXX")
export MUJOCO_GL=${MUJOCO_GL:-egl} PYOPENGL_PLATFORM=${PYOPENGL_PLATFORM:-egl}
export PIP_DISABLE_PIP_VERSION_CHECK=1
t0=$(date +%s)
step() { echo "check_wheel: $1 ($(( $(date +%s) - t0 )) s)"; }
fail() { echo "check_wheel: FAILED: $1 (logs in $work)" >&2; exit 1; }

# 1. Build the wheel (isolated build: the setuptools of pyproject's build-system) from a clean
#    copy of the tree, so that no stale build/ folder of the checkout can leak into it.
mkdir "$work/src"
tar -C "$repo" --exclude=.git --exclude=.venv --exclude=build --exclude=dist --exclude=runs \
  --exclude='*.egg-info' --exclude=__pycache__ -cf - . | tar -C "$work/src" -xf -
"$py" -m pip wheel --quiet --no-deps --wheel-dir "$work/dist" "$work/src" >"$work/build.log" 2>&1 \
  || fail "wheel build: $(tail -n 3 "$work/build.log")"
wheel=$(ls "$work"/dist/naoloc-*.whl)
if grep -qi "warning" "$work/build.log"; then fail "the wheel build printed warnings"; fi
step "built $(basename "$wheel")"

# 2. Every module and data file of the checkout is in the wheel (a new sub-package is found).
"$py" - "$repo" "$wheel" <<'EOF' || fail "the wheel misses files of the checkout"
import sys, zipfile
from pathlib import Path
repo, wheel = Path(sys.argv[1]), sys.argv[2]
names = set(zipfile.ZipFile(wheel).namelist())
def want(src: Path, dst: str) -> list[str]:
    return [f"{dst}/{f.relative_to(src).as_posix()}" for f in src.rglob("*")
            if f.is_file() and "__pycache__" not in f.parts and f.suffix != ".pyc"]
expected = want(repo / "naoloc", "naoloc") + want(repo / "configs", "naoloc/configs")
missing = sorted(set(expected) - names)
for name in missing:
    print(f"  missing from the wheel: {name}", file=sys.stderr)
sys.exit(1 if missing else 0)
EOF
step "the wheel has every file of naoloc/ and configs/"

# 3. A fresh venv outside the checkout: the wheel with its sim extra, next to dm_control.
"$py" -m venv "$work/venv"
vpy="$work/venv/bin/python"
EXTRA=${EXTRA-mujoco<4}
# shellcheck disable=SC2086
"$vpy" -m pip install --quiet "$wheel[sim]" dm_control ${EXTRA} >"$work/install.log" 2>&1 \
  || fail "pip install: $(grep -v '^WARNING: Location' "$work/install.log" | tail -n 3)"
"$vpy" -m pip check >"$work/check.log" 2>&1 || fail "pip check: $(cat "$work/check.log")"
step "installed $(basename "$wheel")[sim] dm_control ${EXTRA}; pip check passes"

cd "$work"  # from here on, nothing may come from the checkout
"$vpy" - <<'EOF' || fail "mujoco, dm_control and naoloc do not coexist"
import importlib.metadata as md
import mujoco
# Two distributions may ship one file of mujoco/ only when it is the same file (mujoco 4's
# metapackage repeats mujoco-core's __init__.py); mujoco 3.x beside mujoco-core 4.x is not.
hashes: dict[str, dict[str, str]] = {}
for d in md.distributions():
    for f in d.files or []:
        if str(f).startswith("mujoco/") and f.hash is not None:
            hashes.setdefault(str(f), {})[f"{d.metadata['Name']} {d.version}"] = f.hash.value
clashes = {f: o for f, o in hashes.items() if len(set(o.values())) > 1}
assert not clashes, f"distributions overwrite each other's mujoco files: {sorted(clashes)[:3]}"
owners = sorted(hashes.get("mujoco/__init__.py", {}))
import naoloc
assert "site-packages" in naoloc.__file__, naoloc.__file__
from dm_control import suite
try:
    env = suite.load("cartpole", "swingup")
    env.reset()
    pixels = env.physics.render(height=48, width=64)
    assert pixels.shape == (48, 64, 3) and pixels.any()
    dm = "renders"
except Exception as err:
    if int(mujoco.__version__.split(".")[0]) < 4:
        raise
    dm = f"FAILS on mujoco {mujoco.__version__} by itself ({type(err).__name__}: {err})"
from naoloc.backends.mujoco.gl import loaded_platform
print(f"check_wheel: mujoco {mujoco.__version__} (from {', '.join(owners)}; "
      f"{loaded_platform(mujoco)}), dm_control {md.version('dm_control')} {dm}, "
      f"naoloc {naoloc.__version__}")
EOF
step "one copy of mujoco; dm_control checked"

naoloc="$work/venv/bin/naoloc"
"$naoloc" survey -c paper_room -o "$work/s.mcap" >"$work/survey.out" 2>"$work/survey.err" \
  || fail "naoloc survey -c paper_room: $(tail -n 1 "$work/survey.err")"
step "naoloc survey -c paper_room: $(tail -n 1 "$work/survey.out")"
"$naoloc" demo -o "$work/demo" >"$work/demo.out" 2>"$work/demo.err" \
  || fail "naoloc demo: $(tail -n 1 "$work/demo.err")"
step "naoloc demo: $(tail -n 1 "$work/demo.out" | cut -c1-160)"

# 4. A smoke subset of the tests against the installed package (cwd outside the checkout).
"$vpy" -m pip install --quiet -c "$repo/constraints.txt" pytest hypothesis websockets \
  >>"$work/install.log" 2>&1 || fail "pip install pytest"
cp -r "$repo/tests" "$work/tests"
"$vpy" -m pytest -q -p no:cacheprovider --rootdir "$work" -c /dev/null \
  "$work/tests/integration/test_packaging.py" "$work/tests/unit/test_config.py" \
  "$work/tests/integration/test_cli.py" "$work/tests/integration/test_fake_backend.py" \
  "$work/tests/net/test_live.py" >"$work/pytest.log" 2>&1 \
  || fail "tests against the installed package: $(tail -n 5 "$work/pytest.log")"
step "tests against the installed package: $(tail -n 1 "$work/pytest.log")"
rm -rf "$work"
