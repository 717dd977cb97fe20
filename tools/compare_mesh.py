#!/usr/bin/env python3
"""organtex mesh beside VTK's segmentation-to-model pipeline as 3D Slicer
runs it (flying edges, windowed-sinc smoothing, quadric decimation) and
scikit-image's marching cubes, on the MNI ICBM152 volumes in
tests/data/volumes (issue 40).

Every surface is measured by the same VTK code: faces, non-manifold and
boundary edges, enclosed volume against the region's voxel volume, the
smallest angle, and smoothness as the spread (standard deviation) of the
mean curvature over the vertices. Time is wall-clock, each tool from the
file to its surface.

Usage: tools/compare_mesh.py [--organtex target/release/organtex]
                             [--faces 50000] [--json OUT.json]
"""

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import pyenv  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
VOLUMES = ROOT / "tests" / "data" / "volumes"
CASES = [
    ("white matter at 0.5", "mni_icbm152_wm_tal_nlin_sym_09a_converted.nii.gz", 127.5),
    ("head, T1 >= 40", "mni_icbm152_t1_tal_nlin_sym_09a_converted.nii.gz", 40.0),
]


def measure(poly, voxel_volume):
    import numpy as np
    import vtk
    from vtk.util.numpy_support import vtk_to_numpy

    tri = vtk.vtkTriangleFilter()
    tri.SetInputData(poly)
    tri.Update()
    poly = tri.GetOutput()
    edges = vtk.vtkFeatureEdges()
    edges.SetInputData(poly)
    edges.BoundaryEdgesOn()
    edges.NonManifoldEdgesOff()
    edges.FeatureEdgesOff()
    edges.ManifoldEdgesOff()
    edges.Update()
    boundary = edges.GetOutput().GetNumberOfCells()
    edges.BoundaryEdgesOff()
    edges.NonManifoldEdgesOn()
    edges.Update()
    non_manifold = edges.GetOutput().GetNumberOfCells()
    mass = vtk.vtkMassProperties()
    mass.SetInputData(poly)
    mass.Update()
    quality = vtk.vtkMeshQuality()
    quality.SetInputData(poly)
    quality.SetTriangleQualityMeasureToMinAngle()
    quality.Update()
    angles = vtk_to_numpy(quality.GetOutput().GetCellData().GetArray("Quality"))
    curv = vtk.vtkCurvatures()
    curv.SetInputData(poly)
    curv.SetCurvatureTypeToMean()
    curv.Update()
    mean = vtk_to_numpy(curv.GetOutput().GetPointData().GetArray("Mean_Curvature"))
    mean = mean[np.isfinite(mean)]
    return {
        "faces": poly.GetNumberOfCells(),
        "boundary_edges": boundary,
        "non_manifold_edges": non_manifold,
        "volume_vs_voxels_pct": 100.0 * (mass.GetVolume() / voxel_volume - 1.0),
        "min_angle": float(angles.min()),
        "mean_curvature_spread": float(mean.std()),
    }


def region(path, level):
    import nibabel
    import numpy as np

    img = nibabel.load(str(path))
    data = np.asarray(img.dataobj, dtype=np.float32)
    spacing = abs(np.linalg.det(img.affine[:3, :3]))
    return data, float((data >= level).sum() * spacing)


def vtk_pipeline(path, level, faces):
    """Slicer's model maker: flying edges, windowed sinc (20 iterations,
    pass band 0.1), quadric decimation to the face budget."""
    import vtk

    start = time.perf_counter()
    reader = vtk.vtkNIFTIImageReader()
    reader.SetFileName(str(path))
    surface = vtk.vtkFlyingEdges3D()
    surface.SetInputConnection(reader.GetOutputPort())
    surface.SetValue(0, level)
    smooth = vtk.vtkWindowedSincPolyDataFilter()
    smooth.SetInputConnection(surface.GetOutputPort())
    smooth.SetNumberOfIterations(20)
    smooth.SetPassBand(0.1)
    smooth.BoundarySmoothingOff()
    smooth.NonManifoldSmoothingOn()
    smooth.NormalizeCoordinatesOn()
    smooth.Update()
    full = smooth.GetOutput().GetNumberOfCells()
    decimate = vtk.vtkQuadricDecimation()
    decimate.SetInputConnection(smooth.GetOutputPort())
    decimate.SetTargetReduction(max(0.0, 1.0 - faces / full))
    decimate.VolumePreservationOn()
    decimate.Update()
    seconds = time.perf_counter() - start
    return decimate.GetOutput(), seconds


def skimage_mc(data, level):
    import numpy as np
    import vtk
    from skimage import measure as skm
    from vtk.util.numpy_support import numpy_to_vtk, numpy_to_vtkIdTypeArray

    start = time.perf_counter()
    verts, faces, _, _ = skm.marching_cubes(data, level)
    seconds = time.perf_counter() - start
    poly = vtk.vtkPolyData()
    points = vtk.vtkPoints()
    points.SetData(numpy_to_vtk(verts.astype(np.float64), deep=True))
    poly.SetPoints(points)
    cells = np.hstack([np.full((len(faces), 1), 3), faces]).astype(np.int64).ravel()
    arr = vtk.vtkCellArray()
    arr.ImportLegacyFormat(numpy_to_vtkIdTypeArray(cells, deep=True))
    poly.SetPolys(arr)
    return poly, seconds


def organtex_mesh(exe, path, level, faces, out):
    import vtk

    start = time.perf_counter()
    subprocess.run(
        [exe, "mesh", str(path), "--threshold", str(level), "--faces", str(faces),
         "-o", str(out), "--json"],
        check=True, capture_output=True,
    )
    seconds = time.perf_counter() - start
    reader = vtk.vtkPLYReader()
    reader.SetFileName(str(out))
    reader.Update()
    return reader.GetOutput(), seconds


def main():
    pyenv.ensure(["vtk", "scikit-image", "nibabel", "numpy"], __file__)
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--organtex", default=str(ROOT / "target" / "release" / "organtex"))
    ap.add_argument("--faces", type=int, default=50000)
    ap.add_argument("--json")
    args = ap.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, file, level in CASES:
            path = VOLUMES / file
            data, voxel_volume = region(path, level)
            poly, t = organtex_mesh(args.organtex, path, level, args.faces, Path(tmp) / "o.ply")
            rows.append({"case": name, "tool": "organtex", "seconds": t, **measure(poly, voxel_volume)})
            poly, t = vtk_pipeline(path, level, args.faces)
            rows.append({"case": name, "tool": "VTK (Slicer's pipeline)", "seconds": t, **measure(poly, voxel_volume)})
            poly, t = skimage_mc(data, level)
            rows.append({"case": name, "tool": "scikit-image marching cubes (no smoothing or decimation)", "seconds": t, **measure(poly, voxel_volume)})
    keys = ["seconds", "faces", "non_manifold_edges", "boundary_edges", "volume_vs_voxels_pct", "min_angle", "mean_curvature_spread"]
    print("| case | tool | " + " | ".join(keys) + " |")
    print("|" + "---|" * (len(keys) + 2))
    for r in rows:
        cells = [f"{r[k]:.3g}" if isinstance(r[k], float) else str(r[k]) for k in keys]
        print(f"| {r['case']} | {r['tool']} | " + " | ".join(cells) + " |")
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=2))


if __name__ == "__main__":
    main()
