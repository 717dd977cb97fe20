#!/usr/bin/env python3
"""Compare organtex's FNPTS synthesis with Embark's texture-synthesis.

Both tools make tileable textures from the same crops (128 -> 256 and
256 -> 512 pixels) with their default settings; each run is timed as a whole
process (load, synthesis, save), the median of --runs runs. Quality is
measured the same way for both (`organtex synth-quality`: coherence,
completeness, seam; lower coherence and completeness are better, seam 1 is
seamless).

Usage: tools/compare_synth.py [--runs 3] [--quick] [IMAGE ...]
  default images: the database's retina (a tissue crop) and ihc photographs,
  then gravel, brick and grass (tests/data/textures); extra IMAGE paths are cropped the same
  way (the centre square). --quick: ihc 128 -> 256 only.
Embark's CLI is installed into target/embark with `cargo install --locked
texture-synthesis-cli` when it is not on the PATH (a few minutes, once).
"""

import argparse
import json
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import pyenv  # noqa: E402

ROOT = pyenv.ROOT
REQUIREMENTS = ["pillow"]
SOURCES = ROOT / "database" / "sources"
# (image, crop centre as fractions of the image): retina on temporal tissue.
TEXTURES = ROOT / "tests" / "data" / "textures"
DEFAULTS = [(SOURCES / "retina.jpg", (0.62, 0.30)), (SOURCES / "ihc.png", (0.5, 0.5)),
            (TEXTURES / "gravel.png", (0.5, 0.5)), (TEXTURES / "brick.png", (0.5, 0.5)),
            (TEXTURES / "grass.png", (0.5, 0.5))]


def embark_binary():
    found = shutil.which("texture-synthesis")
    if found:
        return found
    local = ROOT / "target" / "embark" / "bin" / "texture-synthesis"
    if not local.exists():
        print("compare_synth: installing Embark's texture-synthesis-cli into target/embark", flush=True)
        subprocess.run(["cargo", "install", "--locked", "texture-synthesis-cli", "--root", str(local.parent.parent)],
                       check=True)
    return str(local)


def crop(image, centre, side, out):
    from PIL import Image

    im = Image.open(image).convert("RGB")
    cx, cy = int(centre[0] * im.width), int(centre[1] * im.height)
    x = min(max(cx - side // 2, 0), im.width - side)
    y = min(max(cy - side // 2, 0), im.height - side)
    im.crop((x, y, x + side, y + side)).save(out)


def timed(cmd, runs):
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        subprocess.run(cmd, check=True, capture_output=True)
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def quality(organtex, exemplar, texture):
    out = subprocess.run([organtex, "synth-quality", str(exemplar), str(texture)], check=True,
                         capture_output=True, text=True)
    return json.loads(out.stdout)


def main():
    pyenv.ensure(REQUIREMENTS, __file__)
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("images", nargs="*", type=Path)
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--organtex", default=str(ROOT / "target" / "release" / "organtex"))
    args = parser.parse_args()
    embark = embark_binary()
    images = DEFAULTS + [(p, (0.5, 0.5)) for p in args.images]
    sizes = [(128, 256), (256, 512)]
    if args.quick:
        images, sizes = [(SOURCES / "ihc.png", (0.5, 0.5))], [(128, 256)]

    print(f"{'image':<14}{'size':<11}{'tool':<10}{'time s':>8}{'coherence':>11}{'complete':>10}{'seam':>7}  organtex vs Embark")
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        for image, centre in images:
            for side, out_side in sizes:
                src = tmp / f"{image.stem}{side}.png"
                crop(image, centre, side, src)
                ours, theirs = tmp / "ours.png", tmp / "embark.png"
                t_ours = timed([args.organtex, "synth", str(src), "--size", str(out_side), "--tileable", "-o", str(ours)],
                               args.runs)
                t_emb = timed([embark, "--tiling", "--no-progress", "--out-size", str(out_side), "--out", str(theirs),
                               "generate", str(src)], args.runs)
                q_ours, q_emb = quality(args.organtex, src, ours), quality(args.organtex, src, theirs)
                label = f"{side}->{out_side}"
                verdict = (f"time x{t_ours / t_emb:.2f}, coherence {'better' if q_ours['coherence'] < q_emb['coherence'] else 'WORSE'}, "
                           f"completeness {'better' if q_ours['completeness'] < q_emb['completeness'] else 'WORSE'}")
                for tool, t, q, note in (("organtex", t_ours, q_ours, verdict), ("embark", t_emb, q_emb, "")):
                    print(f"{image.stem:<14}{label:<11}{tool:<10}{t:8.2f}{q['coherence']:11.2f}{q['completeness']:10.2f}"
                          f"{q['seam']:7.2f}  {note}")


if __name__ == "__main__":
    main()
