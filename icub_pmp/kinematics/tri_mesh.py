"""TriMesh: a triangle mesh read from a binary STL, with vertex-clustering simplification.

The icub-models meshes total about 273k faces; offscreen rendering on the CPU (llvmpipe) is
geometry-bound, so the simulator renders a simplified copy. Simplification is uniform vertex
clustering (Rossignac & Borrel 1993): vertices are snapped to a cubic grid of side ``cell``
[m], each cell's vertices merge into their mean, and triangles that collapse are dropped.
It keeps the silhouette to about ``cell`` and is a few lines of numpy.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from icub_pmp.errors import ModelError

__all__ = ["TriMesh"]

_STL_DTYPE = np.dtype(
    [("normal", "<f4", 3), ("v", "<f4", (3, 3)), ("attr", "<u2")]
)


@dataclasses.dataclass(frozen=True)
class TriMesh:
    """Vertices (n, 3) [m] and triangles (m, 3) (vertex indices)."""

    vertices: np.ndarray
    faces: np.ndarray

    @classmethod
    def from_stl(cls, path: str | Path, scale: tuple[float, float, float] = (1.0, 1.0, 1.0)
                 ) -> "TriMesh":
        """Read a binary STL, scale its vertices (URDF ``scale``) and merge duplicates."""
        path = Path(path)
        try:
            raw = path.read_bytes()
        except OSError as exc:
            raise ModelError(f"cannot read mesh {path}: {exc}") from exc
        if len(raw) < 84:
            raise ModelError(f"{path}: not a binary STL (too short)")
        n = int(np.frombuffer(raw, dtype="<u4", count=1, offset=80)[0])
        if len(raw) != 84 + 50 * n:
            raise ModelError(f"{path}: not a binary STL ({n} faces but {len(raw)} bytes)")
        tri = np.frombuffer(raw, dtype=_STL_DTYPE, count=n, offset=84)["v"].astype(float)
        verts = tri.reshape(-1, 3) * np.asarray(scale, dtype=float)
        uniq, inv = np.unique(verts, axis=0, return_inverse=True)
        return cls(uniq, inv.reshape(-1, 3).astype(np.int32))

    def simplified(self, cell: float) -> "TriMesh":
        """Vertex-clustering simplification on a grid of side ``cell`` [m] (see module doc)."""
        if cell <= 0:
            return self
        keys = np.floor(self.vertices / cell).astype(np.int64)
        _, inv, counts = np.unique(keys, axis=0, return_inverse=True, return_counts=True)
        inv = inv.reshape(-1)
        sums = np.zeros((counts.size, 3))
        np.add.at(sums, inv, self.vertices)
        verts = sums / counts[:, None]
        faces = inv[self.faces]
        ok = (faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (
            faces[:, 0] != faces[:, 2])
        faces = faces[ok]
        # drop duplicate triangles (same vertex set), keep the first orientation
        if faces.size:
            _, first = np.unique(np.sort(faces, axis=1), axis=0, return_index=True)
            faces = faces[np.sort(first)]
        used, remap = np.unique(faces, return_inverse=True)
        return TriMesh(verts[used], remap.reshape(-1, 3).astype(np.int32))

    def transformed(self, T: np.ndarray) -> "TriMesh":
        """The mesh with vertices mapped by the homogeneous transform ``T`` (4, 4)."""
        return TriMesh(self.vertices @ T[:3, :3].T + T[:3, 3], self.faces)

    @property
    def n_faces(self) -> int:
        """Number of triangles."""
        return int(self.faces.shape[0])
