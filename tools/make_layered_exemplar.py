#!/usr/bin/env python3
"""Compose database/sources/layered_wall.png, the layered (depth-varying)
exemplar of issue 23, from three real histology photographs in
../shared/data/tissues (their licences in database/sources/LICENSES.md).

Its rows are depth, top = outer: a band of pink collagen stroma (H&E,
OpenSlide OS-1), then endometrial stroma with dense nuclei (IHC, EndoNuke
a), then a gland over loose stroma (IHC, EndoNuke b), each band cut from
its photograph at the exemplar's width and cross-faded into the next over
8 rows. Deterministic: the same sources give the same bytes.

Usage: tools/make_layered_exemplar.py [SHARED_TISSUES_DIR] [OUT_PNG]
"""
import sys
from pathlib import Path

from PIL import Image

WIDTH, BANDS, FADE = 192, [("cat4_he_epithelial_nests_in_stroma_openslide_os1.png", 40, (0, 0, 550, 115)),
                            ("cat4_ihc_endometrium_stroma_nuclei_endonuke_a.png", 44, (0, 120, 342, 225)),
                            ("cat4_ihc_endometrium_gland_stroma_endonuke_b.png", 44, (0, 0, 341, 120))], 8


def main():
    here = Path(__file__).resolve().parent.parent
    src = Path(sys.argv[1]) if len(sys.argv) > 1 else here.parent / "shared" / "data" / "tissues"
    out = Path(sys.argv[2]) if len(sys.argv) > 2 else here / "database" / "sources" / "layered_wall.png"
    height = sum(rows for _, rows, _ in BANDS)
    bands = []
    for name, rows, box in BANDS:
        img = Image.open(src / name).convert("RGB").crop(box)
        # Each band FADE rows taller, so neighbours overlap for the fade.
        bands.append(img.resize((WIDTH, rows + FADE), Image.LANCZOS))
    result = Image.new("RGB", (WIDTH, height))
    top = 0
    for i, (band, (_, rows, _)) in enumerate(zip(bands, BANDS)):
        # A band shows `rows` rows from `start` (after the rows the
        # previous band faded into); its last FADE rows fade into the next
        # band's first FADE.
        start = FADE if i > 0 else 0
        result.paste(band.crop((0, start, WIDTH, start + rows)), (0, top))
        if i + 1 < len(bands):
            for k in range(FADE):
                t = (k + 0.5) / FADE
                row = start + rows - FADE + k
                a = band.crop((0, row, WIDTH, row + 1))
                b = bands[i + 1].crop((0, k, WIDTH, k + 1))
                result.paste(Image.blend(a, b, t), (0, top + rows - FADE + k))
        top += rows
    out.parent.mkdir(parents=True, exist_ok=True)
    result.save(out, optimize=True)
    print(f"{out}: {WIDTH}x{height}")


if __name__ == "__main__":
    main()
