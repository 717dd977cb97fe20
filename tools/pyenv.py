"""The tools' shared Python environment: target/pyenv, created on first use
with the packages a tool needs, then the tool re-runs itself inside it.
Blender's bpy pins its own numpy, so it gets an environment of its own
(`python_with`)."""

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
VENV = ROOT / "target" / "pyenv"
# Packages whose import name differs from their name on PyPI.
IMPORT_NAMES = {"pillow": "PIL"}


def python_with(requirements, venv=VENV, tool="tools"):
    """The interpreter of `venv`, created if missing, with `requirements`
    installed."""
    python = venv / "bin" / "python"
    if not python.exists():
        print(f"{tool}: creating {venv}", flush=True)
        subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
        subprocess.run([str(python), "-m", "pip", "install", "-q", "--upgrade", "pip"], check=True)
    missing = subprocess.run(
        [str(python), "-c", "import importlib.util, sys; sys.exit(any(importlib.util.find_spec(m) is None for m in sys.argv[1:]))",
         *[IMPORT_NAMES.get(name, name) for name in (r.split("=")[0].split("[")[0] for r in requirements)]],
    ).returncode != 0
    if missing:
        print(f"{tool}: installing {' '.join(requirements)}", flush=True)
        subprocess.run([str(python), "-m", "pip", "install", "-q", *requirements], check=True)
    return python


def ensure(requirements, script):
    """Re-run `script` inside target/pyenv with `requirements` installed."""
    python = python_with(requirements, VENV, Path(script).name)
    if Path(sys.prefix).resolve() != VENV.resolve():
        os.execv(str(python), [str(python), script, *sys.argv[1:]])
