#!/usr/bin/env bash
# Headless rendering needs EGL through Mesa (or OSMesa). Install when root and missing; name otherwise.
set -uo pipefail
pkgs="libegl1 libegl-mesa0 libgl1-mesa-dri"
have() { ldconfig -p 2>/dev/null | grep -q "$1"; }
if have libEGL.so.1 && { have libEGL_mesa.so.0 || have libOSMesa.so; }; then exit 0; fi
if have libOSMesa.so; then exit 0; fi
if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
  echo "naoloc: installing headless OpenGL: $pkgs" >&2
  (apt-get install -y --no-install-recommends $pkgs >/dev/null 2>&1 \
    || { apt-get update >/dev/null 2>&1 && apt-get install -y --no-install-recommends $pkgs >/dev/null 2>&1; }) \
    || { echo "naoloc: could not install $pkgs; run: apt-get update && apt-get install -y $pkgs" >&2; exit 1; }
else
  echo "naoloc: headless rendering needs EGL; run as root: apt-get install -y $pkgs (or libosmesa6 with MUJOCO_GL=osmesa)" >&2
  echo "naoloc: continuing; the simulator will say the same if it cannot render" >&2
fi
