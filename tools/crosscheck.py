#!/usr/bin/env python3
"""Cross-check `organtex info` against pymeshlab (MeshLab's vcglib).

For every test mesh (the bundled ones, the generated shapes, and two small
non-manifold cases) compare vertex/face counts, connected components,
boundary loops and edges, genus, non-manifold edge and vertex counts and
unreferenced vertices; on closed meshes also compare per-vertex Gaussian
curvature (angle defect over mixed Voronoi area). Exit 1 on any
disagreement.

On curvature: vcglib's MeanAndGaussian keeps angles in single precision
(`float angle0, angle1, angle2`), so its angle defects carry about 1e-7 rad
of rounding noise. Where a vertex's defect is itself that small, no double-
precision result can agree with it to 1e-3 relative. The script therefore
reports two figures: `strict`, the share of vertices within 1e-3 relative,
and `agree`, the share within 1e-3 relative plus that rounding noise
(valence x ulp(pi) / mixed area). The check requires `agree` >= 99%.

Usage: tools/crosscheck.py [--organtex target/release/organtex]
Creates its own virtualenv under target/pyenv and installs pymeshlab there.
"""

import argparse
import json
import multiprocessing
import subprocess
import sys
import tempfile
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import pyenv  # noqa: E402

ROOT = pyenv.ROOT
REQUIREMENTS = ["pymeshlab==2025.7.post1", "numpy"]


FIN = """v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nf 1 2 3\nf 2 1 4\nf 1 2 5\n"""
BOWTIE = """v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv -1 0 0\nv 0 -1 0\nv 0 0 -1
f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\nf 1 6 5\nf 1 5 7\nf 1 7 6\nf 5 6 7\n"""


def test_meshes(organtex, tmp):
    meshes = [(ROOT / "tests" / "data" / n, True) for n in ("bunny.obj", "bunny10k_textured.obj", "cube.obj")]
    for shape in ("torus", "double-torus", "cylinder", "sphere"):
        out = tmp / f"{shape}.obj"
        subprocess.run([organtex, "generate", shape, "-o", str(out)], check=True, capture_output=True)
        meshes.append((out, True))
    for name, text in (("fin.obj", FIN), ("bowtie.obj", BOWTIE)):
        (tmp / name).write_text(text)
        meshes.append((tmp / name, False))
    return meshes


def organtex_info(organtex, path, manifold, csv):
    cmd = [organtex, "info", "--json", str(path), "--curvature-out", str(csv)]
    if not manifold:
        cmd.append("--repair")
    out = subprocess.run(cmd, check=True, capture_output=True, text=True)
    return json.loads(out.stdout)


def pymeshlab_measures(path, curvature):
    """Topological measures (and per-vertex Gaussian curvature) of one mesh.

    Runs in a fresh process per mesh: pymeshlab 2025.7 carries state between
    MeshSets, e.g. a fin of three faces on one edge reports 1 non-manifold
    edge alone but 3 after the bunny was measured in the same process.
    """
    import pymeshlab

    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(path))
    measures = ms.get_topological_measures()
    measures["vertex_number"] = ms.current_mesh().vertex_number()
    measures["face_number"] = ms.current_mesh().face_number()
    k = valence = None
    if curvature:
        ms.compute_scalar_by_discrete_curvature_per_vertex(curvaturetype="Gaussian Curvature")
        mesh = ms.current_mesh()
        k = mesh.vertex_scalar_array().tolist()
        valence = [int(x) for x in __import__("numpy").bincount(mesh.face_matrix().ravel(), minlength=len(k))]
    return measures, k, valence


def compare_curvature(theirs, valence, csv):
    import numpy as np

    theirs, valence = np.array(theirs), np.array(valence)
    ours = np.genfromtxt(csv, delimiter=",", names=True)
    noise = valence * float(np.spacing(np.float32(np.pi))) / ours["mixed_area"]
    diff = np.abs(ours["gaussian"] - theirs)
    tol = 1e-3 * np.abs(theirs)
    return float(np.mean(diff <= tol)), float(np.mean(diff <= tol + noise))


def main():
    pyenv.ensure(REQUIREMENTS, __file__)
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--organtex", default=str(ROOT / "target" / "release" / "organtex"))
    args = parser.parse_args()

    failures = []
    header = f"{'mesh':<24}{'V':>7}{'F':>7}{'comp':>6}{'loops':>6}{'bedges':>7}{'genus':>6}{'nm-e':>5}{'nm-v':>5}{'unref':>6}  {'K strict':>9}{'K agree':>9}"
    print(header)
    spawn = multiprocessing.get_context("spawn")
    with tempfile.TemporaryDirectory() as tmpdir, ProcessPoolExecutor(
        1, mp_context=spawn, max_tasks_per_child=1
    ) as fresh_process:
        tmp = Path(tmpdir)
        for path, manifold in test_meshes(args.organtex, tmp):
            csv = tmp / "k.csv"
            ours = organtex_info(args.organtex, path, manifold, csv)
            closed = manifold and ours["boundary_loops"] == 0
            t, their_k, valence = fresh_process.submit(pymeshlab_measures, path, closed).result()
            pairs = {
                "non_manifold_edges": (ours["defects"]["non_manifold_edges"], t["non_two_manifold_edges"]),
                "non_manifold_vertices": (ours["defects"]["non_manifold_vertices"], t["non_two_manifold_vertices"]),
                "unreferenced_vertices": (ours["defects"]["unreferenced_vertices"], t["unreferenced_vertices"]),
            }
            if manifold:
                # pymeshlab reports genus and holes only for manifold meshes.
                pairs.update(
                    {
                        "vertices": (ours["vertices"], t["vertex_number"]),
                        "faces": (ours["faces"], t["face_number"]),
                        "components": (ours["components"], t["connected_components_number"]),
                        "boundary_loops": (ours["boundary_loops"], t["number_holes"]),
                        "boundary_edges": (ours["boundary_edges"], t["boundary_edges"]),
                        "genus": (sum(ours["genus"]), t["genus"]),
                    }
                )
            for key, (a, b) in pairs.items():
                if a != b:
                    failures.append(f"{path.name}: {key}: organtex {a}, pymeshlab {b}")
            strict = agree = None
            if closed:
                strict, agree = compare_curvature(their_k, valence, csv)
                if agree < 0.99:
                    failures.append(
                        f"{path.name}: Gaussian curvature agrees on {agree:.2%} of vertices (< 99%)"
                    )
            fmt = lambda x: f"{x:9.2%}" if x is not None else f"{'-':>9}"
            print(
                f"{path.name:<24}{t['vertex_number']:>7}{t['face_number']:>7}{t['connected_components_number']:>6}"
                f"{t['number_holes']:>6}{t['boundary_edges']:>7}{t['genus']:>6}{t['non_two_manifold_edges']:>5}"
                f"{t['non_two_manifold_vertices']:>5}{t['unreferenced_vertices']:>6}  {fmt(strict)}{fmt(agree)}"
            )
    print("(counts are pymeshlab's; every one matched organtex unless listed below)")
    if failures:
        print("\nDISAGREEMENTS:")
        for f in failures:
            print("  " + f)
        sys.exit(1)
    print("crosscheck: organtex and pymeshlab agree")


if __name__ == "__main__":
    main()
