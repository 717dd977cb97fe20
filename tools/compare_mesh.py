#!/usr/bin/env python3
"""organtex mesh beside VTK's segmentation-to-model pipeline as 3D Slicer
runs it (flying edges, windowed-sinc smoothing, quadric decimation) and
scikit-image's marching cubes, on the MNI ICBM152 volumes in
tests/data/volumes (issue 40).

Every surface is measured by the same VTK code: faces, non-manifold and
boundary edges, enclosed volume against the region's voxel volume, the
smallest angle, smoothness as the spread (standard deviation) of the
mean curvature over the vertices, and the Hausdorff distance between the
surface and the region's voxel boundary (the faces between its voxels and
the others), in voxels: both ways, each surface sampled (the mesh at its
vertices and about every 0.3 voxel over its triangles, the voxel faces at
nine points each, half a voxel apart), a point's distance to the mesh
that of the nearest mesh sample, to the voxel boundary the exact
distance to the nearest of its 16 nearest voxel faces. Sampling makes
each figure approximate: "from voxels" may overstate the true one by up
to about 0.17 voxel (the mesh samples' spacing) or understate it by up
to about 0.35 (the faces' samples); "to voxels" may understate it. Time is wall-clock, each
tool from the file to its surface.

Usage: tools/compare_mesh.py [--organtex target/release/organtex] [--max-handle MM] [--within-voxels [V ...]]
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
    ("brain, T1 >= 40", "mni_icbm152_t1_tal_nlin_sym_09a_converted.nii.gz", 40.0),
    ("grey matter at 0.5", "mni_icbm152_gm_tal_nlin_sym_09a_converted.nii.gz", 127.5),
]


def voxel_faces(inside):
    """Centres and normal axes of the faces between the region's voxels
    and the others (outside the volume counts as outside), in voxel
    index coordinates."""
    import numpy as np

    centres, axes = [], []
    for a in range(3):
        pad = [(0, 0)] * 3
        pad[a] = (1, 1)
        p = np.pad(inside, pad)
        lo = np.take(p, range(0, p.shape[a] - 1), axis=a)
        hi = np.take(p, range(1, p.shape[a]), axis=a)
        idx = np.argwhere(lo != hi).astype(np.float64)
        # Index i along a is the face between voxels i - 1 and i.
        idx[:, a] -= 0.5
        centres.append(idx)
        axes.append(np.full(len(idx), a))
    return np.vstack(centres), np.concatenate(axes)


def hausdorff(points, triangles, faces):
    """Both one-sided distances (max) between the mesh (`points` in voxel
    index coordinates, `triangles`) and voxel faces (centres, axes), as
    the module's comment says: from the mesh to the whole region's faces
    (a tool may keep every piece), from the largest piece's faces to the
    mesh (every tool keeps that one)."""
    import numpy as np
    from scipy.spatial import cKDTree

    (centres, axes), (piece_centres, piece_axes) = faces
    # Mesh samples: the vertices and a barycentric grid on every triangle
    # fine enough for 0.3 voxel spacing.
    corners = points[triangles]
    longest = np.max(np.linalg.norm(corners - np.roll(corners, 1, axis=1), axis=2), axis=1)
    samples = [points]
    for n in np.unique(np.ceil(longest / 0.3).astype(int)):
        if n < 2:
            continue
        tri = corners[np.ceil(longest / 0.3).astype(int) == n]
        ij = np.array([(i, j) for i in range(n + 1) for j in range(n + 1 - i)], dtype=np.float64) / n
        w = np.column_stack([1.0 - ij.sum(axis=1), ij])
        samples.append(np.einsum("sk,tkd->tsd", w, tri).reshape(-1, 3))
    mesh_samples = np.vstack(samples)
    # Mesh to voxel faces: exact distance to the nearest of 16 faces, in
    # chunks (millions of samples).
    tree = cKDTree(centres)
    best = []
    for query in np.array_split(mesh_samples, max(1, len(mesh_samples) // 400_000)):
        _, near = tree.query(query, k=16)
        nearest = np.full(len(query), np.inf)
        for k in range(near.shape[1]):
            c = centres[near[:, k]]
            a = axes[near[:, k]]
            d = query - c
            normal = np.take_along_axis(d, a[:, None], axis=1)[:, 0]
            inplane = np.clip(np.abs(d) - 0.5, 0.0, None)
            inplane[np.arange(len(a)), a] = 0.0
            nearest = np.minimum(nearest, np.sqrt(normal**2 + (inplane**2).sum(axis=1)))
        best.append(nearest.max())
    mesh_to_voxels = float(max(best))
    # Voxel faces to the mesh: nine points per face.
    offsets = np.array([(u, v) for u in (-0.5, 0.0, 0.5) for v in (-0.5, 0.0, 0.5)])
    face_points = []
    for a in range(3):
        sel = piece_centres[piece_axes == a]
        others = [b for b in range(3) if b != a]
        for u, v in offsets:
            q = sel.copy()
            q[:, others[0]] += u
            q[:, others[1]] += v
            face_points.append(q)
    face_points = np.vstack(face_points)
    distance, _ = cKDTree(mesh_samples).query(face_points)
    return mesh_to_voxels, float(distance.max())


def measure(poly, voxel_volume, to_voxels=None, faces=None):
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
    figures = {}
    if faces is not None:
        points = vtk_to_numpy(poly.GetPoints().GetData()).astype(np.float64)
        points = to_voxels(points)
        cells = vtk_to_numpy(poly.GetPolys().GetConnectivityArray()).reshape(-1, 3)
        there, back = hausdorff(points, cells, faces)
        figures = {"hausdorff_to_voxels": there, "hausdorff_from_voxels": back,
                   "hausdorff_voxels": max(there, back)}
    return figures | {
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
    from scipy import ndimage

    inside = data >= level
    # The largest piece, its voxels joined as organtex's surface joins
    # them (Kuhn's split: offsets that are 0/1 vectors or their negatives).
    joined = np.zeros((3, 3, 3), dtype=bool)
    for d in np.ndindex(2, 2, 2):
        joined[1 + d[0], 1 + d[1], 1 + d[2]] = True
        joined[1 - d[0], 1 - d[1], 1 - d[2]] = True
    labels, _ = ndimage.label(inside, structure=joined)
    sizes = np.bincount(labels.ravel())
    sizes[0] = 0
    largest = labels == sizes.argmax()
    return data, float(inside.sum() * spacing), (voxel_faces(inside), voxel_faces(largest)), img.affine


def from_world(affine):
    """World millimetres (organtex's output, through the file's sform) to
    voxel indices."""
    import numpy as np

    inverse = np.linalg.inv(affine)
    return lambda p: p @ inverse[:3, :3].T + inverse[:3, 3]


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
    # VTK's reader gives points at origin + spacing * index.
    image = reader.GetOutput()
    origin, spacing = image.GetOrigin(), image.GetSpacing()
    return decimate.GetOutput(), seconds, lambda p: (p - origin) / spacing


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


def organtex_mesh(exe, path, level, faces, out, max_handle=None, within_voxels=None):
    import vtk

    start = time.perf_counter()
    handle = ["--max-handle", str(max_handle)] if max_handle else []
    if within_voxels:
        handle += ["--within-voxels", str(within_voxels)]
    subprocess.run(
        [exe, "mesh", str(path), "--threshold", str(level), "--faces", str(faces),
         "-o", str(out), "--json", *handle],
        check=True, capture_output=True,
    )
    seconds = time.perf_counter() - start
    reader = vtk.vtkPLYReader()
    reader.SetFileName(str(out))
    reader.Update()
    return reader.GetOutput(), seconds


def main():
    pyenv.ensure(["vtk", "scikit-image", "nibabel", "numpy", "scipy"], __file__)
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--organtex", default=str(ROOT / "target" / "release" / "organtex"))
    ap.add_argument("--faces", type=int, default=50000)
    ap.add_argument("--json")
    ap.add_argument("--max-handle", type=float,
                    help="also organtex with --max-handle MM (thin handles cut or plugged)")
    ap.add_argument("--within-voxels", type=float, nargs="*",
                    help="also organtex with --within-voxels V for each V given (every voxel corner held "
                         "within V voxels through the decimation; 0.9 if none given)")
    args = ap.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, file, level in CASES:
            path = VOLUMES / file
            data, voxel_volume, faces, affine = region(path, level)
            poly, t = organtex_mesh(args.organtex, path, level, args.faces, Path(tmp) / "o.ply")
            rows.append({"case": name, "tool": "organtex", "seconds": t,
                         **measure(poly, voxel_volume, from_world(affine), faces)})
            if args.max_handle:
                poly, t = organtex_mesh(args.organtex, path, level, args.faces, Path(tmp) / "h.ply",
                                        args.max_handle)
                rows.append({"case": name, "tool": f"organtex --max-handle {args.max_handle:g}",
                             "seconds": t, **measure(poly, voxel_volume, from_world(affine), faces)})
            for within in ([0.9] if args.within_voxels == [] else args.within_voxels or []):
                poly, t = organtex_mesh(args.organtex, path, level, args.faces, Path(tmp) / "w.ply",
                                        within_voxels=within)
                rows.append({"case": name, "tool": f"organtex --within-voxels {within:g}",
                             "seconds": t, **measure(poly, voxel_volume, from_world(affine), faces)})
            poly, t, to_voxels = vtk_pipeline(path, level, args.faces)
            rows.append({"case": name, "tool": "VTK (Slicer's pipeline)", "seconds": t,
                         **measure(poly, voxel_volume, to_voxels, faces)})
            poly, t = skimage_mc(data, level)
            rows.append({"case": name, "tool": "scikit-image marching cubes (no smoothing or decimation)", "seconds": t,
                         **measure(poly, voxel_volume, lambda p: p, faces)})
            print(f"{name}: measured", flush=True)
    keys = ["seconds", "faces", "non_manifold_edges", "boundary_edges", "volume_vs_voxels_pct", "min_angle",
            "mean_curvature_spread", "hausdorff_to_voxels", "hausdorff_from_voxels"]
    print("| case | tool | " + " | ".join(keys) + " |")
    print("|" + "---|" * (len(keys) + 2))
    for r in rows:
        cells = [f"{r[k]:.3g}" if isinstance(r[k], float) else str(r[k]) for k in keys]
        print(f"| {r['case']} | {r['tool']} | " + " | ".join(cells) + " |")
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=2))


if __name__ == "__main__":
    main()
