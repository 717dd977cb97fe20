"""The tools' shared Python environment: target/pyenv, created on first use
with the packages a tool needs, then the tool re-runs itself inside it."""

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
VENV = ROOT / "target" / "pyenv"
# Packages whose import name differs from their name on PyPI.
IMPORT_NAMES = {"pillow": "PIL"}


def ensure(requirements, script):
    """Re-run `script` inside target/pyenv with `requirements` installed."""
    python = VENV / "bin" / "python"
    inside = Path(sys.prefix).resolve() == VENV.resolve()
    if not python.exists():
        print(f"{Path(script).name}: creating {VENV}", flush=True)
        subprocess.run([sys.executable, "-m", "venv", str(VENV)], check=True)
        subprocess.run([str(python), "-m", "pip", "install", "-q", "--upgrade", "pip"], check=True)
    missing = subprocess.run(
        [str(python), "-c", "import importlib.util, sys; sys.exit(any(importlib.util.find_spec(m) is None for m in sys.argv[1:]))",
         *[IMPORT_NAMES.get(name, name) for name in (r.split("=")[0].split("[")[0] for r in requirements)]],
    ).returncode != 0
    if missing:
        print(f"{Path(script).name}: installing {' '.join(requirements)}", flush=True)
        subprocess.run([str(python), "-m", "pip", "install", "-q", *requirements], check=True)
    if not inside:
        os.execv(str(python), [str(python), script, *sys.argv[1:]])
