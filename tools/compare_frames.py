#!/usr/bin/env python3
"""How much a rendered preview (out/preview.png, a hysteroscope view) looks
like real in-vivo endoscopy: the same image statistics, measured the same
way, on crops of real endoscopic and laparoscopic frames and on the preview.

Statistics (one function each; a crop and the preview go through the same code):
  colour     HSV hue (18 bins of 20 deg) and saturation (10 bins) histograms
             over the pixels not near black (V > 0.08); the mean colour (mean
             RGB of those pixels), its hue and saturation; the S-weighted
             circular mean of the pixels' hues; their 5th and 95th percentile
             about that mean. Hues are signed degrees (-180..180): reds wrap.
  highlights specular highlight = V >= 0.9 and S <= 0.25 (bright, nearly
             white): fraction of the image; spots (8-connected components):
             count, median and largest area as fractions of the image.
  radial     luminance (Rec. 709 luma) against the distance from the image
             centre, the real frames' proxy for distance from the scope (rough:
             crops are off-centre): Spearman correlation; mean luminance of 5
             equal-width rings out to the corners over the image's mean.
  depth      preview, --depth: Spearman correlation of depth and luminance
             over the pixels with depth > 0 (a fixed-seed sample).
  spectrum   image scaled to a shorter side of 128 px (so frequencies are per
             view), local contrast = luminance minus its Gaussian blur (sigma
             8 px), Hann-windowed: the radially averaged power spectrum's
             energy fraction in the octaves 4-8, 8-16, 16-32, 32-64 cycles
             per shorter side, and its log-log slope over 8-64.
  facets     preview, --facets and --facet-names: mean colour of each facet's
             pixels, its hue and saturation (under 200 pixels: skipped).

Targets (--check; exits 1 with one line per miss, and lists what passed):
highlights 0.2%..5% of the preview, median spot < 0.05% of the image and
largest < 1%; depth-luminance correlation <= -0.5 (when --depth is given);
every facet's mean colour hue within the real frames' pixel hue range (5th to
95th percentile, pooled over the frames) and saturation >= 0.15.

The real frames are read from ../shared/data/tissues or database/sources
(see the PROVENANCE.md and LICENSES.md there); where a frame is missing,
their figures come from tools/frames_reference.json (--write-reference).

Usage:
  tools/compare_frames.py --write-reference
  tools/compare_frames.py [PREVIEW.png] [--depth D.png] [--depth-unit 0.01]
      [--facets F.png --facet-names wall,myoma-front,...] [--per-frame]
      [--check] [--json OUT]
"""

import argparse
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import pyenv  # noqa: E402

pyenv.ensure(["numpy", "pillow", "scipy"], __file__)

import numpy as np  # noqa: E402
from PIL import Image  # noqa: E402
from scipy import ndimage, stats  # noqa: E402

ROOT = pyenv.ROOT
SOURCES = [ROOT.parent / "shared" / "data" / "tissues", ROOT / "database" / "sources"]
REFERENCE = ROOT / "tools" / "frames_reference.json"

# In-vivo frames: file, crop box (x0, y0, x1, y1) in pixels, free of figure
# borders, scope masks, burned-in text and instruments, and what it shows.
# Left out: endoslam_* (ex-vivo porcine organs, synthetic renders, figures
# with labels), cat4_*, ihc.png, layered_wall.png (histology), retina.jpg
# (a fundus photograph, not endoscopy).
FRAMES = [
    ("cat1_colonoscopy_mucosa_pitpattern_polypgen_b.png", (0, 0, 280, 282),
     "PolypGen colonoscopy: mucosa, vessels, pit pattern (scope mask corner cut)"),
    ("cat1_colonoscopy_sessile_polyp_polypgen_c.png", (0, 0, 340, 272),
     "PolypGen colonoscopy: sessile polyp on a fold, dark lumen, wet glints"),
    ("cat1_robotic_gastrectomy_omentum_fat_serosa_sisvse_a.png", (124, 0, 278, 215),
     "SISVSE laparoscopy: gastric serosa over omental fat (suture, gauze cut)"),
    ("cat1_robotic_gastrectomy_stomach_serosa_mesentery_sisvse_b.png", (0, 76, 252, 190),
     "SISVSE laparoscopy: gastric serosa, mesentery with vessels (gauze cut)"),
    ("cat1_colonoscopy_polyp_hyperkvasir.png", (112, 14, 396, 344),
     "HyperKvasir colonoscopy: large polyp, lumen, highlights (text, mask cut)"),
]

DARK_V = 0.08                    # near-black pixels are left out of colour
HIGHLIGHT_V, HIGHLIGHT_S = 0.9, 0.25
SAMPLE = 40000                   # pixels sampled for rank correlations
SEED = 0
SPECTRUM_SIDE, BLUR_SIGMA = 128, 8.0
BANDS = [4, 8, 16, 32, 64]       # cycles per shorter side
MIN_FACET_PIXELS = 200
TARGETS = {"highlight": (0.002, 0.05), "spot_median": 0.0005, "spot_largest": 0.01,
           "depth_spearman": -0.5, "facet_sat": 0.15}


def signed(deg):
    """Hue in degrees folded into -180..180."""
    return (np.asarray(deg) + 180.0) % 360.0 - 180.0


def circ_mean(deg, weights=None):
    rad = np.radians(deg)
    return float(np.degrees(np.arctan2(np.average(np.sin(rad), weights=weights),
                                       np.average(np.cos(rad), weights=weights))))


def circ_percentiles(deg, lo=5, hi=95):
    """Percentiles of hues measured about their circular mean."""
    centre = circ_mean(deg)
    p = np.percentile(signed(np.asarray(deg) - centre), [lo, hi]) + centre
    return [float(signed(p[0])), float(signed(p[1]))]


def hue_inside(h, lo, hi):
    return (h - lo) % 360.0 <= (hi - lo) % 360.0


def hsv(rgb):
    """Hue (degrees 0..360), saturation and value of an RGB array in 0..1."""
    mx, mn = rgb.max(-1), rgb.min(-1)
    chroma = mx - mn
    s = np.where(mx > 0, chroma / np.maximum(mx, 1e-12), 0.0)
    c = np.maximum(chroma, 1e-12)
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    h = np.where(mx == r, ((g - b) / c) % 6, np.where(mx == g, (b - r) / c + 2, (r - g) / c + 4))
    return np.where(chroma > 0, h * 60.0, 0.0), s, mx


def luma(rgb):
    return rgb @ np.array([0.2126, 0.7152, 0.0722])


def load_rgb(path, crop=None):
    """An image as floats 0..1, RGB, optionally cropped; exits naming the file."""
    try:
        img = Image.open(path).convert("RGB")
    except OSError as err:
        sys.exit(f"compare_frames: cannot read {path}: {err}")
    if crop:
        if crop[2] > img.width or crop[3] > img.height:
            sys.exit(f"compare_frames: crop {crop} is outside {path} ({img.width}x{img.height})")
        img = img.crop(crop)
    return np.asarray(img, dtype=np.float64) / 255.0


def colour_stats(rgb):
    """Hue and saturation histograms, mean colour, hue percentiles."""
    h, s, v = hsv(rgb)
    keep = (v > DARK_V) if (v > DARK_V).any() else np.ones(v.shape, bool)
    h, s = h[keep], s[keep]
    mean_rgb = rgb[keep].mean(0)
    mh, ms, _ = hsv(mean_rgb[None, :])
    return {"hue_hist": (np.histogram(h, 18, (0, 360))[0] / h.size).tolist(),
            "sat_hist": (np.histogram(s, 10, (0, 1))[0] / s.size).tolist(),
            "mean_rgb": mean_rgb.tolist(), "mean_hue": float(signed(mh[0])), "mean_sat": float(ms[0]),
            "hue_circmean": circ_mean(h, weights=s + 1e-9),
            "hue_p5_p95": circ_percentiles(h)}, h


def highlight_stats(rgb):
    """Specular highlight fraction and the sizes of its 8-connected spots."""
    _, s, v = hsv(rgb)
    mask = (v >= HIGHLIGHT_V) & (s <= HIGHLIGHT_S)
    labels, n = ndimage.label(mask, structure=np.ones((3, 3)))
    areas = np.bincount(labels.ravel())[1:] / mask.size
    return {"highlight_fraction": float(mask.mean()), "spot_count": int(n),
            "spot_median": float(np.median(areas)) if n else 0.0,
            "spot_largest": float(areas.max()) if n else 0.0}


def spearman(a, b, rng):
    """Spearman rank correlation over a fixed-seed sample of pixel pairs."""
    if a.size > SAMPLE:
        pick = rng.choice(a.size, SAMPLE, replace=False)
        a, b = a[pick], b[pick]
    return float(stats.spearmanr(a, b).statistic)


def radial_stats(lum):
    """Luminance against the distance from the image centre (scope proxy)."""
    hgt, wid = lum.shape
    y, x = np.mgrid[:hgt, :wid]
    r = np.hypot(y - (hgt - 1) / 2, x - (wid - 1) / 2)
    r /= r.max()
    ring = np.minimum((r * 5).astype(int), 4)
    profile = np.bincount(ring.ravel(), lum.ravel(), 5) / np.bincount(ring.ravel(), minlength=5)
    return {"radial_spearman": spearman(r.ravel(), lum.ravel(), np.random.default_rng(SEED)),
            "radial_profile": (profile / lum.mean()).tolist()}


def depth_stats(lum, depth):
    """Spearman correlation of depth and luminance where there is a surface."""
    surface = depth > 0
    if surface.sum() < 2:
        return {"depth_spearman": float("nan"), "depth_pixels": int(surface.sum())}
    d = depth[surface]
    return {"depth_spearman": spearman(d, lum[surface], np.random.default_rng(SEED)),
            "depth_pixels": int(surface.sum()), "depth_median": float(np.median(d))}


def spectrum_stats(lum):
    """Octave energy fractions and log-log slope of the local contrast's spectrum."""
    hgt, wid = lum.shape
    k = SPECTRUM_SIDE / min(hgt, wid)
    size = (max(1, round(wid * k)), max(1, round(hgt * k)))
    img = np.asarray(Image.fromarray(lum.astype(np.float32)).resize(
        size, Image.BOX if k < 1 else Image.BICUBIC), dtype=np.float64)
    local = img - ndimage.gaussian_filter(img, BLUR_SIGMA, mode="reflect")
    local *= np.hanning(img.shape[0])[:, None] * np.hanning(img.shape[1])[None, :]
    power = np.abs(np.fft.fft2(local)) ** 2
    f = np.hypot(*np.meshgrid(np.fft.fftfreq(img.shape[0]), np.fft.fftfreq(img.shape[1]),
                              indexing="ij")) * SPECTRUM_SIDE
    energy = np.array([power[(f >= lo) & ((f <= hi) if hi == BANDS[-1] else (f < hi))].sum()
                       for lo, hi in zip(BANDS, BANDS[1:])])
    edges = np.geomspace(8, 64, 13)
    which = np.digitize(f.ravel(), edges) - 1
    ok = (which >= 0) & (which < 12)
    mean_p = np.bincount(which[ok], power.ravel()[ok], 12) / np.maximum(np.bincount(which[ok], minlength=12), 1)
    mean_f = np.sqrt(edges[:-1] * edges[1:])
    good = mean_p > 0
    slope = np.polyfit(np.log(mean_f[good]), np.log(mean_p[good]), 1)[0] if good.sum() > 1 else float("nan")
    return {"band_fractions": (energy / max(energy.sum(), 1e-30)).tolist(), "spectrum_slope": float(slope)}


def facet_stats(rgb, facets, names):
    """Mean rendered colour, hue and saturation of each named facet."""
    out, unnamed = {}, np.unique(facets[facets > len(names)])
    if unnamed.size:
        print(f"compare_frames: facet ids {unnamed.tolist()} have no name; left out", file=sys.stderr)
    for i, name in enumerate(names, start=1):
        sel = facets == i
        if sel.sum() < MIN_FACET_PIXELS:
            out[name] = {"pixels": int(sel.sum()), "skipped": True}
            continue
        mean = rgb[sel].mean(0)
        h, s, _ = hsv(mean[None, :])
        out[name] = {"pixels": int(sel.sum()), "mean_rgb": mean.tolist(),
                     "hue": float(signed(h[0])), "sat": float(s[0])}
    return out


def measure(rgb):
    """Every statistic of one image, and its pixels' hues (for pooling)."""
    colour, hues = colour_stats(rgb)
    lum = luma(rgb)
    return {**colour, **highlight_stats(rgb), **radial_stats(lum), **spectrum_stats(lum)}, hues


def find_frame(name):
    return next((d / name for d in SOURCES if (d / name).exists()), None)


def measure_real(required):
    """The real frames' statistics and their aggregate; None if a frame is
    missing (unless required, when that is an error)."""
    paths = [find_frame(name) for name, _, _ in FRAMES]
    missing = [n for (n, _, _), p in zip(FRAMES, paths) if p is None]
    if missing:
        if required:
            sys.exit(f"compare_frames: {', '.join(missing)} not found in " + " or ".join(map(str, SOURCES)))
        return None
    frames, pooled, rng = [], [], np.random.default_rng(SEED)
    for (name, crop, what), path in zip(FRAMES, paths):
        figures, hues = measure(load_rgb(path, crop))
        frames.append({"file": name, "crop": list(crop), "what": what, "stats": figures})
        pooled.append(rng.choice(hues, min(hues.size, 20000), replace=False))  # frames weigh alike
    pooled = np.concatenate(pooled)
    means = np.array([f["stats"]["mean_hue"] for f in frames])
    centre = circ_mean(means)
    col = lambda key: np.array([f["stats"][key] for f in frames])  # noqa: E731
    aggregate = {
        "pixel_hue_p5_p95": circ_percentiles(pooled),
        "mean_hue_range": [float(signed(centre + signed(means - centre).min())),
                           float(signed(centre + signed(means - centre).max()))],
        "highlight_fraction_range": [float(col("highlight_fraction").min()), float(col("highlight_fraction").max())],
        "radial_spearman_range": [float(col("radial_spearman").min()), float(col("radial_spearman").max())],
        "band_fractions_median": np.median(col("band_fractions"), 0).tolist(),
        "band_fractions_range": [col("band_fractions").min(0).tolist(), col("band_fractions").max(0).tolist()],
    }
    return {"frames": frames, "aggregate": aggregate}


def read_map(path, shape, what):
    """A greyscale PNG (8- or 16-bit) as integers, the preview's size."""
    try:
        img = Image.open(path)
    except OSError as err:
        sys.exit(f"compare_frames: cannot read {what} {path}: {err}")
    if img.mode not in ("L", "I", "I;16", "I;16B", "I;16L", "P"):
        sys.exit(f"compare_frames: {what} {path} is {img.mode}, not a greyscale PNG")
    data = np.asarray(img).astype(np.int64)
    if data.shape != shape:
        sys.exit(f"compare_frames: {what} {path} is {data.shape[1]}x{data.shape[0]}, "
                 f"the preview {shape[1]}x{shape[0]}")
    return data


def measure_preview(args):
    rgb = load_rgb(args.preview)
    figures, _ = measure(rgb)
    if args.depth:
        figures.update(depth_stats(luma(rgb), read_map(args.depth, rgb.shape[:2], "depth map") * args.depth_unit))
    if args.facets:
        if not args.facet_names:
            sys.exit("compare_frames: --facets needs --facet-names")
        figures["facets"] = facet_stats(rgb, read_map(args.facets, rgb.shape[:2], "facet map"),
                                        args.facet_names.split(","))
    return figures


def rows(figures):
    """(label, value) rows of one image's figures, lists flattened."""
    out = [(f"hue {20 * i}-{20 * i + 20} deg, share %", 100 * v) for i, v in enumerate(figures["hue_hist"])]
    out += [(f"saturation {i / 10:.1f}-{(i + 1) / 10:.1f}, share %", 100 * v) for i, v in enumerate(figures["sat_hist"])]
    out += [("mean colour hue, deg", figures["mean_hue"]), ("mean colour saturation", figures["mean_sat"]),
            ("hue circular mean (S-weighted), deg", figures["hue_circmean"]),
            ("pixel hue 5th pct, deg", figures["hue_p5_p95"][0]), ("pixel hue 95th pct, deg", figures["hue_p5_p95"][1]),
            ("highlight fraction %", 100 * figures["highlight_fraction"]), ("highlight spots", figures["spot_count"]),
            ("median spot, % of image", 100 * figures["spot_median"]),
            ("largest spot, % of image", 100 * figures["spot_largest"]),
            ("luminance-radius Spearman", figures["radial_spearman"])]
    out += [(f"luminance ring {i + 1}/5 / mean", v) for i, v in enumerate(figures["radial_profile"])]
    out += [(f"contrast energy {lo}-{hi} cyc %", 100 * v)
            for lo, hi, v in zip(BANDS, BANDS[1:], figures["band_fractions"])]
    out += [("contrast spectrum slope", figures["spectrum_slope"])]
    if "depth_spearman" in figures:
        out += [("depth-luminance Spearman", figures["depth_spearman"]), ("depth pixels", figures["depth_pixels"])]
    for name, f in figures.get("facets", {}).items():
        out += [(f"facet {name}: pixels", f["pixels"])]
        if not f.get("skipped"):
            out += [(f"facet {name}: hue, deg", f["hue"]), (f"facet {name}: saturation", f["sat"])]
    return out


def fmt(v):
    if v is None:
        return "-"
    if isinstance(v, int):
        return str(v)
    return "nan" if v != v else f"{v:.3g}" if abs(v) < 100 else f"{v:.0f}"


def print_table(real, preview, per_frame):
    real_rows = [dict(rows(f["stats"])) for f in real["frames"]]
    labels = [label for label, _ in rows(preview)] if preview else list(real_rows[0])
    head = ["statistic", "real median", "real range"]
    head += [f["file"].replace("cat1_", "").replace(".png", "") for f in real["frames"]] if per_frame else []
    head += ["preview"] if preview else []
    print("| " + " | ".join(head) + " |\n|" + "---|" * len(head))
    prev = dict(rows(preview)) if preview else {}
    for label in labels:
        vals = [r[label] for r in real_rows if label in r]
        if label.endswith("share %") and max(vals + [prev.get(label, 0)]) < 1:
            continue  # histogram bins empty (under 1%) everywhere
        cells = [fmt(float(np.median(vals))), f"{fmt(min(vals))}..{fmt(max(vals))}"] if vals else ["-", "-"]
        cells += [fmt(r.get(label)) for r in real_rows] if per_frame else []
        cells += [fmt(prev.get(label))] if preview else []
        print(f"| {label} | " + " | ".join(cells) + " |")
    agg = real["aggregate"]
    lo, hi = agg["pixel_hue_p5_p95"]
    print(f"\nreal frames: pixel hue 5th..95th pct {lo:.1f}..{hi:.1f} deg, mean colour hue "
          f"{agg['mean_hue_range'][0]:.1f}..{agg['mean_hue_range'][1]:.1f} deg")


def check(preview, real):
    """One line per target, PASS or FAIL; the failures."""
    lines, failed = [], []

    def target(ok, text):
        lines.append(("PASS " if ok else "FAIL ") + text)
        failed.extend([] if ok else [text])

    lo, hi = TARGETS["highlight"]
    hf = preview["highlight_fraction"]
    target(lo <= hf <= hi, f"highlight fraction {100 * hf:.3f}% in {100 * lo:.1f}%..{100 * hi:.0f}%")
    target(preview["spot_count"] > 0 and preview["spot_median"] < TARGETS["spot_median"],
           f"median highlight spot {100 * preview['spot_median']:.4f}% of the image "
           f"< {100 * TARGETS['spot_median']:.2f}% ({preview['spot_count']} spots)")
    target(preview["spot_count"] > 0 and preview["spot_largest"] < TARGETS["spot_largest"],
           f"largest highlight spot {100 * preview['spot_largest']:.4f}% < {100 * TARGETS['spot_largest']:.0f}%")
    if "depth_spearman" in preview:
        d = preview["depth_spearman"]
        target(d <= TARGETS["depth_spearman"], f"depth-luminance Spearman {d:.3f} <= {TARGETS['depth_spearman']}")
    hlo, hhi = real["aggregate"]["pixel_hue_p5_p95"]
    for name, f in preview.get("facets", {}).items():
        if f.get("skipped"):
            lines.append(f"SKIP facet {name}: {f['pixels']} pixels < {MIN_FACET_PIXELS}")
            continue
        target(hue_inside(f["hue"], hlo, hhi), f"facet {name} hue {f['hue']:.1f} deg in the in-vivo {hlo:.1f}..{hhi:.1f}")
        target(f["sat"] >= TARGETS["facet_sat"], f"facet {name} saturation {f['sat']:.3f} >= {TARGETS['facet_sat']}")
    print("\n" + "\n".join(lines))
    return failed


def rounded(x):
    """Figures to 5 significant digits, to keep the reference small."""
    if isinstance(x, float):
        return float(f"{x:.5g}")
    if isinstance(x, dict):
        return {k: rounded(v) for k, v in x.items()}
    if isinstance(x, list):
        return [rounded(v) for v in x]
    return x


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("preview", nargs="?", type=Path, help="the rendered preview (e.g. out/preview.png)")
    parser.add_argument("--depth", type=Path, help="16-bit greyscale PNG, distance from the eye, 0 = no surface")
    parser.add_argument("--depth-unit", type=float, default=0.01, help="depth per PNG unit (default 0.01)")
    parser.add_argument("--facets", type=Path, help="8-bit greyscale PNG: 0 = background, i = the i-th facet name")
    parser.add_argument("--facet-names", help="comma-separated facet names, in the facet map's order from 1")
    parser.add_argument("--write-reference", action="store_true", help=f"measure the real frames into {REFERENCE.name}")
    parser.add_argument("--reference", type=Path, default=REFERENCE, help="the reference json to read or write")
    parser.add_argument("--per-frame", action="store_true", help="one column per real frame too")
    parser.add_argument("--check", action="store_true", help="exit 1 when the preview misses a target")
    parser.add_argument("--json", type=Path, help="write every figure here")
    args = parser.parse_args()
    if args.check and not args.preview:
        parser.error("--check needs a PREVIEW")

    real = measure_real(required=args.write_reference)
    if args.write_reference:
        args.reference.write_text(json.dumps(rounded(real), separators=(",", ":")) + "\n")
        print(f"compare_frames: wrote {args.reference} ({args.reference.stat().st_size} bytes)")
    elif real is None:
        if not args.reference.exists():
            sys.exit(f"compare_frames: the real frames are not in {' or '.join(map(str, SOURCES))} "
                     f"and {args.reference} is missing")
        print(f"compare_frames: real frames' figures from {args.reference}")
        real = json.loads(args.reference.read_text())
    preview = measure_preview(args) if args.preview else None
    print_table(real, preview, args.per_frame)
    if args.json:
        args.json.write_text(json.dumps({"real": real, "preview": preview}, indent=1))
    if args.check and check(preview, real):
        sys.exit(1)


if __name__ == "__main__":
    main()
