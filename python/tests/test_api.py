"""The Python API on real data: what the CLI's tests assert, through
organtex's numpy interface."""

import subprocess

import numpy as np
import pytest
from PIL import Image

import organtex


def test_the_bunny_unwraps_into_one_chart_without_flips(root):
    mesh = organtex.read_mesh(root / "tests/data/bunny.obj")
    assert mesh.vertices.shape == (28088, 3) and mesh.faces.shape == (56172, 3)
    calls = []
    uv, uv_faces, report = organtex.unwrap(mesh.vertices, mesh.faces,
                                           progress=lambda *a: calls.append(a))
    assert uv_faces.shape == mesh.faces.shape and uv.shape[1] == 2
    assert len(report["pieces"]) == 1 and report["pieces"][0]["charts"] == 1
    assert report["metrics"]["charts"] == 1 and report["metrics"]["flips"] == 0
    # No uv triangle is flipped: every signed area positive.
    a, b, c = (uv[uv_faces[:, k]] for k in range(3))
    signed = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    assert (signed > 0).all()
    assert calls and all(isinstance(s, str) for s, _, _ in calls)


def test_synthesis_tiles_and_repeats_for_a_seed(root):
    photo = np.asarray(Image.open(root / "tests/data/textures/gravel.png").convert("RGB"))[:128, :128]
    out = organtex.synth(photo, 128, seed=3)
    assert out.shape == (128, 128, 3) and out.dtype == np.uint8
    # Tiles: the step across the wrap is no larger than steps inside.
    o = out.astype(int)
    inner = np.abs(np.diff(o, axis=1)).mean()
    wrap = np.abs(o[:, 0] - o[:, -1]).mean()
    assert wrap <= 1.15 * inner, (wrap, inner)
    assert (organtex.synth(photo, 128, seed=3) == out).all()
    # A masked exemplar never gives its masked colour.
    masked = photo.copy()
    masked[:32, :32] = [255, 0, 255]
    mask = np.ones(photo.shape[:2], bool)
    mask[:32, :32] = False
    out = organtex.synth(masked, 64, mask=mask)
    assert not ((out == [255, 0, 255]).all(axis=2)).any()


def test_a_block_and_its_section(root):
    photo = np.asarray(Image.open(root / "tests/data/textures/gravel.png").convert("RGB"))[:64, :64]
    block = organtex.synth3d(photo, 32)
    assert block.shape == (32, 32, 32, 3)
    cube = organtex.read_mesh(root / "tests/data/cube.obj")
    v, f, rgb = organtex.section(cube.vertices, cube.faces, block, (0, 0, 1, 0.1), scale=0.05)
    assert len(f) > 0 and rgb.shape == v.shape
    # The colours are the block's at those points: all in its palette.
    palette = {tuple(c) for c in block.reshape(-1, 3)}
    assert len(palette) > 10 and all(np.asarray(rgb).min(axis=0) >= 0)


def test_a_closed_mesh_fills_with_positive_tets(root):
    bunny = organtex.read_mesh(root / "tests/data/bunny.obj")
    points, tets, report = organtex.tetra(bunny.vertices, bunny.faces, cells=20000)
    assert tets.shape[1] == 4 and 10000 < len(tets) < 40000, len(tets)
    a, b, c, d = (points[tets[:, k]] for k in range(4))
    volume = np.einsum("ij,ij->i", b - a, np.cross(c - a, d - a)) / 6
    assert (volume > 0).all() and report["edge_length"] > 0


def test_bad_input_raises_with_the_librarys_message(root, tmp_path):
    with pytest.raises(organtex.OrgantexError, match="nope.obj"):
        organtex.read_mesh(tmp_path / "nope.obj")
    bad = tmp_path / "bad.obj"
    bad.write_text("v 0 0 0\nv 1 0 0\nf 1 2 7\n")
    with pytest.raises(organtex.OrgantexError, match="bad.obj"):
        organtex.read_mesh(bad)
    with pytest.raises(organtex.OrgantexError, match="names vertex 9"):
        organtex.unwrap(np.zeros((3, 3)), [[0, 1, 9]])
    with pytest.raises(organtex.OrgantexError, match=r"\(h, w, 3\) uint8"):
        organtex.synth(np.zeros((8, 8)), 16)


def test_a_bake_is_the_clis_byte_for_byte(root, tmp_path):
    report = organtex.bake(root / "scenes/bunny.toml", tmp_path / "py")
    assert report["scene"] == "bunny" and report["facets"]
    exe = root / "target/release/organtex"
    subprocess.run([exe, "bake", root / "scenes/bunny.toml", "-o", tmp_path / "cli"], check=True,
                   capture_output=True)
    assert (tmp_path / "py/scene.glb").read_bytes() == (tmp_path / "cli/scene.glb").read_bytes()


def test_a_morph_shows_its_photographs_on_their_planes(root):
    data = root / "tests/data/morph"
    box = organtex.read_mesh(data / "box.obj")
    morph = organtex.Morph(box.vertices, box.faces, data / "sections.toml")
    assert (morph.exemplars, morph.regions) == (3, 4)
    photo = np.asarray(Image.open(data / "slice_096.png").convert("L"), dtype=int)
    h, w = photo.shape
    j, i = np.mgrid[0:h, 0:w]
    points = np.stack([i + 0.5, j + 0.5, np.full(i.shape, 96.5)], axis=-1).reshape(-1, 3)
    rgb = morph.colours(points).reshape(h, w, 3).astype(int)
    assert np.abs(rgb[3:-3, 3:-3, 0] - photo[3:-3, 3:-3]).max() <= 2
    with pytest.raises(organtex.OrgantexError, match="box.obj"):
        organtex.Morph(box.vertices, box.faces, data / "box.obj")
