"""organtex from Python: read meshes, unwrap them, synthesise tileable
textures and solid blocks, cut sections, morph interiors from photographed
cuts, bake scenes. Arrays are numpy
arrays in and out; every call releases the GIL while it works, takes an
optional ``progress(stage, done, total)`` callable, stops on Ctrl-C, and
raises :class:`OrgantexError` with the library's message (which names the
file and what is wrong).

Batch bakes of many scenes on a Ray cluster: ``python -m organtex.batch``.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from os import PathLike
from typing import Callable, Optional, Sequence, Tuple, Union

import numpy as np

from . import _core
from ._core import OrgantexError

__all__ = ["Mesh", "Morph", "OrgantexError", "read_mesh", "unwrap", "synth", "synth3d", "section",
           "tetra", "bake", "check_scene", "manifest"]

Progress = Optional[Callable[[str, int, int], None]]
Path_ = Union[str, "PathLike[str]"]


@dataclass
class Mesh:
    """A triangle mesh: ``vertices`` (n, 3) float64, ``faces`` (m, 3)
    uint32 (counter-clockwise seen from outside), ``facets`` (m,) uint32,
    each face's index into ``facet_names``."""

    vertices: np.ndarray
    faces: np.ndarray
    facets: np.ndarray
    facet_names: list


def _f64(a, columns: int, name: str) -> bytes:
    a = np.ascontiguousarray(a, dtype="<f8")
    if a.ndim != 2 or a.shape[1] != columns:
        raise OrgantexError(f"{name} must be an (n, {columns}) array, not shape {a.shape}")
    return a.tobytes()


def _u32(a, columns: int, name: str) -> bytes:
    a = np.asarray(a)
    if a.ndim != 2 or a.shape[1] != columns:
        raise OrgantexError(f"{name} must be an (m, {columns}) array, not shape {a.shape}")
    if a.size and (a.min() < 0 or a.max() > 0xFFFFFFFF):
        raise OrgantexError(f"{name} holds an index that is negative or too large")
    return np.ascontiguousarray(a, dtype="<u4").tobytes()


def _rgb(image) -> Tuple[bytes, int, int]:
    a = np.asarray(image)
    if a.ndim != 3 or a.shape[2] < 3 or a.dtype != np.uint8:
        raise OrgantexError(f"an image must be an (h, w, 3) uint8 array, not {a.dtype} {a.shape}")
    a = np.ascontiguousarray(a[:, :, :3])
    return a.tobytes(), a.shape[1], a.shape[0]


def read_mesh(path: Path_) -> Mesh:
    """Read an OBJ, PLY or STL mesh (OBJ groups and STL solids become
    facets)."""
    v, f, ids, names = _core.read_mesh(str(path))
    return Mesh(np.frombuffer(v, "<f8").reshape(-1, 3), np.frombuffer(f, "<u4").reshape(-1, 3),
                np.frombuffer(ids, "<u4"), list(names))


def unwrap(vertices, faces, *, split_overlaps: bool = False, atlas_faces: Optional[int] = None,
           progress: Progress = None) -> Tuple[np.ndarray, np.ndarray, dict]:
    """Cut a closed or open mesh along hidden seams (Seamster) and flatten
    each piece with ABF++: ``(uv, uv_faces, report)``, ``uv`` (k, 2)
    float64, ``uv_faces`` (m, 3) uint32 indexing ``uv`` per corner (a seam
    gives one vertex several uvs), ``report`` as ``organtex unwrap --json``
    prints it (charts, flipped triangles, stretch, timings)."""
    uv, uv_faces, report = _core.unwrap(_f64(vertices, 3, "vertices"), _u32(faces, 3, "faces"),
                                        split_overlaps, atlas_faces, progress)
    return (np.frombuffer(uv, "<f8").reshape(-1, 2), np.frombuffer(uv_faces, "<u4").reshape(-1, 3),
            json.loads(report))


def synth(exemplar, size: int, tileable: bool = True, seed: int = 0, mask=None,
          progress: Progress = None) -> np.ndarray:
    """A ``size`` x ``size`` texture synthesised pixel by pixel (FNPTS)
    from an (h, w, 3) uint8 exemplar; ``mask`` (h, w), true where pixels
    may be copied. Tileable by default; the same seed gives the same
    pixels on any number of threads."""
    data, w, h = _rgb(exemplar)
    m = None
    if mask is not None:
        m = np.ascontiguousarray(np.asarray(mask) != 0, dtype=np.uint8)
        if m.shape != (h, w):
            raise OrgantexError(f"the mask must be {h}x{w} (rows, columns), not {m.shape}")
        m = m.tobytes()
    out = _core.synth(data, w, h, size, tileable, seed, m, progress)
    return np.frombuffer(out, np.uint8).reshape(size, size, 3)


def synth3d(exemplar, size: int, seed: int = 0, method: str = "fnpts",
            progress: Progress = None) -> np.ndarray:
    """A solid texture block tiling in x, y and z, (size, size, size, 3)
    uint8 indexed [z, y, x], from an (h, w, 3) uint8 exemplar; ``method``
    "fnpts" (sharp) or "optimize" (no streaks, softer)."""
    data, w, h = _rgb(exemplar)
    out = _core.synth3d(data, w, h, size, seed, method, progress)
    return np.frombuffer(out, np.uint8).reshape(size, size, size, 3)


def section(vertices, faces, block, plane: Sequence[float], scale: float = 1.0
            ) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The section of a closed mesh by the plane ``(nx, ny, nz, d)``
    (n . p = d), coloured from a tiling ``block`` ((n, n, n, 3) uint8,
    [z, y, x], one voxel ``scale`` mesh units, placed at the origin):
    ``(positions (k, 3), triangles (t, 3), colours (k, 3) uint8)``."""
    b = np.ascontiguousarray(np.asarray(block, dtype=np.uint8))
    if b.ndim != 4 or b.shape[3] != 3 or not (b.shape[0] == b.shape[1] == b.shape[2]):
        raise OrgantexError(f"the block must be an (n, n, n, 3) uint8 array, not {b.shape}")
    if len(plane) != 4:
        raise OrgantexError("the plane is four numbers: nx, ny, nz, d")
    v, f, c = _core.section(_f64(vertices, 3, "vertices"), _u32(faces, 3, "faces"), b.tobytes(),
                            b.shape[0], [float(x) for x in plane[:3]], float(plane[3]), float(scale))
    return (np.frombuffer(v, "<f8").reshape(-1, 3), np.frombuffer(f, "<u4").reshape(-1, 3),
            np.frombuffer(c, np.uint8).reshape(-1, 3))


class Morph:
    """An interior morphed from photographs of a few cuts placed as planes
    in a closed mesh (seed 003; the sections file as ``organtex morph
    --help`` describes it): precomputed once, then ``colours(points)`` at
    any points, on demand."""

    def __init__(self, vertices, faces, sections: Path_, *, progress: Progress = None):
        self._core = _core.Morph(_f64(vertices, 3, "vertices"), _u32(faces, 3, "faces"), str(sections),
                                 progress)

    @property
    def exemplars(self) -> int:
        return self._core.exemplars

    @property
    def regions(self) -> int:
        return self._core.regions

    def colours(self, points) -> np.ndarray:
        """The colours, (n, 3) uint8, at ``points`` (n, 3)."""
        rgb = self._core.colours(_f64(points, 3, "points"))
        return np.frombuffer(rgb, np.uint8).reshape(-1, 3)


def tetra(vertices, faces, *, edge_length: Optional[float] = None, cells: Optional[int] = None,
          graded: bool = False, progress: Progress = None) -> Tuple[np.ndarray, np.ndarray, dict]:
    """Fill a closed mesh with tetrahedra (isosurface stuffing, as
    ``organtex tetra``): ``(points (n, 3) float64, tets (t, 4) uint32,
    report)``, every tet positively oriented; by default a resolution
    whose boundary stays within 1% of the bounding diagonal."""
    p, t, report = _core.tetra(_f64(vertices, 3, "vertices"), _u32(faces, 3, "faces"), edge_length,
                               cells, graded, progress)
    return np.frombuffer(p, "<f8").reshape(-1, 3), np.frombuffer(t, "<u4").reshape(-1, 4), json.loads(report)


def bake(scene_path: Path_, out_dir: Path_, atlas: Optional[int] = None,
         progress: Progress = None) -> dict:
    """Bake a scene file into ``out_dir`` (scene.glb, report.json,
    preview.png, interior/), exactly as ``organtex bake`` does: the same
    scene and seed give the same bytes. Returns report.json as a dict.
    Files already in ``out_dir`` are replaced only when the bake
    succeeds."""
    return json.loads(_core.bake(str(scene_path), str(out_dir), atlas, progress))


def check_scene(scene_path: Path_) -> None:
    """Raise what a bake of the scene would raise before its long steps
    (the file, its includes, each node's mesh read or generated, facets
    matched); return quietly if it would start."""
    _core.check_scene(str(scene_path))


def manifest(path: Path_) -> list:
    """The scene paths a manifest lists (one per line, relative to it;
    blank and # lines skipped), as ``organtex bake --manifest`` reads it."""
    return [str(p) for p in _core.manifest(str(path))]
