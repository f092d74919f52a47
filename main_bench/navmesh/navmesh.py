"""`NavMesh`: the walkable surface of a scene for one agent size, with islands, floors and geodesic queries."""

from __future__ import annotations

import hashlib
import io
import json
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import NavMeshError
from ..io import atomic_path
from .build import ALGORITHM_VERSION, Grid, build_grid, column_starts, find_floors
from .cells import NavCells
from .field import SNAP_RADIUS, DistanceField, FieldSpace
from .settings import NavMeshSettings

#: Version of the navmesh file layout (2: links stored relative to their node, 0 for none: 25x smaller files;
#: version 1 files, absolute links, are still read).
SCHEMA_VERSION = 2


@dataclass(frozen=True)
class Island:
    """A connected walkable region. area in m^2 (horizontal projection); bounds in m, canonical frame."""

    index: int
    area: float
    floor: int
    bounds_min: tuple[float, float, float]
    bounds_max: tuple[float, float, float]
    cell_count: int

    def to_json(self) -> dict[str, Any]:
        """JSON-ready dict."""
        return {"index": self.index, "area": round(self.area, 4), "floor": self.floor,
                "bounds_min": [round(v, 4) for v in self.bounds_min],
                "bounds_max": [round(v, 4) for v in self.bounds_max], "cell_count": self.cell_count}


@dataclass(frozen=True)
class Floor:
    """A storey: index (0 = lowest), z = height of its floor surface (m), area of flat floor at that height (m^2)."""

    index: int
    z: float
    area: float

    def to_json(self) -> dict[str, Any]:
        """JSON-ready dict."""
        return {"index": self.index, "z": round(self.z, 4), "area": round(self.area, 4)}


def geometry_hash(vertices: np.ndarray, faces: np.ndarray) -> str:
    """SHA-256 of the canonical-frame triangles (so up-axis, scale and moves change it)."""
    h = hashlib.sha256(np.ascontiguousarray(vertices, dtype=np.float64).tobytes())
    h.update(np.ascontiguousarray(faces, dtype=np.int64).tobytes())
    return h.hexdigest()


def build_key(geom_hash: str, settings: NavMeshSettings, algorithm: int = ALGORITHM_VERSION) -> str:
    """Cache key: geometry, settings and algorithm version (this toolkit's unless given)."""
    doc = {"geometry": geom_hash, "settings": settings.to_json(), "algorithm": algorithm}
    return hashlib.sha256(json.dumps(doc, sort_keys=True).encode()).hexdigest()


def _npz_bytes(**arrays: np.ndarray) -> bytes:
    """A compressed NumPy archive of `arrays` whose bytes depend only on the arrays (no zip timestamps), so a
    navmesh file's SHA-256 identifies its content."""
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        for name, arr in arrays.items():
            one = io.BytesIO()
            np.lib.format.write_array(one, np.ascontiguousarray(arr), allow_pickle=False)
            info = zipfile.ZipInfo(f"{name}.npy", date_time=(1980, 1, 1, 0, 0, 0))
            info.compress_type = zipfile.ZIP_DEFLATED
            zf.writestr(info, one.getvalue())
    return buf.getvalue()


def _relative_links(nbr: np.ndarray) -> np.ndarray:
    """(N, 8) links as offsets from their own node (0: no link; a node never links to itself), int32."""
    own = np.arange(len(nbr), dtype=np.int64)[:, None]
    return np.where(nbr >= 0, nbr - own, 0).astype(np.int32)


def _absolute_links(rel: np.ndarray) -> np.ndarray:
    """Inverse of `_relative_links`: (N, 8) int64 node indices, -1 for no link."""
    rel = np.asarray(rel, dtype=np.int64)
    own = np.arange(len(rel), dtype=np.int64)[:, None]
    return np.where(rel != 0, rel + own, -1)


class NavMesh(NavCells):
    """Walkable cells of a scene (`NavCells`: a 2.5D grid of cell_size squares, several layers per column, and
    the point queries on them) with their floors, islands and geodesic distances, built from a scene or read
    from a file.
    """

    def __init__(self, grid: Grid, settings: NavMeshSettings, scene_id: str, scene_hash: str,
                 geom_hash: str, floors: list[tuple[float, float]] | None = None) -> None:
        super().__init__(grid, settings)
        self.scene_id = scene_id
        self.scene_hash = scene_hash
        self.geometry_hash = geom_hash
        #: The build algorithm's version (a loaded file's own; see `build_key`).
        self.algorithm_version = ALGORITHM_VERSION
        if floors is None:
            floors = find_floors(grid.z, grid.cell_size * grid.cell_size, settings)
        self.floors: tuple[Floor, ...] = tuple(Floor(i, z, a) for i, (z, a) in enumerate(floors))
        self._floor_z = np.array([f.z for f in self.floors])
        self.islands: tuple[Island, ...] = self._make_islands()
        self._space: FieldSpace | None = None

    # ----------------------------------------------------------------- building and files
    @classmethod
    def build(cls, scene: Any, settings: NavMeshSettings = NavMeshSettings()) -> NavMesh:
        """Build the navmesh of a `Scene` (canonical frame). Raises NavMeshError naming the scene's file and the
        settings to change."""
        try:
            grid = build_grid(scene.vertices, scene.faces, settings)
        except NavMeshError as exc:
            if exc.path is not None or getattr(scene, "path", None) is None:
                raise
            raise NavMeshError(exc.problem, path=scene.path) from None
        return cls(grid, settings, str(scene.scene_id), str(scene.content_hash),
                   geometry_hash(scene.vertices, scene.faces))

    @classmethod
    def from_triangles(cls, vertices: np.ndarray, faces: np.ndarray,
                       settings: NavMeshSettings = NavMeshSettings(), scene_id: str = "mesh") -> NavMesh:
        """Build from a triangle soup already in the canonical frame (+Z up, metres): (V, 3) and (F, 3)."""
        vertices = np.asarray(vertices, dtype=np.float64)
        faces = np.asarray(faces, dtype=np.int64)
        if vertices.ndim != 2 or vertices.shape[1] != 3 or faces.ndim != 2 or faces.shape[1] != 3 \
                or not len(faces):
            raise NavMeshError(f"need (V, 3) vertices and a non-empty (F, 3) faces array, got "
                               f"{vertices.shape} and {faces.shape}")
        gh = geometry_hash(vertices, faces)
        return cls(build_grid(vertices, faces, settings), settings, scene_id, gh, gh)

    @classmethod
    def flat_square(cls, n: int = 3, settings: NavMeshSettings = NavMeshSettings()) -> NavMesh:
        """An n x n-cell navmesh on one flat floor (z = 0, corner at the origin), made in memory with the array
        types of a loaded one: it loads numba's distance-field kernels without reading a scene or a file."""
        from ._raster import DX, DY

        iy, ix = np.divmod(np.arange(n * n, dtype=np.int64), n)
        nbr = np.full((n * n, 8), -1, np.int64)
        for d in range(8):
            jx, jy = ix + DX[d], iy + DY[d]
            inside = (jx >= 0) & (jx < n) & (jy >= 0) & (jy < n)
            nbr[inside, d] = (jy * n + jx)[inside]
        z = np.zeros(n * n)
        cs = float(settings.cell_size)
        grid = Grid(x0=0.0, y0=0.0, cell_size=cs, nx=n, ny=n, ix=ix, iy=iy, z=z, zs=z.copy(), nbr=nbr,
                    island=np.zeros(n * n, np.int64), col_start=column_starts(ix, iy, n, n), ox=z.copy(), oy=z.copy())
        return cls(grid, settings, f"flat-square-{n}", "", "", [(0.0, n * n * cs * cs)])

    @classmethod
    def build_cached(cls, scene: Any, settings: NavMeshSettings, cache_dir: str | Path) -> NavMesh:
        """Like `build`, reusing `cache_dir/<scene_id>-<key>.navmesh` keyed by geometry, settings, algorithm."""
        key = cls.key_of(scene, settings)
        path = Path(cache_dir) / f"{scene.scene_id}-{key[:20]}.navmesh"
        if path.is_file():
            try:
                nm = cls.load(path)
                if nm.build_key == key:
                    return nm
            except NavMeshError:
                pass
        nm = cls.build(scene, settings)
        nm.save(path)
        return nm

    @staticmethod
    def key_of(scene: Any, settings: NavMeshSettings) -> str:
        """The cache key a navmesh of `scene` built with `settings` gets (compare with `build_key`)."""
        return build_key(geometry_hash(scene.vertices, scene.faces), settings)

    @property
    def build_key(self) -> str:
        """The cache key this navmesh was built under (geometry hash, settings, and the algorithm version that
        built it: a file from an older algorithm never matches a fresh key, so it is rebuilt)."""
        return build_key(self.geometry_hash, self.settings, self.algorithm_version)

    def save(self, path: str | Path) -> None:
        """Write the navmesh (compressed NumPy archive with a JSON header) atomically."""
        g = self._grid
        meta = {
            "schema_version": SCHEMA_VERSION, "format": "main-bench-navmesh", "algorithm": self.algorithm_version,
            "settings": self.settings.to_json(), "scene_id": self.scene_id, "scene_hash": self.scene_hash,
            "geometry_hash": self.geometry_hash, "grid": {"x0": g.x0, "y0": g.y0, "cell_size": g.cell_size,
                                                          "nx": g.nx, "ny": g.ny},
            "floors": [[f.z, f.area] for f in self.floors],
        }
        data = _npz_bytes(meta=np.frombuffer(json.dumps(meta, sort_keys=True).encode(), np.uint8),
                          ix=g.ix.astype(np.int32), iy=g.iy.astype(np.int32), z=g.z, zs=g.zs,
                          nbr_rel=_relative_links(g.nbr), island=g.island.astype(np.int32),
                          ox=self._ax - self._px, oy=self._ay - self._py)
        with atomic_path(path) as tmp:
            tmp.write_bytes(data)

    @classmethod
    def load(cls, path: str | Path) -> NavMesh:
        """Read a file written by `save`; a missing, foreign or newer file raises NavMeshError."""
        path = Path(path)
        if not path.is_file():
            raise NavMeshError("navmesh file not found; build it with `main-bench navmesh build`", path=path)
        try:
            with np.load(path, allow_pickle=False) as z:
                arrays = {k: z[k] for k in z.files}
            meta = json.loads(arrays["meta"].tobytes().decode())
        except Exception as exc:
            raise NavMeshError(f"not a main-bench navmesh file ({type(exc).__name__}); "
                               "rebuild it with `main-bench navmesh build`", path=path) from None
        if not isinstance(meta, dict) or meta.get("format") != "main-bench-navmesh":
            raise NavMeshError("not a main-bench navmesh file; rebuild it with `main-bench navmesh build`", path=path)
        version = meta.get("schema_version")
        if not isinstance(version, int) or version > SCHEMA_VERSION:
            raise NavMeshError(f"navmesh schema_version {version!r}; this main-bench reads up to {SCHEMA_VERSION}; "
                               "upgrade main-bench or rebuild the navmesh", path=path)
        try:
            gm = meta["grid"]
            ix = arrays["ix"].astype(np.int64)
            iy = arrays["iy"].astype(np.int64)
            nx, ny = int(gm["nx"]), int(gm["ny"])
            grid = Grid(x0=float(gm["x0"]), y0=float(gm["y0"]), cell_size=float(gm["cell_size"]), nx=nx, ny=ny,
                        ix=ix, iy=iy, z=arrays["z"].astype(np.float64), zs=arrays["zs"].astype(np.float64),
                        nbr=_absolute_links(arrays["nbr_rel"]) if "nbr_rel" in arrays
                        else arrays["nbr"].astype(np.int64), island=arrays["island"].astype(np.int64),
                        col_start=column_starts(ix, iy, nx, ny), ox=arrays.get("ox"), oy=arrays.get("oy"))
            settings = NavMeshSettings.from_json(meta["settings"])
            nm = cls(grid, settings, str(meta["scene_id"]), str(meta["scene_hash"]), str(meta["geometry_hash"]),
                     [(float(a), float(b)) for a, b in meta["floors"]])
        except NavMeshError:
            raise
        except Exception as exc:
            raise NavMeshError(f"corrupt navmesh file ({type(exc).__name__}: {exc}); rebuild it", path=path) from None
        nm.algorithm_version = int(meta.get("algorithm", 0))
        return nm

    # ----------------------------------------------------------------- summary
    def _make_islands(self) -> tuple[Island, ...]:
        g = self._grid
        if len(g.z) == 0:
            return ()
        k = int(g.island.max()) + 1
        counts = np.bincount(g.island, minlength=k)
        out = []
        cs = g.cell_size
        for i in range(k):
            sel = g.island == i
            xs, ys, zz = self._px[sel], self._py[sel], g.z[sel]
            floor = int(self.floor_of(np.array([[0.0, 0.0, float(np.median(zz))]]))[0])
            out.append(Island(i, float(counts[i] * cs * cs), floor,
                              (float(xs.min() - cs / 2), float(ys.min() - cs / 2), float(zz.min())),
                              (float(xs.max() + cs / 2), float(ys.max() + cs / 2), float(zz.max())),
                              int(counts[i])))
        return tuple(out)

    @property
    def navigable_area(self) -> float:
        """Total walkable area, m^2 (horizontal projection)."""
        return float(len(self._grid.z) * self._grid.cell_size ** 2)

    def info(self) -> dict[str, Any]:
        """JSON-ready summary: settings, scene, area, floors, islands."""
        return {"scene_id": self.scene_id, "scene_hash": self.scene_hash, "settings": self.settings.to_json(),
                "navigable_area": round(self.navigable_area, 4), "cell_count": int(len(self._grid.z)),
                "floors": [f.to_json() for f in self.floors], "islands": [i.to_json() for i in self.islands]}

    # ----------------------------------------------------------------- grid accessors
    def cells(self, index: np.ndarray | None = None) -> np.ndarray:
        """(C, 3) centres of navigable cells at surface height, m; with `index`, only those cells' rows (cheaper
        than indexing the whole array on a large navmesh)."""
        if index is None:
            return np.stack([self._px, self._py, self._grid.z], axis=1)
        index = np.asarray(index, dtype=np.int64)
        return np.stack([self._px[index], self._py[index], self._grid.z[index]], axis=1)

    def cell_island(self) -> np.ndarray:
        """(C,) island index of each cell (same order as `cells`)."""
        return self._grid.island.copy()

    def cell_floor(self) -> np.ndarray:
        """(C,) floor index of each cell (same order as `cells`)."""
        return self.floor_of(self.cells())

    def cell_links(self) -> np.ndarray:
        """(C, 8) linked cell per direction E, N, W, S, NE, NW, SW, SE, or -1 (for graph exports)."""
        return self._grid.nbr.copy()

    def grid_shape(self) -> tuple[float, float, float, int, int]:
        """(x0, y0, cell_size, nx, ny): column (i, j) covers [x0 + i*cs, x0 + (i+1)*cs) x [y0 + j*cs, ...)."""
        g = self._grid
        return g.x0, g.y0, g.cell_size, g.nx, g.ny

    def cell_indices(self) -> tuple[np.ndarray, np.ndarray]:
        """(C,) column indices i, j of each cell."""
        return self._grid.ix.copy(), self._grid.iy.copy()

    # ----------------------------------------------------------------- point queries
    def island_of(self, points: np.ndarray) -> np.ndarray:
        """(N,) island index of each point, -1 where off the navmesh."""
        nodes = self._locate(self._points(points))
        return np.where(nodes >= 0, self._grid.island[np.maximum(nodes, 0)], -1)

    def floor_of(self, points: np.ndarray) -> np.ndarray:
        """(N,) floor index: the highest floor at most max_climb + 5 cm above the point; -1 below every floor."""
        pts = self._points(points)
        if len(self._floor_z) == 0:
            return np.full(len(pts), -1, np.int64)
        idx = np.searchsorted(self._floor_z, pts[:, 2] + self._below, side="right") - 1
        return idx.astype(np.int64)

    def sample(self, n: int, rng: np.random.Generator, island: int | None = None) -> np.ndarray:
        """(n, 3) points uniform over the navigable area (of one island if given), at surface height."""
        g = self._grid
        if island is None:
            ids = np.arange(len(g.z))
        else:
            self._check_island(island)
            ids = np.flatnonzero(g.island == island)
        pick = ids[rng.integers(0, len(ids), size=int(n))]
        off = rng.random((int(n), 2))
        cs = g.cell_size
        return np.stack([g.x0 + (g.ix[pick] + off[:, 0]) * cs, g.y0 + (g.iy[pick] + off[:, 1]) * cs, g.z[pick]],
                        axis=1)

    # ----------------------------------------------------------------- geodesics
    def _field_space(self) -> FieldSpace:
        """The cells as the distance fields number them (`FieldSpace`), made once: tile by tile, links as int32
        (the propagation runs about a tenth faster on half the bytes, and a tenth faster again by tiles)."""
        if self._space is None:
            self._space = FieldSpace.of(self)
        return self._space

    def distance_field(self, targets: np.ndarray) -> DistanceField:
        """Distances to the nearest of targets (3,) or (M, 3), computed once for any number of look-ups.

        Targets up to 0.5 m off the navmesh are snapped to the nearest navigable cell on their level.
        """
        return DistanceField(self, self._field_space(), self._points(targets))

    def geodesic_distance(self, a: np.ndarray, b: np.ndarray) -> float | np.ndarray:
        """Geodesic distance (m) from a to b: (3,) and (3,) -> float; (N, 3) and (3,) -> (N,); (N, 3) and
        (N, 3) -> (N,) row by row. inf when unreachable."""
        a_arr = np.asarray(a, dtype=np.float64)
        b_arr = np.asarray(b, dtype=np.float64)
        if b_arr.ndim == 1:
            return self.distance_field(b_arr).distance(a_arr)
        a2 = self._points(a_arr)
        b2 = self._points(b_arr)
        if len(a2) != len(b2):
            raise ValueError(f"a and b must have the same number of rows, got {len(a2)} and {len(b2)}")
        return np.array([self.distance_field(bb).distance(aa) for aa, bb in zip(a2, b2, strict=True)])

    def shortest_path(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """(K, 3) polyline from a to b on the navigable surface; (0, 3) when unreachable."""
        return self.distance_field(np.asarray(b, dtype=np.float64)).path(np.asarray(a, dtype=np.float64))


__all__ = ["SNAP_RADIUS", "SCHEMA_VERSION", "Floor", "Island", "NavMesh"]
