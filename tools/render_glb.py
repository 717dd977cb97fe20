"""Render a .glb headlessly in Blender, as an engine that reads the file sees it.

Usage: tools/render_glb.py IN.glb OUT.png [--size 640x480] [--samples 16]
           [--engine cycles|eevee] [--lighting unitless|standard|raw]
           [--view Standard|AgX|"Khronos PBR Neutral"] [--exposure EV] [--denoise]

Re-runs itself inside target/bpyenv (Blender's bpy from PyPI, the environment
tools/compare_uv.py uses; bpy 4.5 wheels need Python 3.11, so a python3.11 on
PATH is used when the current python is another version). Then it imports
IN.glb with Blender's glTF importer, looks through the file's first camera
(cameras[0], on the first node that uses it), and lights the scene with the
file's KHR_lights_punctual lights alone: the world is black, strength 0.
Punctual lights get radius 0, as glTF defines them.

--lighting is the importer's lighting mode for the lights' intensities:
  unitless (default): Blender W = 4*pi*cd, so a spot of I cd gives I/d^2
      irradiance at d metres, as three.js, Babylon.js and the Khronos sample
      viewer show the file (no exposure, no 683 lm/W);
  standard: the physical one, W = 4*pi*cd/683 (683x darker: about -9.4 EV);
  raw: W = cd.
Cycles runs on the CPU, without denoising unless --denoise (OpenImageDenoise);
--engine eevee runs on software EGL, some 5x slower. The view transform is
"Standard" (plain sRGB: highlights clip to white as in a viewer without tone
mapping); AgX and Khronos PBR Neutral compress highlights, so fewer count.

Prints the extensions the file uses and which of them Blender's importer reads
or ignores (it ignores unknown ones silently), each material's Principled BSDF
(roughness, coat weight and roughness), each light, the render time, and the
fraction of pixels that are specular highlights (HSV V >= 0.9 and S <= 0.25),
then one JSON line with all of it.
"""

import argparse
import json
import os
import shutil
import struct
import sys
import time
from pathlib import Path

BPY = ["bpy==4.5.4"]  # the pin tools/compare_uv.py uses: one target/bpyenv for both
LIGHTING = {"unitless": "COMPAT", "standard": "SPEC", "raw": "RAW"}


def relaunch():
    """Re-run this script inside target/bpyenv, created with Python 3.11."""
    if sys.version_info[:2] != (3, 11) and shutil.which("python3.11"):
        os.execvp("python3.11", ["python3.11", __file__, *sys.argv[1:]])
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    import pyenv
    venv = pyenv.ROOT / "target" / "bpyenv"
    if sys.version_info[:2] != (3, 11) and not (venv / "bin" / "python").exists():
        sys.exit(f"render_glb.py: {BPY[0]} needs Python 3.11, and this is {sys.version.split()[0]}")
    python = pyenv.python_with(BPY, venv, "render_glb.py")
    if Path(sys.prefix).resolve() == venv.resolve():
        sys.exit("render_glb.py: bpy does not import in target/bpyenv")  # no loop
    os.execv(str(python), [str(python), __file__, *sys.argv[1:]])


def glb_json(path):
    data = Path(path).read_bytes()
    magic, _, _ = struct.unpack_from("<III", data)
    length, kind = struct.unpack_from("<II", data, 12)
    if magic != 0x46546C67 or kind != 0x4E4F534A:
        sys.exit(f"render_glb.py: {path} is not a glTF binary")
    return json.loads(data[20:20 + length])


def first_camera(doc):
    """The Blender object of cameras[0]: the importer names it after its node."""
    import bpy
    cams = [o for o in bpy.context.scene.objects if o.type == "CAMERA"]
    if not cams:
        sys.exit("render_glb.py: the file has no camera")
    nodes = [n for n in doc.get("nodes", []) if n.get("camera") == 0]
    name = nodes[0].get("name") if nodes else None
    name = name or doc["cameras"][0].get("name") or "Camera"
    exact = [o for o in cams if o.name == name] or [o for o in cams if o.name.startswith(name)]
    return (exact or sorted(cams, key=lambda o: o.name))[0]


def socket(node, name):
    s = node.inputs.get(name)
    if s is None or s.is_linked:
        return "texture" if s else None
    v = s.default_value
    return round(v, 4) if isinstance(v, float) else [round(c, 4) for c in v]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("glb"), ap.add_argument("png"), ap.add_argument("--size", default="640x480")
    ap.add_argument("--samples", type=int, default=16)
    ap.add_argument("--engine", choices=["cycles", "eevee"], default="cycles")
    ap.add_argument("--lighting", choices=list(LIGHTING), default="unitless")
    ap.add_argument("--view", default="Standard"), ap.add_argument("--exposure", type=float, default=0.0)
    ap.add_argument("--denoise", action="store_true", help="OpenImageDenoise (Cycles)")
    ap.add_argument("--check", action="store_true",
                    help="exit 1 unless Blender reads every extension the file uses, a material with a "
                         "clear coat came in coated, a light came in, and the render shows highlights")
    args = ap.parse_args()
    width, height = (int(v) for v in args.size.lower().split("x"))
    try:
        import bpy
        import numpy as np
    except ImportError:
        relaunch()
    from io_scene_gltf2.io.imp.gltf2_io_gltf import glTFImporter

    glb, png = str(Path(args.glb).resolve()), str(Path(args.png).resolve())
    doc = glb_json(glb)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    start = time.perf_counter()
    bpy.ops.import_scene.gltf(filepath=glb, export_import_convert_lighting_mode=LIGHTING[args.lighting])
    print(f"bpy {bpy.app.version_string}, python {sys.version.split()[0]}: imported in {time.perf_counter() - start:.2f} s")

    read = set(glTFImporter(glb, {"import_user_extensions": []}).extensions_managed)
    used = doc.get("extensionsUsed", [])
    exts = {"used": used, "required": doc.get("extensionsRequired", []),
            "read": [e for e in used if e in read], "ignored": [e for e in used if e not in read]}
    print(f"extensions: used {used or 'none'}; Blender reads {exts['read'] or 'none'}; ignores {exts['ignored'] or 'none'}")

    scene = bpy.context.scene
    camera = first_camera(doc)
    scene.camera = camera
    print(f"camera: {camera.name} ({camera.data.type}, vertical fov {camera.data.angle_y:.4f} rad)")
    scene.world = world = bpy.data.worlds.new("black")
    world.use_nodes = True
    background = world.node_tree.nodes["Background"]
    background.inputs["Color"].default_value, background.inputs["Strength"].default_value = (0, 0, 0, 1), 0.0

    materials = []
    for mat in bpy.data.materials:
        bsdf = next((n for n in mat.node_tree.nodes if n.type == "BSDF_PRINCIPLED"), None) if mat.use_nodes else None
        m = {"name": mat.name, "principled": bsdf is not None}
        if bsdf:
            m.update({k.lower().replace(" ", "_"): socket(bsdf, k) for k in
                      ("Base Color", "Roughness", "Metallic", "Coat Weight", "Coat Roughness")})
            m["coat"] = m["coat_weight"] == "texture" or (m["coat_weight"] or 0) > 0
        materials.append(m)
        print("material: " + ", ".join(f"{k} {v}" for k, v in m.items() if k != "name") + f"  [{mat.name}]")
    lights = []
    for obj in (o for o in scene.objects if o.type == "LIGHT"):
        light = obj.data
        light.shadow_soft_size = 0.0  # punctual
        entry = {"name": obj.name, "type": light.type, "power_w": round(light.energy, 4),
                 "color": [round(c, 4) for c in light.color]}
        if light.type == "SPOT":
            entry["spot_size_deg"] = round(light.spot_size * 180 / 3.141592653589793, 3)
            entry["spot_blend"] = round(light.spot_blend, 4)
        lights.append(entry)
        print("light: " + ", ".join(f"{k} {v}" for k, v in entry.items()))
    for g in doc.get("extensions", {}).get("KHR_lights_punctual", {}).get("lights", []):
        print(f"glTF light: {g.get('name')}, {g['type']}, intensity {g.get('intensity', 1.0)}, spot {g.get('spot')}")
    if not lights:
        print("render_glb.py: warning: the file has no KHR_lights_punctual light: the image is black")

    render = scene.render
    if args.engine == "cycles":
        render.engine = "CYCLES"
        cycles = scene.cycles
        cycles.device, cycles.samples, cycles.use_adaptive_sampling = "CPU", args.samples, False
        cycles.use_denoising, cycles.denoiser = args.denoise, "OPENIMAGEDENOISE"
    else:
        render.engine = "BLENDER_EEVEE_NEXT" if bpy.app.version < (5, 0) else "BLENDER_EEVEE"
        scene.eevee.taa_render_samples = args.samples
    render.resolution_x, render.resolution_y, render.resolution_percentage = width, height, 100
    render.film_transparent, render.filepath = False, png
    render.image_settings.file_format, render.image_settings.color_mode = "PNG", "RGB"
    view = scene.view_settings
    view.view_transform, view.look, view.exposure = args.view, "None", args.exposure
    sys.stdout.flush()
    saved, null = os.dup(1), os.open(os.devnull, os.O_WRONLY)
    os.dup2(null, 1)  # Cycles prints a progress line for each sample: keep them out
    try:
        start = time.perf_counter()
        bpy.ops.render.render(write_still=True)
        seconds = time.perf_counter() - start
    finally:
        os.dup2(saved, 1), os.close(saved), os.close(null)
    print(f"render: {args.engine}, {width}x{height}, {args.samples} samples, {seconds:.1f} s -> {png}")

    image = bpy.data.images.load(png)
    px = np.empty(width * height * 4, dtype=np.float32)
    image.pixels.foreach_get(px)
    rgb = px.reshape(-1, 4)[:, :3]
    v = rgb.max(axis=1)
    s = (v - rgb.min(axis=1)) / np.maximum(v, 1e-9)
    highlight, lit = (v >= 0.9) & (s <= 0.25), v > 0.02
    frac = float(highlight.mean())
    frac_lit = float(highlight.sum() / max(lit.sum(), 1))
    print(f"highlights (V >= 0.9, S <= 0.25): {frac:.4%} of the image, {frac_lit:.4%} of its lit pixels "
          f"(V > 0.02: {lit.mean():.2%} of the image); mean V {v.mean():.3f}")
    print(json.dumps({"bpy": bpy.app.version_string, "extensions": exts, "camera": camera.name,
                      "materials": materials, "lights": lights, "render_seconds": round(seconds, 2),
                      "highlight_fraction": round(frac, 6), "highlight_fraction_lit": round(frac_lit, 6),
                      "lit_fraction": round(float(lit.mean()), 6), "png": png}))
    if args.check:
        failures = [f"Blender ignores {e}" for e in exts["ignored"]]
        if "KHR_materials_clearcoat" in exts["used"] and not any(m.get("coat") for m in materials):
            failures.append("no material came in with a clear coat")
        if not lights:
            failures.append("no light came in")
        if frac <= 0.0:
            failures.append("the render shows no highlight")
        for f in failures:
            print(f"render_glb.py: FAIL: {f}")
        if failures:
            sys.exit(1)
        print("render_glb.py: every extension read, coat and light in, highlights shown")


if __name__ == "__main__":
    main()
