#!/usr/bin/env bash
# Stop early, with the fix, when the interpreter is too old or cannot make a venv.
set -euo pipefail
py=${1:-python3}
if ! command -v "$py" >/dev/null 2>&1; then
  echo "naoloc: $py not found; install Python 3.11+ (Debian: apt-get install python3 python3-venv)" >&2; exit 1
fi
if ! "$py" -c 'import sys; sys.exit(0 if sys.version_info >= (3, 11) else 1)'; then
  echo "naoloc: needs Python 3.11+, $py is $("$py" -V 2>&1); run: make PYTHON=python3.11 ..." >&2; exit 1
fi
if ! "$py" -c 'import venv, ensurepip' >/dev/null 2>&1; then
  echo "naoloc: $py cannot create virtual environments; run: apt-get install python3-venv" >&2; exit 1
fi
