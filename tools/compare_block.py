#!/usr/bin/env python3
"""Slices of organtex's solid texture blocks against its own 2D synthesis.

The 3D block synthesis issue asks that slices of a block along x, y and z
score within 1.5x of the 2D synthesiser's coherence and completeness on the
same exemplar. For each exemplar crop (the top-left N x N of a database
photograph, as tests/block.rs takes them) this runs the 2D synthesiser
(`organtex synth --tileable`, N x N, seeds 0-2, median figures, measured by
`organtex synth-quality`) and each block method (`organtex synth3d --size
N`, which measures four slices per axis), and prints every axis's figures,
their ratio to 2D, the tiling seam and the time; "missed" marks an axis
over 1.5x of 2D or with a seam over 1.15 (the issue's targets).

Usage: tools/compare_block.py [--sizes 64 128] [--methods fnpts optimize]
                              [--organtex target/release/organtex] [IMAGE ...]
  default images: the database's gravel and ihc photographs.
Exits 1 if a block fails to synthesise; the ratios are reported, not judged.
"""

import argparse
import json
import re
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SOURCES = ROOT / "database" / "sources"
LIMIT = 1.5
NUMBER = r"(-?[\d.]+|NaN|inf)"
SLICE = re.compile(rf"slices across (\w): coherence {NUMBER}, completeness {NUMBER}, tiling seam {NUMBER}")
TIME = re.compile(r"exemplar\(s\) in ([\d.]+) s$", re.M)
SEAM_LIMIT = 1.15


def run(cmd):
    out = subprocess.run([str(c) for c in cmd], capture_output=True, text=True)
    if out.returncode != 0:
        sys.exit(f"compare_block: {' '.join(map(str, cmd))} failed:\n{out.stderr.strip()}")
    return out.stdout


def reference(organtex, image, side, tmp):
    """The 2D synthesiser's median coherence and completeness over 3 seeds."""
    crop = f"0,0,{side},{side}"
    figures = []
    for seed in range(3):
        texture = tmp / f"flat_{seed}.png"
        run([organtex, "synth", image, "--crop", crop, "--size", side, "--tileable", "--seed", seed, "-o", texture])
        figures.append(json.loads(run([organtex, "synth-quality", image, texture, "--crop", crop])))
    return (statistics.median(f["coherence"] for f in figures),
            statistics.median(f["completeness"] for f in figures))


def block(organtex, image, side, method, tmp):
    """Seconds, and per axis (axis, coherence, completeness, seam)."""
    out = run([organtex, "synth3d", image, "--crop", f"0,0,{side},{side}", "--size", side,
               "--method", method, "-o", tmp / "block.nrrd"])
    axes = [(a, float(c), float(k), float(s)) for a, c, k, s in SLICE.findall(out)]
    seconds = TIME.search(out)
    if len(axes) != 3 or not seconds:
        sys.exit(f"compare_block: could not read synth3d's figures from:\n{out}")
    return float(seconds.group(1)), axes


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("images", nargs="*", type=Path)
    parser.add_argument("--sizes", nargs="+", type=int, default=[64, 128])
    parser.add_argument("--methods", nargs="+", default=["fnpts", "optimize"])
    parser.add_argument("--organtex", default=str(ROOT / "target" / "release" / "organtex"))
    args = parser.parse_args()
    images = args.images or [SOURCES / "gravel.png", SOURCES / "ihc.png"]

    print(f"{'exemplar':<12}{'size':>5}  {'method':<9}{'time s':>8}  {'axis':<5}{'coh':>7}{'comp':>7}"
          f"{'coh/2D':>8}{'comp/2D':>8}{'seam':>6}")
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        for image in images:
            for side in args.sizes:
                coh2, comp2 = reference(args.organtex, image, side, tmp)
                print(f"{image.stem:<12}{side:>5}  {'2D':<9}{'':>8}  {'':<5}{coh2:7.2f}{comp2:7.2f}")
                for method in args.methods:
                    seconds, axes = block(args.organtex, image, side, method, tmp)
                    for k, (axis, coh, comp, seam) in enumerate(axes):
                        within = coh <= LIMIT * coh2 and comp <= LIMIT * comp2 and seam <= SEAM_LIMIT
                        print(f"{image.stem:<12}{side:>5}  {method:<9}{f'{seconds:.2f}' if k == 0 else '':>8}  {axis:<5}"
                              f"{coh:7.2f}{comp:7.2f}{coh / coh2:8.2f}{comp / comp2:8.2f}{seam:6.2f}"
                              f"{'' if within else '  missed'}", flush=True)


if __name__ == "__main__":
    main()
