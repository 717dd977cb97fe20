"""Scene variants for batch bakes: seeded, valid, and different."""

import organtex
from organtex import batch


def test_variants_are_seeded_valid_and_different(root, tmp_path):
    base = root / "scenes" / "hysteroscopy_myomas.toml"
    first = batch.vary(base, 4, seed=7, out_dir=tmp_path / "a")
    again = batch.vary(base, 4, seed=7, out_dir=tmp_path / "b")
    other = batch.vary(base, 4, seed=8, out_dir=tmp_path / "c")
    assert [p.name for p in first] == [f"hysteroscopy_myomas-{k:03d}.toml" for k in range(4)]
    for a, b, c in zip(first, again, other):
        assert a.read_text() == b.read_text()
        assert a.read_text() != c.read_text() and a.read_text() != base.read_text()
        organtex.check_scene(a)
    assert len({p.read_text() for p in first}) == 4
    assert not list((tmp_path / "a").glob("*.tmp"))
