#!/usr/bin/env python3
"""Cross-section morphing (seed 003) against ground truth: a real brain MRI
template (tests/data/volumes). Slices every SPACING voxels are the exemplar
"photographs"; the slices held back between them are the truth. Each
held-back slice is predicted by

  organtex   `organtex morph --grid` (BSP, warps, eq. 4, histogram matching)
  nearest    the nearest exemplar, copied
  crossfade  linear cross-fading of the two bounding exemplars

and scored by
  blurred RMS   RMS difference after a Gaussian blur of sigma 2 px: is the
                structure where it should be (lower is better)
  detail        mean gradient magnitude over the truth's: is the detail
                kept (1 is right; cross-fading blurs it away)
the RMS over the tissue of either (above 8, grown by 4 px), the detail
over the whole slice. Also the
largest difference on an exemplar plane (away from the border), and the
evaluation speed organtex reports.

    python3 tools/compare_morph.py --organtex target/release/organtex
    python3 tools/compare_morph.py --quick        # fewer held-back slices
    python3 tools/compare_morph.py --uterus       # also the bundled uterus scene
    python3 tools/compare_morph.py --write-test-slices tests/data/morph
"""

import argparse
import gzip
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import pyenv  # noqa: E402

pyenv.ensure(["numpy", "scipy", "pillow"], __file__)

import numpy as np  # noqa: E402
from PIL import Image  # noqa: E402
from scipy import ndimage  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
VOLUME = ROOT / "tests" / "data" / "volumes" / "mni_icbm152_t1_tal_nlin_sym_09a_converted.nii.gz"


def read_nifti(path):
    """A uint8 NIfTI-1 volume as an array indexed [z, y, x]."""
    raw = gzip.open(path).read()
    header = np.frombuffer(raw[:348], dtype=np.uint8)
    dims = np.frombuffer(raw[40:56], dtype="<i2")
    dtype = int(np.frombuffer(raw[70:72], dtype="<i2")[0])
    offset = int(np.frombuffer(raw[108:112], dtype="<f4")[0])
    if int(np.frombuffer(header[:4].tobytes(), dtype="<i4")[0]) != 348 or dtype != 2:
        sys.exit(f"{path}: not a little-endian uint8 NIfTI-1 volume")
    nx, ny, nz = (int(d) for d in dims[1:4])
    data = np.frombuffer(raw[offset:offset + nx * ny * nz], dtype=np.uint8)
    return data.reshape(nz, ny, nx)


def box_obj(path, size):
    sx, sy, sz = size
    v = [(x, y, z) for z in (0, sz) for y in (0, sy) for x in (0, sx)]
    # Outward counter-clockwise faces of the box with corners v[0..8].
    f = [(1, 3, 2), (2, 3, 4), (5, 6, 8), (5, 8, 7), (1, 2, 6), (1, 6, 5),
         (3, 7, 8), (3, 8, 4), (1, 5, 7), (1, 7, 3), (2, 4, 8), (2, 8, 6)]
    with open(path, "w") as out:
        for p in v:
            out.write("v %g %g %g\n" % p)
        for t in f:
            out.write("f %d %d %d\n" % t)


def write_sections(vol, zs, folder):
    folder.mkdir(parents=True, exist_ok=True)
    with open(folder / "sections.toml", "w") as toml:
        for z in zs:
            name = f"slice_{z:03d}.png"
            Image.fromarray(vol[z]).save(folder / name)
            toml.write(f'[[exemplar]]\nimage = "{name}"\norigin = [0.0, 0.0, {z + 0.5}]\n'
                       f"u = [1.0, 0.0, 0.0]\nv = [0.0, 1.0, 0.0]\n\n")
    nz, ny, nx = vol.shape
    box_obj(folder / "box.obj", (nx, ny, nz))


def run_grid(organtex, mesh, sections, grid, out, extra=()):
    """`organtex morph --grid`: the image (float RGB) and the JSON summary."""
    res = subprocess.run([organtex, "morph", str(mesh), "--sections", str(sections), "--grid", grid,
                          "-o", str(out), "--json", *extra], capture_output=True, text=True)
    if res.returncode != 0:
        sys.exit(f"organtex morph failed:\n{res.stderr}")
    return np.asarray(Image.open(out).convert("RGB"), dtype=np.float64), json.loads(res.stdout)


def morph_slice(organtex, folder, z, shape, extra):
    """The morph of the axial slice at voxel z (grey), and its summary."""
    ny, nx = shape
    img, summary = run_grid(organtex, folder / "box.obj", folder / "sections.toml",
                            f"0,0,{z + 0.5};1,0,0;0,1,0;{nx},{ny}", folder / f"morph_{z:03d}.png", extra)
    return img.mean(axis=2), summary


def gradient(img):
    gy, gx = np.gradient(img)
    return np.hypot(gx, gy)


def scores(pred, truth):
    region = ndimage.binary_dilation((truth > 8) | (pred > 8), iterations=4)
    blur = lambda a: ndimage.gaussian_filter(a, 2.0)  # noqa: E731
    rms = float(np.sqrt(np.mean((blur(pred) - blur(truth))[region] ** 2)))
    # Over the whole slice: the background has no gradient in either.
    detail = float(gradient(pred).mean() / gradient(truth).mean())
    return rms, detail


def uterus(organtex):
    """The bundled scene scenes/myoma_cuts.toml: the default uterus, two
    photographed cuts through the front myoma. No truth inside it; what is
    measured: each exemplar plane shows its photograph, the colour is
    continuous across the planes (the BSP's region boundaries), and the
    speed of a 512x512 cut."""
    result = {}
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        # The scene's cuts with its photographs decoded once, by PIL, into
        # PNGs: JPEG decoders differ by a level or two, and this measures
        # the morph, not the decoders.
        scene_sections = ROOT / "scenes" / "myoma_cuts" / "sections.toml"
        text = scene_sections.read_text()
        for name in ("../../database/sources/ihc.png", "he_nests.jpg"):
            png = Path(name).stem + ".png"
            Image.open(scene_sections.parent / name).convert("RGB").save(tmp / png)
            text = text.replace(f'"{name}"', f'"{png}"')
        sections = tmp / "sections.toml"
        sections.write_text(text)
        mesh = tmp / "uterus.obj"
        subprocess.run([organtex, "generate", "uterus", "--wall-thickness", "10", "--resolution", "5",
                        "-o", str(mesh)], check=True, capture_output=True)
        planes = [(tmp / "ihc.png", 8.0), (tmp / "he_nests.png", 12.0)]
        worst = 0.0
        for photo, y in planes:
            img = np.asarray(Image.open(photo).convert("RGB"), dtype=np.float64)
            h, w = img.shape[:2]
            got, _ = run_grid(organtex, mesh, sections, f"-25.6,{y},-1.5;0.1,0,0;0,0,0.1;{w},{h}", tmp / "p.png")
            worst = max(worst, float(np.abs(got - img)[3:-3, 3:-3].max()))
        result["largest_difference_on_exemplar_planes"] = worst
        # Rows along y through the myoma (x = 2.7), 0.05 apart, from y = 6
        # to 14: each row a line of 400 points along z.
        step = 0.05
        rows = int(8 / step)
        got, _ = run_grid(organtex, mesh, sections, f"2.7,6,18.7;0,0,0.03;0,{step},0;400,{rows}", tmp / "c.png")
        ys = 6 + (np.arange(rows) + 0.5) * step
        jumps = np.abs(np.diff(got, axis=0)).mean(axis=(1, 2))
        across = [jumps[int(np.searchsorted(ys, y)) - 1] for _, y in planes]
        result["jump_across_planes"] = [float(j) for j in across]
        result["jump_between_ordinary_rows_median"] = float(np.median(jumps))
        result["jump_between_ordinary_rows_max"] = float(jumps.max())
        speeds = []
        for _ in range(5):
            _, summary = run_grid(organtex, mesh, sections, "-12,-12,24.7;0.07,0,0;0,0.07,0;512,512", tmp / "s.png")
            speeds.append(summary["seconds"])
        result["cut_512_seconds_median"] = float(np.median(speeds))
    print("uterus (scenes/myoma_cuts.toml, two cuts through the front myoma):")
    print(f"  largest difference on an exemplar plane: {result['largest_difference_on_exemplar_planes']:.1f}/255")
    print(f"  mean jump between rows 0.05 apart: across the planes {', '.join(f'{j:.2f}' for j in across)}; "
          f"elsewhere median {result['jump_between_ordinary_rows_median']:.2f}, "
          f"max {result['jump_between_ordinary_rows_max']:.2f}")
    print(f"  512x512 cut: {1e3 * result['cut_512_seconds_median']:.1f} ms (median of 5)")
    return result


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--organtex", default=str(ROOT / "target" / "release" / "organtex"))
    ap.add_argument("--spacing", type=int, default=16, help="voxels between exemplars")
    ap.add_argument("--first", type=int, default=40, help="the first exemplar slice")
    ap.add_argument("--count", type=int, default=8, help="exemplars")
    ap.add_argument("--axis", choices=["z", "y", "x"], default="z",
                    help="slice across z (axial, the default), y (coronal) or x (sagittal)")
    ap.add_argument("--quick", action="store_true", help="hold back only the middle slice of each gap")
    ap.add_argument("--no-matching", action="store_true", help="organtex without histogram matching")
    ap.add_argument("--low-sigma", type=float, help="organtex --low-sigma")
    ap.add_argument("--json", type=Path, help="write the figures here")
    ap.add_argument("--write-test-slices", type=Path, metavar="DIR",
                    help="write three exemplar slices and the truth between them for the Rust tests, and stop")
    ap.add_argument("--uterus", action="store_true",
                    help="also measure the bundled uterus scene's morph (scenes/myoma_cuts.toml)")
    ap.add_argument("--check", action="store_true",
                    help="exit 1 unless the targets of issue 27 are met")
    args = ap.parse_args()

    vol = read_nifti(VOLUME)
    # Slices along the chosen axis become the first index.
    vol = {"z": vol, "y": vol.transpose(1, 0, 2), "x": vol.transpose(2, 0, 1)}[args.axis]
    if args.write_test_slices:
        # Slices 80, 96, 112 as exemplars; 88 and 104 held back.
        write_sections(vol, [80, 96, 112], args.write_test_slices)
        for z in (88, 104):
            Image.fromarray(vol[z]).save(args.write_test_slices / f"truth_{z:03d}.png")
        print(f"wrote {args.write_test_slices}")
        return

    zs = [args.first + k * args.spacing for k in range(args.count)]
    if zs[-1] >= vol.shape[0]:
        sys.exit(f"exemplars run past the volume's {vol.shape[0]} slices")
    extra = []
    if args.no_matching:
        extra.append("--no-matching")
    if args.low_sigma:
        extra += ["--low-sigma", str(args.low_sigma)]
    offsets = [args.spacing // 2] if args.quick else [args.spacing // 4, args.spacing // 2, 3 * args.spacing // 4]
    rows = {m: [] for m in ("organtex", "nearest", "crossfade")}
    speeds = []
    precompute = []
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        write_sections(vol, zs, folder)
        for a, b in zip(zs, zs[1:]):
            for off in offsets:
                z = a + off
                truth = vol[z].astype(np.float64)
                pred, summary = morph_slice(args.organtex, folder, z, truth.shape, extra)
                speeds.append(summary["points_per_second"])
                precompute.append(summary["precompute_seconds"])
                alpha = off / (b - a)
                nearest = vol[a if alpha < 0.5 else b].astype(np.float64)
                fade = (1 - alpha) * vol[a] + alpha * vol[b].astype(np.float64)
                for name, p in (("organtex", pred), ("nearest", nearest), ("crossfade", fade)):
                    rows[name].append(scores(p, truth))
        plane_errors = []
        for z in zs[1:-1:2]:
            pred, _ = morph_slice(args.organtex, folder, z, vol[z].shape, extra)
            diff = np.abs(pred - vol[z].astype(np.float64))[3:-3, 3:-3]
            plane_errors.append(float(diff.max()))

    result = {"axis": args.axis, "spacing": args.spacing, "exemplars": zs, "held_back": len(rows["organtex"]),
              "largest_difference_on_exemplar_planes": max(plane_errors),
              "points_per_second_median": float(np.median(speeds)),
              "precompute_seconds_median": float(np.median(precompute)), "methods": {}}
    print(f"{len(rows['organtex'])} held-back slices across {args.axis}, exemplars {args.spacing} apart "
          f"({zs[0]}..{zs[-1]})")
    print(f"{'method':<12}{'blurred RMS':>14}{'detail':>10}")
    for name, r in rows.items():
        rms = float(np.mean([x[0] for x in r]))
        detail = float(np.mean([x[1] for x in r]))
        result["methods"][name] = {"blurred_rms": rms, "detail_ratio": detail,
                                   "detail_ratio_min": float(min(x[1] for x in r)),
                                   "detail_ratio_max": float(max(x[1] for x in r))}
        print(f"{name:<12}{rms:>14.3f}{detail:>10.3f}")
    print(f"largest difference on an exemplar plane: {max(plane_errors):.1f}/255")
    print(f"organtex: {result['points_per_second_median'] / 1e6:.2f} M points/s (median), "
          f"precompute {result['precompute_seconds_median']:.2f} s")
    if args.uterus:
        result["uterus"] = uterus(args.organtex)
    if args.json:
        args.json.write_text(json.dumps(result, indent=2))
    if args.check:
        m = result["methods"]
        ok = (m["organtex"]["blurred_rms"] < m["nearest"]["blurred_rms"]
              and m["organtex"]["blurred_rms"] <= 1.2 * m["crossfade"]["blurred_rms"]
              and 0.85 <= m["organtex"]["detail_ratio"] <= 1.2
              and result["largest_difference_on_exemplar_planes"] <= 2.0
              and (not args.uterus or (result["uterus"]["largest_difference_on_exemplar_planes"] <= 2.0
                                       and max(result["uterus"]["jump_across_planes"])
                                       <= result["uterus"]["jump_between_ordinary_rows_max"])))
        print("targets:", "met" if ok else "MISSED")
        sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
