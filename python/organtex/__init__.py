"""organtex from Python: read meshes, unwrap them, synthesise tileable
textures and solid blocks, cut sections, morph interiors from photographed
cuts, bake scenes, and carve a bake's tet meshes as a simulator does
(:class:`Bake`, :class:`Carving`). Arrays are numpy
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
           "tetra", "bake", "check_scene", "manifest", "Bake", "Node", "Carving", "Step"]

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
    preview.png, interior/, unwraps/), exactly as ``organtex bake`` does: the same
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


# The simulator's runtime: a bake's nodes, their colours, and carving.

@dataclass
class Step:
    """What one carving step changed. ``removed`` (k,) uint32 tet ids;
    the faces that appeared: ``ids`` (n,) uint32 (``4 * tet + k``),
    ``vertices`` (n, 3) uint32 tet mesh vertex ids (counter-clockwise seen
    from outside), ``pages`` (n,) uint32 atlas pages, ``uvs`` (n, 3, 2)
    float32 (0..1, v down), ``colours`` (n, 3, 3) uint8 (each corner's
    interior colour); the faces that vanished: ``vanished_ids`` (m,),
    ``vanished_vertices`` (m, 3); ``dirty`` (d, 5) uint32 rectangles
    (page, x, y, width, height) to upload; ``released`` pages no face uses
    any more; ``texels_pending`` when a background job still fills this
    step's texels (:meth:`Carving.wait`); ``seconds`` the step took."""

    removed: np.ndarray
    ids: np.ndarray
    vertices: np.ndarray
    pages: np.ndarray
    uvs: np.ndarray
    colours: np.ndarray
    vanished_ids: np.ndarray
    vanished_vertices: np.ndarray
    dirty: np.ndarray
    released: np.ndarray
    texels_pending: bool
    seconds: float


def _step(raw) -> Step:
    (removed, ids, vertices, pages, uvs, colours, gone, gone_vertices, dirty, released, pending,
     seconds) = raw
    return Step(np.frombuffer(removed, "<u4"), np.frombuffer(ids, "<u4"),
                np.frombuffer(vertices, "<u4").reshape(-1, 3), np.frombuffer(pages, "<u4"),
                np.frombuffer(uvs, "<f4").reshape(-1, 3, 2),
                np.frombuffer(colours, np.uint8).reshape(-1, 3, 3), np.frombuffer(gone, "<u4"),
                np.frombuffer(gone_vertices, "<u4").reshape(-1, 3),
                np.frombuffer(dirty, "<u4").reshape(-1, 5), np.frombuffer(released, "<u4"),
                bool(pending), float(seconds))


class Node:
    """A node of a bake (see :class:`Bake`): its interior and tet mesh."""

    def __init__(self, core):
        self._core = core

    @property
    def name(self) -> str:
        return self._core.name

    def tet_mesh(self) -> Tuple[np.ndarray, np.ndarray]:
        """``(positions (n, 3) float64, tets (m, 4) uint32)``, the ids of
        the bake's .vtk, as a simulator's physics loads it."""
        p, t = self._core.tet_mesh()
        return np.frombuffer(p, "<f8").reshape(-1, 3), np.frombuffer(t, "<u4").reshape(-1, 4)

    def colours(self, points) -> np.ndarray:
        """The interior's (n, 3) uint8 colours at (n, 3) points."""
        return np.frombuffer(self._core.colours(_f64(points, 3, "points")), np.uint8).reshape(-1, 3)


class Bake:
    """A bake folder opened for a simulator (``organtex bake SCENE -o DIR``
    wrote it): ``nodes`` lists the nodes with an interior, ``node(name)``
    opens one."""

    def __init__(self, path: Path_):
        self._core = _core.Bake(str(path))

    @property
    def nodes(self) -> list:
        return list(self._core.nodes)

    def node(self, name: str) -> Node:
        return Node(self._core.node(name))


class Carving:
    """A carving session over a node's tet mesh, as a simulator cuts:
    remove tets by id (SOFA's TetrahedraRemoved) or under a tool, and get
    each :class:`Step`'s new faces textured from the interior (an atlas
    grown page by page at ``texels_per_unit``) and the faces that vanished.
    A tool also removes tets that would leave an edge with more than two
    faces, so the surface stays closed."""

    def __init__(self, node: Node, texels_per_unit: float = 8.0, page_size: int = 1024,
                 background_texels: bool = False):
        self._core = _core.Carving(node._core, texels_per_unit, page_size, background_texels)

    def remove(self, tets) -> Step:
        """Remove exactly the tets ``tets`` (ids)."""
        ids = np.asarray(tets)
        if ids.ndim != 1 or (ids.size and (ids.min() < 0 or ids.max() > 0xFFFFFFFF)):
            raise OrgantexError(f"tet ids must be a 1-d array of non-negative ids, not {ids.shape}")
        return _step(self._core.remove(np.ascontiguousarray(ids, dtype="<u4").tobytes()))

    def sphere(self, centre: Sequence[float], radius: float) -> Step:
        """Remove the tets whose centroid lies within ``radius`` of ``centre``."""
        return _step(self._core.sphere([float(x) for x in centre], float(radius)))

    def capsule(self, a: Sequence[float], b: Sequence[float], radius: float) -> Step:
        """Remove the tets under a sphere swept from ``a`` to ``b``."""
        return _step(self._core.capsule([float(x) for x in a], [float(x) for x in b], float(radius)))

    def wait(self) -> np.ndarray:
        """Finish background texels: the (d, 5) rectangles written."""
        return np.frombuffer(self._core.wait(), "<u4").reshape(-1, 5)

    def page(self, page: int) -> np.ndarray:
        """Atlas page ``page`` as a (side, side, 4) uint8 RGBA array."""
        rgba, side = self._core.page(page)
        return np.frombuffer(rgba, np.uint8).reshape(side, side, 4)

    @property
    def pages(self) -> list:
        return list(self._core.pages())

    def surface(self) -> Tuple[np.ndarray, np.ndarray]:
        """The carved surface now: ``(ids (n,), vertices (n, 3))``."""
        ids, v = self._core.surface()
        return np.frombuffer(ids, "<u4"), np.frombuffer(v, "<u4").reshape(-1, 3)

    def write_glb(self, path: Path_) -> None:
        """The carved surface with its atlas as a .glb."""
        self._core.write_glb(str(path))
