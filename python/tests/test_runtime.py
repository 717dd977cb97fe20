"""Carving from Python (organtex.Carving), numpy in and out, on a bake of
the default scene: the tunnel through the uterine wall the C, C++ and C#
examples carve, the carved surface closed after every step, the new faces'
texels the interior's colours, bad input refused with the session going on.
ORGANTEX_TEST_BAKE names a bake to reuse (tools/test.sh makes one)."""

import os
from collections import Counter

import numpy as np
import pytest

import organtex

from conftest import ROOT


@pytest.fixture(scope="module")
def bake_dir(tmp_path_factory):
    given = os.environ.get("ORGANTEX_TEST_BAKE")
    if given:
        return given
    out = tmp_path_factory.mktemp("bake")
    organtex.bake(ROOT / "scenes/hysteroscopy_myomas.toml", out)
    return out


def wall_path(step):
    a = step / 100 * 0.95 * 2 * np.pi
    return [18.5 * np.cos(a), 11.8 * np.sin(a), 20.0]


def directed(faces):
    return Counter((int(f[k]), int(f[(k + 1) % 3])) for f in faces for k in range(3))


def test_a_tunnel_through_the_wall_keeps_the_surface_closed_and_textured(bake_dir):
    bake = organtex.Bake(bake_dir)
    assert bake.nodes == ["uterus"]
    node = bake.node("uterus")
    positions, tets = node.tet_mesh()
    assert tets.shape == (275122, 4) and positions.shape[1] == 3
    carving = organtex.Carving(node)
    ids, faces = carving.surface()
    surface = dict(zip(ids.tolist(), map(tuple, faces.tolist())))
    defects = {e for e, n in directed(faces).items() if n > 1}
    steps = []
    for i in range(1, 31):
        s = carving.capsule(wall_path(i - 1), wall_path(i), 1.5)
        steps.append(s)
        assert s.vertices.shape == (len(s.ids), 3) and s.uvs.shape == (len(s.ids), 3, 2)
        assert s.colours.dtype == np.uint8 and s.colours.shape == (len(s.ids), 3, 3)
        for f in s.vanished_ids.tolist():
            del surface[f]
        for f, v in zip(s.ids.tolist(), s.vertices.tolist()):
            surface[f] = tuple(v)
        ids, faces = carving.surface()
        assert dict(zip(ids.tolist(), map(tuple, faces.tolist()))) == surface
        edges = directed(faces)
        for (a, b), n in edges.items():
            assert n <= (2 if (a, b) in defects else 1) and edges[(b, a)] == n, (i, a, b)
        # Each new face's centroid texel: the interior's colour there, a
        # hair inside its own tet.
        tet_of = tets[s.ids // 4]
        inside = positions[tet_of].mean(axis=1)
        for k in range(len(s.ids)):
            page = carving.page(int(s.pages[k]))
            side = page.shape[0]
            uv = s.uvs[k].astype(np.float64) * side
            t = np.floor(uv.mean(axis=0))
            c = t + 0.5
            m = np.array([[uv[1, 0] - uv[0, 0], uv[2, 0] - uv[0, 0]], [uv[1, 1] - uv[0, 1], uv[2, 1] - uv[0, 1]]])
            if abs(np.linalg.det(m)) < 1e-9:
                continue
            w1, w2 = np.linalg.solve(m, c - uv[0])
            w = np.array([1 - w1 - w2, w1, w2])
            if (w < 0).any():
                continue
            p = (w[:, None] * positions[s.vertices[k]]).sum(axis=0)
            p = p + (inside[k] - p) * 1e-7
            want = node.colours(p[None, :])[0].astype(int)
            got = page[int(t[1]), int(t[0])].astype(int)
            assert np.abs(got[:3] - want).max() <= 1 and got[3] == 255, (i, k, got, want)
    assert sum(len(s.removed) for s in steps) > 600
    assert all(len(s.dirty) for s in steps if len(s.ids))


def test_bad_input_is_refused_and_the_session_goes_on(bake_dir, tmp_path):
    node = organtex.Bake(bake_dir).node("uterus")
    n = len(node.tet_mesh()[1])
    carving = organtex.Carving(node)
    first = carving.remove([10, 11])
    assert first.removed.tolist() == [10, 11]
    for call, needle in [
        (lambda: carving.remove([n]), "out of range"),
        (lambda: carving.remove([10]), "already removed"),
        (lambda: carving.remove([12, 12]), "twice"),
        (lambda: carving.remove([-1]), "non-negative"),
        (lambda: carving.sphere([np.nan, 0, 0], 1.0), "not finite"),
        (lambda: carving.capsule([0, 0, 0], [0, 0, np.inf], 1.0), "not finite"),
        (lambda: carving.sphere([0, 0, 20], 0.0), "radius"),
        (lambda: organtex.Carving(node, texels_per_unit=0.0), "density"),
        (lambda: organtex.Bake(tmp_path), "no report.json"),
        (lambda: organtex.Bake(bake_dir).node("liver"), "no node 'liver'"),
        (lambda: node.colours([[0, np.nan, 0]]), "finite"),
    ]:
        with pytest.raises(organtex.OrgantexError, match=needle):
            call()
    assert carving.remove([12]).removed.tolist() == [12]
    background = organtex.Carving(node, background_texels=True)
    s = background.sphere(wall_path(0), 3.0)
    assert s.texels_pending and len(s.ids) > 20
    dirty = background.wait()
    assert len(dirty) and dirty.shape[1] == 5
    page = background.page(int(s.pages[0]))
    assert page[..., 3].max() == 255
    background.write_glb(tmp_path / "carved.glb")
    assert (tmp_path / "carved.glb").read_bytes()[:4] == b"glTF"
