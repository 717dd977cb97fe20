"""Unwrap an OBJ with Blender (bpy), for tools/compare_uv.py --blender.

Runs inside target/bpyenv. Usage: blender_unwrap.py METHOD IN.obj OUT.obj
  abf:   Blender's "Unwrap" (angle based: ABF++) along the seams IN.obj's uv
         islands give, so the flattening alone is compared on the same cut;
  smart: "Smart UV Project", Blender's automatic charting (its own seams).
Prints {"seconds": ...}: the unwrap operator alone, not import or export.
Axes are kept as in the file (forward Y, up Z both ways), and no margin
is added round the islands.
"""

import json
import sys
import time

import bpy


def main():
    method, source, target = sys.argv[1:4]
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.wm.obj_import(filepath=source, forward_axis="Y", up_axis="Z")
    obj = bpy.context.selected_objects[0]
    bpy.context.view_layer.objects.active = obj
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.select_all(action="SELECT")
    if method == "abf":
        bpy.ops.uv.select_all(action="SELECT")
        bpy.ops.uv.seams_from_islands(mark_seams=True)
        start = time.perf_counter()
        bpy.ops.uv.unwrap(method="ANGLE_BASED", margin=0.0)
    elif method == "smart":
        start = time.perf_counter()
        bpy.ops.uv.smart_project(island_margin=0.0)
    else:
        sys.exit(f"blender_unwrap.py: unknown method {method!r} (abf or smart)")
    seconds = time.perf_counter() - start
    bpy.ops.object.mode_set(mode="OBJECT")
    bpy.ops.wm.obj_export(filepath=target, forward_axis="Y", up_axis="Z", export_selected_objects=True,
                          export_uv=True, export_normals=False, export_materials=False,
                          apply_modifiers=False)
    print(json.dumps({"seconds": seconds}))


if __name__ == "__main__":
    main()
