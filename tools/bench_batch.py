#!/usr/bin/env python3
"""Issue 24's overhead figure: N seeded variants of the default scene
baked by `python -m organtex.batch --local CPUS` (each scene a Ray task)
against a plain serial loop of `organtex bake` on the same files, on this
machine. Prints both wall times, Ray's own start-up, the ratio, and
checks that the batch's scene.glb files are the CLI's byte for byte.

Usage: tools/bench_batch.py [--variants 12] [--cpus 2] [--cpus-per-task 1]
Needs the Python package installed in target/pyorgantex (tools/test.sh
makes it).
"""

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PYTHON = ROOT / "target" / "pyorgantex" / "bin" / "python"
ORGANTEX = ROOT / "target" / "release" / "organtex"


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--variants", type=int, default=12)
    p.add_argument("--cpus", type=int, default=2)
    p.add_argument("--cpus-per-task", type=float, default=1.0)
    args = p.parse_args()
    with tempfile.TemporaryDirectory() as d:
        d = Path(d)
        start = time.monotonic()
        subprocess.run([PYTHON, "-m", "organtex.batch", ROOT / "scenes" / "hysteroscopy_myomas.toml",
                        "-o", d / "ray", "--vary", str(args.variants), "--local", str(args.cpus),
                        "--cpus-per-task", str(args.cpus_per_task), "--quiet"], check=True)
        ray_wall = time.monotonic() - start
        summary = json.loads((d / "ray" / "summary.json").read_text())
        variants = sorted((d / "ray" / "variants").glob("*.toml"))
        start = time.monotonic()
        for v in variants:
            subprocess.run([ORGANTEX, "bake", v, "-o", d / "cli" / v.stem], check=True,
                           capture_output=True)
        serial = time.monotonic() - start
        same = all((d / "ray" / v.stem / "scene.glb").read_bytes() == (d / "cli" / v.stem / "scene.glb").read_bytes()
                   for v in variants)
    print(f"{len(variants)} variants: Ray batch {ray_wall:.1f} s (Ray start {summary['ray_start_seconds']:.1f} s, "
          f"{summary['ok']} ok, {summary['failed']} failed), serial CLI loop {serial:.1f} s, "
          f"ratio {ray_wall / serial:.3f}; scene.glb identical: {same}")
    return 0 if same and summary["failed"] == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
