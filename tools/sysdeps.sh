#!/usr/bin/env bash
# Headless rendering needs EGL through Mesa's software rasteriser (or OSMesa).
# Installs the Debian packages when root and missing; otherwise names the command to run.
set -uo pipefail
pkgs="libegl1 libegl-mesa0 libgl1-mesa-dri"
missing=""
if command -v dpkg-query >/dev/null 2>&1; then
  for p in $pkgs; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing="$missing $p"
  done
  if [ -n "$missing" ] && dpkg-query -W -f='${Status}' libosmesa6 2>/dev/null | grep -q "install ok installed"; then
    missing=""  # OSMesa works as a fallback (MUJOCO_GL=osmesa is chosen automatically)
  fi
else
  # Not Debian: look for the libraries themselves.
  have() { ldconfig -p 2>/dev/null | grep -q "$1"; }
  { have libEGL.so.1 && have libEGL_mesa.so.0; } || have libOSMesa.so || missing=" $pkgs"
fi
[ -z "$missing" ] && exit 0
if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
  echo "naoloc: installing headless OpenGL:$missing" >&2
  export DEBIAN_FRONTEND=noninteractive
  if ! apt-get install -y --no-install-recommends $missing >/dev/null 2>&1; then
    apt-get update >/dev/null 2>&1
    apt-get install -y --no-install-recommends $missing >/dev/null 2>&1 \
      || { echo "naoloc: could not install:$missing; run: apt-get update && apt-get install -y$missing" >&2; exit 1; }
  fi
else
  echo "naoloc: headless rendering needs:$missing; run as root: apt-get install -y$missing" >&2
  echo "naoloc: (or libosmesa6 with MUJOCO_GL=osmesa); continuing, the simulator will say the same" >&2
fi
