#!/usr/bin/env python3
"""Bake every scene in scenes/ and check the .glb files with other tools.

For each scene (layered; the default scene also with --atlas 2048):
- the Khronos glTF validator (npm gltf-validator, installed under
  target/gltf-validator when missing) must report 0 errors;
- trimesh, an independent glTF reader, must load it with one node per facet
  named in report.json, every primitive with texture coordinates and a
  decoded texture image, layered bakes with their texture transforms and
  blend layers carrying vertex alpha;
- report.json's contrast figures must be within the targets: seams and
  facet borders <= 1.2 blended, and above that unblended wherever seams or
  borders exist (the blend must be what hides them);
- every interior block report.json lists must be an RGB uint8 NRRD of the
  listed size and spacing.

Usage: tools/check_bakes.py [--organtex target/release/organtex] [--out DIR]
Exits 1 on any failure.
"""

import argparse
import json
import shutil
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import pyenv  # noqa: E402

ROOT = pyenv.ROOT
REQUIREMENTS = ["trimesh==4.12.2", "numpy", "pillow"]
VALIDATOR = ROOT / "target" / "gltf-validator"
TARGET = 1.2


def ensure_validator():
    if (VALIDATOR / "node_modules" / "gltf-validator").is_dir():
        return
    if shutil.which("npm") is None:
        sys.exit("check_bakes.py: npm is needed for the glTF validator (tools/test.sh installs it)")
    VALIDATOR.mkdir(parents=True, exist_ok=True)
    print("check_bakes.py: installing gltf-validator", flush=True)
    subprocess.run(["npm", "install", "--silent", "--no-audit", "--no-fund", "--prefix", str(VALIDATOR), "gltf-validator@2.0.0-dev.3.10"], check=True)


def read_json(glb):
    data = glb.read_bytes()
    length = int.from_bytes(data[12:16], "little")
    return json.loads(data[20 : 20 + length])


def check_glb(glb, report, failures):
    """Load `glb` with trimesh: every primitive (trimesh makes each its own
    geometry) with its vertices, texture coordinates and decoded texture."""
    import trimesh

    doc = read_json(glb)
    primitives = sum(len(m["primitives"]) for m in doc["meshes"])
    scene = trimesh.load(str(glb), force="scene", process=False)
    if len(scene.geometry) != primitives:
        failures.append(f"{glb}: trimesh read {len(scene.geometry)} primitives of {primitives}")
    for name, geometry in scene.geometry.items():
        visual = geometry.visual
        uv = getattr(visual, "uv", None)
        if len(geometry.faces) == 0 or uv is None or len(uv) != len(geometry.vertices):
            failures.append(f"{glb}: {name} has no faces or texture coordinates")
        material = getattr(visual, "material", None)
        image = getattr(material, "baseColorTexture", None) if material is not None else None
        if image is None or min(image.size) < 64:
            failures.append(f"{glb}: {name} has no decoded base colour texture")
    return len(scene.geometry)


def check_json(glb, report, failures):
    """One mesh node per facet, a camera node per scene camera (the first
    with the scope's spot light), and what trimesh does not expose:
    texture transforms and vertex alpha."""
    doc = read_json(glb)
    nodes = sorted(n["name"] for n in doc["nodes"] if "mesh" in n)
    expected = sorted(f"{f['node']}/{f['facet']}" for f in report["facets"])
    if nodes != expected:
        failures.append(f"{glb}: mesh nodes {nodes}, report facets {expected}")
    cameras = [n for n in doc["nodes"] if "camera" in n]
    if cameras:
        lights = doc.get("extensions", {}).get("KHR_lights_punctual", {}).get("lights", [])
        if cameras[0].get("extensions", {}).get("KHR_lights_punctual", {}).get("light") != 0 or not lights:
            failures.append(f"{glb}: the first camera carries no scope light")
    if report["mode"] == "layered":
        if "KHR_texture_transform" not in doc.get("extensionsUsed", []):
            failures.append(f"{glb}: layered bake without KHR_texture_transform")
        blended = [m for m in doc["materials"] if m.get("alphaMode") == "BLEND"]
        if not blended:
            failures.append(f"{glb}: layered bake without blend layers")
        for mesh in doc["meshes"]:
            for p in mesh["primitives"]:
                if doc["materials"][p["material"]].get("alphaMode") == "BLEND" and "COLOR_0" not in p["attributes"]:
                    failures.append(f"{glb}: {mesh['name']} has a blend layer without vertex alpha")
    elif any(m.get("alphaMode") == "BLEND" for m in doc["materials"]):
        failures.append(f"{glb}: atlas bake with blend layers")


def check_figures(name, report, failures):
    """Seam and border contrast within the target, and lower than without
    blending."""
    figures = [(f"{f['node']}/{f['facet']} seam", f["seam_contrast"], f["seam_contrast_unblended"]) for f in report["facets"]]
    figures += [(f"{b['node']} facet border", b["border_contrast"], b["border_contrast_unblended"]) for b in report["borders"]]
    for what, blended, plain in figures:
        if blended is None:
            continue
        print(f"  {what} contrast {blended:.2f} (unblended {plain:.2f})")
        if blended > TARGET:
            failures.append(f"{name}: {what} contrast {blended:.2f} > {TARGET}")
        if plain <= blended:
            failures.append(f"{name}: {what} shows no less with blending ({blended:.2f} vs {plain:.2f})")


def check_interiors(target, report, failures):
    """Every interior block the report lists is an RGB uint8 NRRD of the
    listed size and voxel spacing, with all its voxel bytes (what 3D Slicer
    and ITK need to open it)."""
    for line in report.get("interiors", []):
        path = target / line["file"]
        data = path.read_bytes() if path.exists() else b""
        header, _, body = data.partition(b"\n\n")
        fields = dict(l.split(": ", 1) for l in header.decode(errors="replace").splitlines()[1:] if ": " in l)
        n = line["voxels"]
        spacing = [float(x) for x in fields.get("spacings", "").split()[1:]] or [0.0]
        if (not data.startswith(b"NRRD000") or fields.get("type") != "uint8" or fields.get("sizes") != f"3 {n} {n} {n}"
                or len(body) != 3 * n ** 3 or any(abs(x - line["voxel_size"]) > 1e-9 for x in spacing)):
            failures.append(f"{path}: not the {n}^3 RGB block of {line['voxel_size']} units the report lists")
        else:
            print(f"  interior {line['node']}: {n}^3 voxels of {line['voxel_size']} units")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--organtex", default=str(ROOT / "target" / "release" / "organtex"))
    parser.add_argument("--out", default=str(ROOT / "target" / "bake-check"))
    parser.add_argument("--glb", action="append", default=[], metavar="FILE",
                        help="also validate this .glb and load it with trimesh (e.g. a carved surface "
                             "written through the C API); repeatable")
    args = parser.parse_args()
    ensure_validator()

    out = Path(args.out)
    jobs = []
    for scene in sorted((ROOT / "scenes").glob("*.toml")):
        jobs.append((scene.stem, scene, []))
        if scene.stem == "hysteroscopy_myomas":
            jobs.append((scene.stem + "-atlas", scene, ["--atlas", "2048"]))
    failures = []
    glbs = []
    for name, scene, extra in jobs:
        target = out / name
        print(f"\n== bake {name}", flush=True)
        run = subprocess.run([args.organtex, "bake", str(scene), "-o", str(target), *extra], capture_output=True, text=True)
        if run.returncode != 0:
            failures.append(f"{name}: bake failed: {run.stderr.strip()}")
            continue
        report = json.loads((target / "report.json").read_text())
        glb = target / "scene.glb"
        glbs.append(glb)
        count = check_glb(glb, report, failures)
        check_json(glb, report, failures)
        print(f"  trimesh loaded {count} primitives; baked in {report['timings']['total_s']:.1f} s")
        check_figures(name, report, failures)
        check_interiors(target, report, failures)

    # A cut surface from `organtex section`: a small block, an oblique plane
    # through the bunny; trimesh must load it textured too.
    print("\n== section bunny", flush=True)
    cut = out / "section"
    cut.mkdir(parents=True, exist_ok=True)
    block = cut / "block.nrrd"
    steps = [
        [args.organtex, "synth3d", str(ROOT / "database" / "sources" / "ihc.png"), "--crop", "0,0,64,64", "--size", "32", "-o", str(block)],
        [args.organtex, "section", str(ROOT / "tests" / "data" / "bunny.obj"), "--block", str(block), "--plane", "0.3,0.2,1,0.35", "--scale", "0.004", "--resolution", "256", "-o", str(cut / "cut.glb")],
    ]
    for step in steps:
        run = subprocess.run(step, capture_output=True, text=True)
        if run.returncode != 0:
            failures.append(f"section: {step[1]} failed: {run.stderr.strip()}")
            break
    else:
        import trimesh

        scene = trimesh.load(str(cut / "cut.glb"), force="scene", process=False)
        geometry = list(scene.geometry.values())
        if len(geometry) != 1 or geometry[0].visual.uv is None or len(geometry[0].faces) == 0:
            failures.append("section: cut.glb is not one textured mesh with uvs")
        else:
            print(f"  trimesh loaded {len(geometry[0].faces)} textured triangles")
        glbs.append(cut / "cut.glb")

    for extra in map(Path, args.glb):
        print(f"\n== {extra}", flush=True)
        import trimesh

        if not extra.is_file():
            failures.append(f"{extra}: missing")
            continue
        scene = trimesh.load(str(extra), force="scene", process=False)
        faces = sum(len(g.faces) for g in scene.geometry.values())
        textured = sum(1 for g in scene.geometry.values() if getattr(g.visual, "uv", None) is not None)
        if faces == 0 or textured == 0:
            failures.append(f"{extra}: no textured triangles")
        print(f"  trimesh loaded {faces} triangles in {len(scene.geometry)} primitives, {textured} textured")
        glbs.append(extra)

    print("\n== glTF validator", flush=True)
    validator = subprocess.run(["node", str(ROOT / "tools" / "validate_gltf.js"), *map(str, glbs)], env={"GLTF_VALIDATOR_DIR": str(VALIDATOR / "node_modules" / "gltf-validator"), "PATH": shutil.os.environ.get("PATH", "")})
    if validator.returncode != 0:
        failures.append("the glTF validator reported errors")
    if failures:
        print("\nFAILED:\n  " + "\n  ".join(failures))
        sys.exit(1)
    print("\nall bakes valid")


if __name__ == "__main__":
    pyenv.ensure(REQUIREMENTS, __file__)
    main()
