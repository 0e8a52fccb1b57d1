#!/usr/bin/env bash
# Install everything b2d needs on a fresh Debian machine with Python 3.11 (run as root):
# the GL libraries for headless MuJoCo rendering, a virtual environment in .venv, the package.
set -euo pipefail
cd "$(dirname "$0")/.."
# GL for headless rendering; PostgreSQL and Redis for the scale-out tests (deploy/: started on 127.0.0.1 on demand)
GL_PACKAGES="libosmesa6 libegl1 libgl1-mesa-dri libglx-mesa0 libgles2 postgresql redis-server"
if ! dpkg -s $GL_PACKAGES >/dev/null 2>&1; then
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $GL_PACKAGES >/dev/null
fi
[ -x .venv/bin/python ] || python3 -m venv .venv
.venv/bin/python -m pip install -q --upgrade pip
.venv/bin/python -m pip install -q -e ".[dev,scale]"
echo "b2d installed in $(pwd)/.venv"
