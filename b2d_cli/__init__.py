"""The `b2d` command line (b2d_cli/main.py)."""

import os

# the renderers' default GL (sim/offscreen.py), set before any command imports mujoco: without MUJOCO_GL,
# `import mujoco` loads GLFW (~0.15 CPU-s) in this process and in every process a command spawns
os.environ.setdefault("MUJOCO_GL", "egl")
