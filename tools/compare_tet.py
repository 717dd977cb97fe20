#!/usr/bin/env python3
"""Compare organtex's tet meshes with TetGen's and fTetWild's on the same meshes.

Each mesh goes to TetGen first (pip `tetgen`, a PLC with quality
refinement at radius-edge ratio 1.5 and dihedral target 10 degrees, i.e.
switches -pq1.5/10: the settings of issue 21's table, which they reproduce,
174,388 tets on the bunny and 7,167 on the bone; the package's bare
defaults, ratio 2, give 113k and 6.5k), then to fTetWild (pip
`pytetwild`, its defaults: ideal edge length 1/20 of the bbox diagonal,
envelope 1e-3), then to `organtex tetra --cells N` with N = TetGen's tet
count (fTetWild's where TetGen failed; organtex's default resolution where
both did). Every result is measured here by the same code: min/max dihedral
angle over all tets, and the two-sided Hausdorff distance between the
mesh's boundary (the tet faces that belong to one tet only) and the input
surface, as a percentage of the input's bounding box diagonal ("hausd %"),
and its one-sided part from the boundary to the surface ("b->s %"): where
the input intersects itself, the parts of the surface inside the solid are
far from any boundary, so only the one-sided figure judges the mesh there.
organtex's own figures (its --json) are listed beside ours.

Hausdorff sampling: from each surface, every vertex plus SAMPLES points
drawn uniformly by area (fixed seed), each measured against the other
surface by exact point-triangle distance to candidate triangles from a k-d
tree of their centroids (see farthest_distance: the largest distance over
the samples is exact). So the figure is a lower bound of the true one, short
of it by at most the sample spacing.

Each tool runs once per mesh in a child process of its own, under a time
limit (a timeout is a failure): "s" is the tool's own time (the wall clock
around the tetrahedralize call for TetGen and fTetWild, the `seconds`
organtex reports for itself), "wall" the child's whole run (interpreter
start and mesh loading included for the Python tools; loading, meshing,
measuring and writing for organtex), "MB" the child's peak RSS (from
wait4; the Python children's includes 40-60 MB of interpreter, numpy and
mesh, their peak before the call, given in the notes). TetGen is single-threaded; fTetWild
and organtex use every core.

organtex's mesh is written as .vtk by the timed run, and again as .msh and
.mesh (untimed runs at the same --cells); meshio loads each file, which must
have organtex's --json vertex and tet counts, only positive tet volumes, and
the same points and tets as the .vtk.

--unseen: organtex alone, at its default resolution, on every mesh
`tools/compare_uv.py --unseen` fetches (Stanford's raw dragon scans, a
scanned bust, the Utah teapot from npm; CGAL's demo meshes from Debian),
each file read back by meshio as above, with the issue's targets per mesh:
dihedral angles within the proven bound, enclosed volume within 2% of the
surface's (closed surfaces), Hausdorff distance within 1% of the diagonal
(two-sided for closed surfaces; for open ones the surface to the boundary,
since the boundary must cap their holes). Exits 1 on a bound or file
failure; a missed distance or volume target is listed, not an exit.

Usage: tools/compare_tet.py [MESH ...] [--quick | --unseen] [--json OUT] [--organtex PATH]
  default meshes: tests/data/bunny.obj and cube.obj, pymeshlab's sample cow
  (self-intersecting) and bone, and two interpenetrating icospheres written
  as one OBJ (target/compare-tet/two_spheres.obj); --quick: the two spheres
  only (a smoke test for CI, 10-25 s on this 2-core machine).
Exits 1 if organtex fails on a mesh, leaves its dihedral bound
[10.7, 164.8] degrees, or writes a file meshio does not read back as above.
"""

import argparse
import contextlib
import io
import json
import os
import resource
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import pyenv  # noqa: E402

ROOT = pyenv.ROOT
REQUIREMENTS = ["tetgen==0.8.4", "pytetwild==0.4.2", "meshio==5.3.5", "numpy", "scipy"]
# Only for its sample meshes (the cow and the bone), so not for --quick.
PYMESHLAB = ["pymeshlab==2025.7.post1"]
WORK = ROOT / "target" / "compare-tet"
SAMPLES = 200_000
DIHEDRAL_BOUND = (10.7, 164.8)


# --- meshes ---------------------------------------------------------------

def load_surface(path):
    """Points (float64) and triangles of a surface mesh; polygons are fanned."""
    import meshio
    import numpy as np

    mesh = meshio.read(path)
    tris = []
    for block in mesh.cells:
        if block.type == "triangle":
            tris.append(block.data)
        elif block.type in ("quad", "polygon") or block.type.startswith("polygon"):
            d = block.data
            tris += [d[:, [0, i, i + 1]] for i in range(1, d.shape[1] - 1)]
    return np.asarray(mesh.points, dtype=np.float64), np.concatenate(tris).astype(np.int64)


def sample_meshes():
    import pymeshlab

    folder = Path(pymeshlab.__file__).parent / "tests" / "sample_meshes"
    return [folder / n for n in ("cow.obj", "bone.ply") if (folder / n).exists()]


def icosphere(level):
    """Unit icosphere: an icosahedron whose faces are split in four `level` times."""
    import numpy as np

    t = (1 + 5 ** 0.5) / 2
    verts = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t),
             (0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
             (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
             (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    verts = [np.array(v, dtype=float) / np.linalg.norm(v) for v in verts]
    for _ in range(level):
        midpoint, split = {}, []

        def mid(a, b):
            key = (min(a, b), max(a, b))
            if key not in midpoint:
                m = verts[a] + verts[b]
                verts.append(m / np.linalg.norm(m))
                midpoint[key] = len(verts) - 1
            return midpoint[key]

        for a, b, c in faces:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            split += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = split
    return np.array(verts), np.array(faces)


def two_spheres():
    """Two unit icospheres 0.9 apart, one OBJ: each closed, together
    self-intersecting along a circle."""
    path = WORK / "two_spheres.obj"
    if not path.exists():
        WORK.mkdir(parents=True, exist_ok=True)
        v, f = icosphere(3)
        with open(path, "w") as out:
            out.write("# two interpenetrating icospheres (tools/compare_tet.py)\n")
            for shift in (-0.45, 0.45):
                for p in v:
                    out.write(f"v {p[0] + shift:.17g} {p[1]:.17g} {p[2]:.17g}\n")
            for base in (0, len(v)):
                for a, b, c in f + base + 1:
                    out.write(f"f {a} {b} {c}\n")
    return path


# --- measures -------------------------------------------------------------

# The six edges of a tet (i, j) with the two other corners (k, l).
TET_EDGES = [(0, 1, 2, 3), (0, 2, 1, 3), (0, 3, 1, 2), (1, 2, 0, 3), (1, 3, 0, 2), (2, 3, 0, 1)]


def dihedral_range(points, tets):
    """Smallest and largest dihedral angle (degrees) over all tets."""
    import numpy as np

    c = points[tets]
    lo, hi = 180.0, 0.0
    for i, j, k, l in TET_EDGES:
        e = c[:, j] - c[:, i]
        n1 = np.cross(e, c[:, k] - c[:, i])
        n2 = np.cross(e, c[:, l] - c[:, i])
        angle = np.degrees(np.arctan2(np.linalg.norm(np.cross(n1, n2), axis=1), np.einsum("ij,ij->i", n1, n2)))
        lo, hi = min(lo, angle.min()), max(hi, angle.max())
    return float(lo), float(hi)


def signed_volumes(points, tets):
    import numpy as np

    c = points[tets]
    return np.einsum("ij,ij->i", c[:, 1] - c[:, 0], np.cross(c[:, 2] - c[:, 0], c[:, 3] - c[:, 0])) / 6.0


def boundary_triangles(tets):
    """The tet faces that belong to exactly one tet."""
    import numpy as np

    faces = np.concatenate([tets[:, [1, 2, 3]], tets[:, [0, 3, 2]], tets[:, [0, 1, 3]], tets[:, [0, 2, 1]]])
    _, first, count = np.unique(np.sort(faces, axis=1), axis=0, return_index=True, return_counts=True)
    return faces[first[count == 1]]


def point_triangle_distance(p, a, b, c):
    """Distance from points p to triangles (a, b, c), elementwise (arrays
    broadcast over leading axes): the closest point by its Voronoi region
    of the triangle (vertex, edge or face), tested in that order."""
    import numpy as np

    dot = lambda x, y: np.einsum("...i,...i->...", x, y)  # noqa: E731
    ab, ac, ap, bp, cp = b - a, c - a, p - a, p - b, p - c
    d1, d2, d3, d4, d5, d6 = dot(ab, ap), dot(ac, ap), dot(ab, bp), dot(ac, bp), dot(ab, cp), dot(ac, cp)
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
    with np.errstate(divide="ignore", invalid="ignore"):
        t_ab = d1 / (d1 - d3)
        t_ac = d2 / (d2 - d6)
        t_bc = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        s = va + vb + vc
        v, w = vb / s, vc / s
        closest = np.select(
            [((d1 <= 0) & (d2 <= 0))[..., None], ((d3 >= 0) & (d4 <= d3))[..., None],
             ((vc <= 0) & (d1 >= 0) & (d3 <= 0))[..., None], ((d6 >= 0) & (d5 <= d6))[..., None],
             ((vb <= 0) & (d2 >= 0) & (d6 <= 0))[..., None], ((va <= 0) & (d4 >= d3) & (d5 >= d6))[..., None]],
            [a, b, a + t_ab[..., None] * ab, c, a + t_ac[..., None] * ac, b + t_bc[..., None] * (c - b)],
            a + v[..., None] * ab + w[..., None] * ac,
        )
        d = np.linalg.norm(p - closest, axis=-1)
    # A degenerate triangle can give NaN; its corners still bound the distance.
    corners = np.minimum(np.minimum(np.linalg.norm(ap, axis=-1), np.linalg.norm(bp, axis=-1)), np.linalg.norm(cp, axis=-1))
    return np.fmin(d, corners)


def surface_samples(points, tris, rng):
    """Every vertex used by a triangle, and SAMPLES points uniform by area."""
    import numpy as np

    a, b, c = points[tris[:, 0]], points[tris[:, 1]], points[tris[:, 2]]
    area = np.linalg.norm(np.cross(b - a, c - a), axis=1)
    pick = rng.choice(len(tris), SAMPLES, p=area / area.sum())
    r1, r2 = np.sqrt(rng.random(SAMPLES))[:, None], rng.random(SAMPLES)[:, None]
    inside = (1 - r1) * a[pick] + r1 * (1 - r2) * b[pick] + r1 * r2 * c[pick]
    return np.concatenate([points[np.unique(tris)], inside])


def farthest_distance(samples, points, tris):
    """Largest distance from `samples` to the triangles, exact at each sample."""
    import numpy as np
    from scipy.spatial import cKDTree

    a, b, c = points[tris[:, 0]], points[tris[:, 1]], points[tris[:, 2]]
    centroid = (a + b + c) / 3
    reach = np.max(np.linalg.norm(np.stack([a, b, c]) - centroid, axis=2))  # farthest corner from its centroid
    tree = cKDTree(centroid)
    m = len(tris)
    # Bounds on each sample's distance: the nearest of its k candidate
    # triangles gives an upper one; a triangle not among them has its
    # centroid at least the k-th candidate's distance away, so is at least
    # that less `reach` away, which gives a lower one. Samples are refined
    # with 4x the candidates while their bounds differ and their upper bound
    # exceeds every sample's lower bound (else they cannot be the farthest).
    lower, upper = np.zeros(len(samples)), np.full(len(samples), np.inf)
    todo, k = np.arange(len(samples)), min(16, m)
    while todo.size:
        for chunk in np.array_split(todo, max(1, todo.size * k // 500_000)):
            near, idx = tree.query(samples[chunk], k=k)
            near, idx = near.reshape(len(chunk), k), idx.reshape(len(chunk), k)
            d = point_triangle_distance(samples[chunk][:, None], a[idx], b[idx], c[idx]).min(axis=1)
            upper[chunk] = d
            lower[chunk] = d if k == m else np.minimum(d, np.maximum(near[:, -1] - reach, 0))
        todo = todo[(lower[todo] < upper[todo]) & (upper[todo] > lower.max())]
        k = min(4 * k, m)
    return float(lower.max()) if len(samples) else 0.0


def measure(points, tets, surface, diagonal):
    """Quality and boundary distance of a tet mesh, as the table shows them."""
    import numpy as np

    points, tets = np.asarray(points, dtype=np.float64), np.asarray(tets, dtype=np.int64)
    lo, hi = dihedral_range(points, tets)
    boundary = boundary_triangles(tets)
    rng = np.random.default_rng(0)
    b2s = farthest_distance(surface_samples(points, boundary, rng), *surface)
    s2b = farthest_distance(surface_samples(*surface, rng), points, boundary)
    volumes = signed_volumes(points, tets)
    return {
        "vertices": len(points), "tets": len(tets), "min_dihedral": lo, "max_dihedral": hi,
        "boundary_to_surface": b2s, "surface_to_boundary": s2b,
        "hausdorff_percent": 100 * max(b2s, s2b) / diagonal,
        "b2s_percent": 100 * b2s / diagonal,
        "volume": float(np.abs(volumes).sum()),
        "inverted": int(min((volumes < 0).sum(), (volumes > 0).sum())),  # against the majority's orientation
    }


# --- children -------------------------------------------------------------

# Runs argv[3:] for at most argv[2] seconds (then kills it) and writes its
# exit code, wall time and peak RSS to argv[1]. A child's peak RSS counts
# the memory of the process it was forked from (Linux keeps the high-water
# mark across exec), so the tools are started from this small interpreter,
# not from the comparison's large one.
LAUNCHER = """
import json, os, signal, sys, time
start = time.perf_counter()
pid = os.fork()
if pid == 0:
    try:
        os.execvp(sys.argv[3], sys.argv[3:])
    finally:
        os._exit(127)
timed_out = []
def stop(*_):
    timed_out.append(True)
    os.kill(pid, signal.SIGKILL)
signal.signal(signal.SIGALRM, stop)
signal.setitimer(signal.ITIMER_REAL, float(sys.argv[2]))
_, status, usage = os.wait4(pid, 0)
wall = time.perf_counter() - start
with open(sys.argv[1], "w") as f:
    json.dump({"code": None if timed_out else os.waitstatus_to_exitcode(status), "wall": wall,
               "MB": usage.ru_maxrss / 1024}, f)
"""


def run_child(cmd, timeout, cwd=None):
    """Run `cmd` through LAUNCHER; return (exit code, or None if it ran out
    of time, wall seconds, peak RSS in MB, stdout, stderr)."""
    with tempfile.TemporaryDirectory() as tmp:
        figures = Path(tmp) / "figures.json"
        out, err = open(Path(tmp) / "out", "w+b"), open(Path(tmp) / "err", "w+b")
        start = time.perf_counter()
        child = subprocess.Popen([sys.executable, "-S", "-c", LAUNCHER, str(figures), str(timeout), *map(str, cmd)],
                                 stdout=out, stderr=err, cwd=cwd, start_new_session=True)
        try:
            child.wait(timeout + 30)
        except subprocess.TimeoutExpired:  # the launcher itself hangs: end its whole session
            os.killpg(child.pid, signal.SIGKILL)
            child.wait()
        with out, err:
            out.seek(0)
            err.seek(0)
            stdout, stderr = out.read().decode(errors="replace"), err.read().decode(errors="replace")
        if not figures.exists():
            return 1, time.perf_counter() - start, float("nan"), stdout, stderr + "\nerror: the launcher failed"
        f = json.loads(figures.read_text())
        return f["code"], f["wall"], f["MB"], stdout, stderr


def failure(code, stdout, stderr, timeout):
    if code is None:
        return f"timeout after {timeout:.0f} s"
    lines = [l.strip() for l in (stderr + stdout).splitlines() if l.strip()]
    errors = [l for l in lines if l.lower().startswith("error")]
    why = (errors or lines or ["no message"])[-1]
    return f"exit {code}: {why}" if code > 0 else f"killed by signal {-code}: {why}"


def worker(tool, mesh, out):
    """Child side for TetGen and fTetWild: load, tetrahedralize (timed), save."""
    import numpy as np

    points, tris = load_surface(mesh)
    if tool == "tetgen":
        import tetgen

        run = lambda: tetgen.TetGen(points, tris.astype(np.int32)).tetrahedralize(minratio=1.5, mindihedral=10)[:2]  # noqa: E731
    else:
        import importlib.util
        import types

        # pytetwild 0.4.2 imports pyvista on import (to register an accessor
        # on its meshes) but does not depend on it; the array API used here
        # needs none of it, so an empty module stands in for it.
        if importlib.util.find_spec("pyvista") is None:
            sys.modules["pyvista"] = types.ModuleType("pyvista")
        import pytetwild

        run = lambda: pytetwild.tetrahedralize(points, tris.astype(np.int32))  # noqa: E731
    base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    start = time.perf_counter()
    nodes, tets = run()
    seconds = time.perf_counter() - start
    np.savez(out, points=nodes, tets=tets, seconds=seconds, base=base)


def run_python_tool(tool, mesh, tmp, timeout):
    out = tmp / f"{tool}.npz"
    # In `tmp`: TetGen leaves debug files (_skipped.node, ...) in its working
    # folder when it fails.
    cmd = [sys.executable, str(Path(__file__).resolve()), "--worker", tool, str(mesh.resolve()), str(out.resolve())]
    code, wall, mb, stdout, stderr = run_child(cmd, timeout, cwd=tmp)
    row = {"wall": wall, "MB": mb}
    if code != 0 or not out.exists():
        return {**row, "error": failure(code, stdout, stderr, timeout)}
    import numpy as np

    r = np.load(out)
    if len(r["tets"]) == 0:
        return {**row, "error": "no tets"}
    return {**row, "seconds": float(r["seconds"]), "base_MB": float(r["base"]), "points": r["points"], "tet_array": r["tets"]}


def run_organtex(organtex, mesh, out, cells, timeout):
    cmd = [organtex, "tetra", str(mesh), "-o", str(out), "--json"] + (["--cells", str(cells)] if cells else [])
    code, wall, mb, stdout, stderr = run_child(cmd, timeout)
    row = {"wall": wall, "MB": mb, "cells": cells}
    if code != 0:
        return {**row, "error": failure(code, stdout, stderr, timeout)}
    try:
        report = json.loads(stdout)
    except json.JSONDecodeError:
        return {**row, "error": f"--json printed no JSON: {stdout[:200]!r}"}
    return {**row, "seconds": report["seconds"], "own": report}


def check_file(path, own, reference=None):
    """Problems meshio finds with one file organtex wrote (empty if none)."""
    import meshio
    import numpy as np

    try:
        with contextlib.redirect_stdout(io.StringIO()):  # meshio's gmsh reader prints a blank line
            m = meshio.read(path)
    except Exception as e:
        return [f"meshio cannot read it: {e}"], None
    tets = np.concatenate([b.data for b in m.cells if b.type == "tetra"] or [np.empty((0, 4), int)])
    problems = []
    if len(m.points) != own["vertices"]:
        problems.append(f"{len(m.points)} points, --json says {own['vertices']}")
    if len(tets) != own["tets"]:
        problems.append(f"{len(tets)} tets, --json says {own['tets']}")
    if len(tets):
        bad = int((signed_volumes(np.asarray(m.points, float), tets) <= 0).sum())
        if bad:
            problems.append(f"{bad} tets of non-positive volume")
    if reference is not None and not problems:
        if not np.array_equal(tets, reference[1]):
            problems.append("tets differ from the .vtk's")
        elif not np.allclose(m.points, reference[0], rtol=1e-6, atol=1e-9 * np.abs(reference[0]).max()):
            problems.append("points differ from the .vtk's")
    return problems, (np.asarray(m.points, float), tets)


# --- table ----------------------------------------------------------------

def compare(mesh, args):
    """All rows for one mesh, and the list of organtex's problems on it."""
    import numpy as np

    surface = load_surface(mesh)
    diagonal = float(np.linalg.norm(surface[0].max(axis=0) - surface[0].min(axis=0)))
    rows, problems = [], []
    with tempfile.TemporaryDirectory() as tmpdir:
        tmp = Path(tmpdir)
        for tool, name in (("tetgen", "TetGen"), ("ftetwild", "fTetWild")):
            r = run_python_tool(tool, mesh, tmp, args.timeout)
            if "error" not in r:
                r.update(measure(r.pop("points"), r.pop("tet_array"), surface, diagonal))
            rows.append({"mesh": mesh.name, "tool": name, **r})
        cells = next((r["tets"] for r in rows if "tets" in r), None)
        vtk = tmp / "organtex.vtk"
        r = {"mesh": mesh.name, "tool": "organtex", **run_organtex(args.organtex, mesh, vtk, cells, args.timeout)}
        rows.append(r)
        if "error" in r:
            problems.append(f"organtex failed: {r['error']}")
            return rows, problems
        own = r["own"]
        reference = None
        files = {}
        for ext in ("vtk", "msh", "mesh"):
            path = tmp / f"organtex.{ext}"
            if ext != "vtk":  # the same mesh again, written in another format
                again = run_organtex(args.organtex, mesh, path, cells, args.timeout)
                if "error" in again:
                    files[ext] = [again["error"]]
                    continue
            found, read = check_file(path, own, reference)
            files[ext] = found
            if ext == "vtk" and read is not None:
                reference = read
                r.update(measure(*read, surface, diagonal))
        r["files"] = files
        problems += [f".{ext}: {p}" for ext, found in files.items() for p in found]
    if "min_dihedral" in r and not (DIHEDRAL_BOUND[0] <= r["min_dihedral"] and r["max_dihedral"] <= DIHEDRAL_BOUND[1]):
        problems.append(f"dihedral angles {r['min_dihedral']:.2f}-{r['max_dihedral']:.2f} outside {DIHEDRAL_BOUND}")
    return rows, problems


def print_row(r):
    num = lambda key, fmt: format(r[key], fmt) if key in r else "-"  # noqa: E731
    if "error" in r:
        note = r["error"]
    elif r["tool"] == "organtex":
        own = r["own"]
        note = (f"own: {own['min_dihedral']:.2f}-{own['max_dihedral']:.2f} deg, {100 * own['hausdorff_relative']:.3f}%, "
                f"volume {own['volume'] / own['surface_volume']:.4f} x surface's; files: "
                + ", ".join(f".{e} {'ok' if not p else '; '.join(p)}" for e, p in r["files"].items()))
    else:
        note = f"{r['base_MB']:.0f} MB before the call" + (f"; {r['inverted']} tets inverted" if r["inverted"] else "")
    print(f"{r['mesh']:<16}{r['tool']:<10}{num('tets', 'd'):>8}{num('min_dihedral', '.2f'):>8}{num('max_dihedral', '.2f'):>8}"
          f"{num('hausdorff_percent', '.3f'):>9}{num('b2s_percent', '.3f'):>8}{num('seconds', '.2f'):>8}{num('wall', '.2f'):>8}{num('MB', '.0f'):>7}  {note}", flush=True)


def closed(path):
    """Whether every edge of the surface is in exactly two faces."""
    import numpy as np

    _, tris = load_surface(path)
    edges = np.sort(np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]]), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    return bool((counts == 2).all())


def unseen(args):
    """organtex's default resolution on the unseen meshes (see the usage)."""
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    import compare_uv

    meshes = [*compare_uv.unseen_meshes(), *compare_uv.cgal_meshes()]
    tmp = ROOT / "target" / "compare-tet" / "unseen"
    tmp.mkdir(parents=True, exist_ok=True)
    print(f"{'mesh':<18}{'closed':>7}{'tets':>10}{'graded':>7}{'min deg':>8}{'max deg':>8}"
          f"{'b->s %':>8}{'s->b %':>8}{'vol %':>8}{'s':>7}{'MB':>7}  targets", flush=True)
    rows, failures, missed = [], [], []
    for mesh in meshes:
        out = tmp / (mesh.stem + ".vtk")
        r = run_organtex(args.organtex, mesh, out, None, args.timeout)
        name = mesh.stem
        if "error" in r:
            print(f"{name:<18}  FAILED: {r['error']}", flush=True)
            failures.append(f"{name}: {r['error']}")
            continue
        own = r["own"]
        is_closed = closed(mesh)
        problems, _ = check_file(out, own)
        if not (DIHEDRAL_BOUND[0] <= own["min_dihedral"] and own["max_dihedral"] <= DIHEDRAL_BOUND[1]):
            problems.append(f"dihedral {own['min_dihedral']:.2f}-{own['max_dihedral']:.2f} outside the bound")
        failures += [f"{name}: {p}" for p in problems]
        h = own["hausdorff"]
        b2s, s2b = 100 * h["boundary_to_surface"] / h["diagonal"], 100 * h["surface_to_boundary"] / h["diagonal"]
        vol = 100 * (own["volume"] - own["surface_volume"]) / own["surface_volume"]
        misses = []
        if max(s2b, b2s if is_closed else 0) > 1:
            misses.append("Hausdorff > 1%")
        if is_closed and abs(vol) > 2:
            misses.append("volume off > 2%")
        missed += [f"{name}: {m}" for m in misses]
        print(f"{name:<18}{'yes' if is_closed else 'no':>7}{own['tets']:>10}{'yes' if own['graded'] else 'no':>7}"
              f"{own['min_dihedral']:>8.2f}{own['max_dihedral']:>8.2f}{b2s:>8.3f}{s2b:>8.3f}{vol:>+8.2f}"
              f"{own['seconds']:>7.2f}{r['MB']:>7.0f}  {', '.join(misses + problems) or 'met'}", flush=True)
        rows.append({"mesh": name, "closed": is_closed, **r})
        out.unlink(missing_ok=True)
    return rows, failures, missed


def main():
    if sys.argv[1:2] == ["--worker"]:
        return worker(*sys.argv[2:5])
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("meshes", nargs="*", type=Path)
    parser.add_argument("--quick", action="store_true", help="the two interpenetrating spheres only")
    parser.add_argument("--unseen", action="store_true",
                        help="organtex alone at its default resolution on the meshes compare_uv.py --unseen fetches")
    parser.add_argument("--organtex", default=str(ROOT / "target" / "release" / "organtex"))
    parser.add_argument("--timeout", type=float, default=300, help="seconds each tool gets per mesh")
    parser.add_argument("--json", type=Path, metavar="OUT", help="also write every row as JSON")
    args = parser.parse_args()
    pyenv.ensure(REQUIREMENTS + ([] if args.quick or args.meshes else PYMESHLAB), __file__)
    if args.unseen:
        rows, failures, missed = unseen(args)
        if args.json:
            args.json.write_text(json.dumps(rows, indent=1) + "\n")
        if missed:
            print("\ntargets missed:\n  " + "\n  ".join(missed))
        if failures:
            print("\nFAILED:\n  " + "\n  ".join(failures))
            sys.exit(1)
        return
    data = ROOT / "tests" / "data"
    meshes = args.meshes or ([two_spheres()] if args.quick else
                             [data / "bunny.obj", data / "cube.obj", *sample_meshes(), two_spheres()])

    print(f"{'mesh':<16}{'tool':<10}{'tets':>8}{'min deg':>8}{'max deg':>8}{'hausd %':>9}{'b->s %':>8}{'s':>8}{'wall':>8}{'MB':>7}  notes", flush=True)
    rows, failures = [], []
    for mesh in meshes:
        mesh_rows, problems = compare(mesh, args)
        for r in mesh_rows:
            print_row(r)
        rows += mesh_rows
        failures += [f"{mesh.name}: {p}" for p in problems]
        ours = mesh_rows[-1]
        peer = next((r for r in mesh_rows[:-1] if "tets" in r), None)  # the one whose count organtex was given
        if peer and "tets" in ours and peer["seconds"] > 0:
            print(f"{'':<16}organtex: {ours['seconds'] / peer['seconds']:.3g}x {peer['tool']}'s time, "
                  f"{ours['tets'] / peer['tets']:.2f}x its tets, {ours['MB'] / peer['MB']:.2f}x its peak RSS", flush=True)
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1) + "\n")
    if failures:
        print("\nFAILED:\n  " + "\n  ".join(failures))
        sys.exit(1)


if __name__ == "__main__":
    main()
