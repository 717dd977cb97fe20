"""Batch bakes on a local Ray cluster of two nodes (a head and a second
node on this machine, started and stopped here): the bundled scenes and a
broken one, results identical to the CLI's, up-to-date scenes skipped, and
a worker killed mid-bake retried."""

import json
import os
import signal
import threading
import time

import pytest

ray = pytest.importorskip("ray")
from ray.cluster_utils import Cluster  # noqa: E402

from organtex import batch  # noqa: E402


@pytest.fixture(scope="module")
def cluster():
    # Both nodes on this machine's own address: with node_ip_address
    # 127.0.0.1 the head starts, but a driver's ray.init never reaches it
    # (Ray 2.x on this machine).
    c = Cluster(initialize_head=True, head_node_args={"num_cpus": 1, "include_dashboard": False})
    c.add_node(num_cpus=1)
    c.wait_for_nodes(timeout=60)
    yield c
    c.shutdown()


BROKEN = """name = "broken"
[[node]]
name = "organ"
mesh = { file = "liver.obj" }
[[node.facet]]
name = "*"
texture = "fundus-tissue"
"""


def test_the_bundled_scenes_bake_on_two_nodes_and_a_broken_one_is_reported(cluster, root, tmp_path):
    broken = tmp_path / "broken.toml"
    broken.write_text(BROKEN)
    bundled = sorted((root / "scenes").glob("*.toml"))
    assert len(bundled) >= 3
    scenes = bundled + [broken]
    out = tmp_path / "out"
    summary = batch.run(scenes, out, address=cluster.address, progress=False)
    by_name = {r["name"]: r for r in summary["results"]}
    assert summary["ok"] == len(bundled) and summary["failed"] == 1, summary
    assert "liver.obj not found" in by_name["broken"]["error"]
    assert str(broken) in by_name["broken"]["error"]
    # Nothing half-written for the broken scene; whole bakes for the rest.
    assert not (out / "broken" / "scene.glb").exists()
    for name in (s.stem for s in bundled):
        assert (out / name / "scene.glb").stat().st_size > 0
        assert json.loads((out / name / "report.json").read_text())["scene"] == name
    assert not list(out.glob(".*.running"))
    # Both nodes took tasks.
    assert len({r["node"] for r in summary["results"]}) == 2
    assert json.loads((out / "summary.json").read_text())["ok"] == len(bundled)
    # Up to date: skipped, unless forced.
    again = batch.run(scenes[:3], out, address=cluster.address, progress=False)
    assert again["skipped"] == 3, again


def test_a_worker_killed_mid_bake_is_retried_and_the_batch_completes(cluster, root, tmp_path):
    scene = root / "scenes" / "hysteroscopy_myomas.toml"
    out = tmp_path / "out"
    killed = []

    def kill_when_running():
        running = out / ".hysteroscopy_myomas.running"
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline:
            if running.exists():
                text = running.read_text().split()
                if len(text) == 2:
                    time.sleep(1.0)  # well into the bake
                    os.kill(int(text[1]), signal.SIGKILL)
                    killed.append(int(text[1]))
                    return
            time.sleep(0.05)

    killer = threading.Thread(target=kill_when_running)
    killer.start()
    summary = batch.run([scene], out, address=cluster.address, retries=2, progress=False)
    killer.join()
    assert killed, "the bake never started"
    assert summary["ok"] == 1, summary
    assert (out / "hysteroscopy_myomas" / "scene.glb").stat().st_size > 0
    # Nothing of the killed attempt is left: no staging folder, no part
    # file, only the whole bake.
    assert sorted(p.name for p in out.iterdir()) == ["hysteroscopy_myomas", "summary.json"]
    assert not list((out / "hysteroscopy_myomas").rglob("*.part"))


def test_a_batch_rebake_after_a_tissue_change_takes_the_kept_unwraps(root, tmp_path):
    """A scene baked again by the batch, after its tissue changed, takes
    the unwraps its previous bake kept (as `organtex bake` into the same
    folder does), and its files are those of a bake from scratch."""
    text = (root / "scenes" / "bunny.toml").read_text().replace(
        '"../tests/data/bunny.obj"', json.dumps(str(root / "tests" / "data" / "bunny.obj")))
    scene = tmp_path / "bunny.toml"
    scene.write_text(text)
    out, fresh = tmp_path / "out", tmp_path / "fresh"
    first = batch.bake_one(str(scene), str(out), None, True)
    assert first["status"] == "ok", first
    scene.write_text(text.replace('texture = "fundus-tissue"', 'texture = "colon-mucosa"'))
    again = batch.bake_one(str(scene), str(out), None, True)
    assert again["status"] == "ok", again
    stages = [s["stage"] for s in json.loads((out / "bunny" / "report.json").read_text())["timings"]["stages"]]
    assert "unwrap reused" in stages and "unwrap" not in stages, stages
    assert batch.bake_one(str(scene), str(fresh), None, True)["status"] == "ok"
    assert (out / "bunny" / "scene.glb").read_bytes() == (fresh / "bunny" / "scene.glb").read_bytes()
    # The previous bake's folder was replaced whole: no staging left.
    assert not list(out.glob(".*"))
