"""The walkable surface as a triangle mesh (OBJ/GLB) and as a top-down picture per floor."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import NavMeshError
from ..io import atomic_path
from .navmesh import NavMesh

EXPORT_FORMATS = ("obj", "glb")


def surface_mesh(nm: NavMesh) -> tuple[np.ndarray, np.ndarray]:
    """(V, 3) vertices and (F, 3) faces: one horizontal square (two triangles) per navigable cell at its
    surface height, canonical frame (+Z up, metres)."""
    x0, y0, cs, _, _ = nm.grid_shape()
    ix, iy = nm.cell_indices()
    z = nm.cells()[:, 2]
    corners = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=np.float64)
    vx = x0 + (ix[:, None] + corners[None, :, 0]) * cs
    vy = y0 + (iy[:, None] + corners[None, :, 1]) * cs
    verts = np.stack([vx, vy, np.repeat(z[:, None], 4, axis=1)], axis=2).reshape(-1, 3)
    base = 4 * np.arange(len(z))[:, None]
    faces = np.concatenate([base + [0, 1, 2], base + [0, 2, 3]], axis=1).reshape(-1, 3)
    return verts, faces


def export_surface(nm: NavMesh, out: str | Path, fmt: str, up: str = "z") -> dict[str, float | int]:
    """Write the walkable surface to `out` as OBJ or GLB, atomically. up="y" rotates to glTF's +Y-up frame.

    Returns counts: vertices, triangles, area (m^2).
    """
    import trimesh

    if fmt not in EXPORT_FORMATS:
        raise NavMeshError(f"export format must be one of {', '.join(EXPORT_FORMATS)}, got {fmt!r}")
    verts, faces = surface_mesh(nm)
    mesh = trimesh.Trimesh(verts, faces, process=False)
    mesh.merge_vertices()
    if up == "y":
        mesh.apply_transform(np.array([[1.0, 0, 0, 0], [0, 0, 1, 0], [0, -1, 0, 0], [0, 0, 0, 1]]))
    data = mesh.export(file_type=fmt)
    with atomic_path(out, suffix=f".{fmt}") as tmp:
        tmp.write_bytes(data if isinstance(data, bytes) else data.encode())
    return {
        "vertices": int(len(mesh.vertices)),
        "triangles": int(len(mesh.faces)),
        "area": round(float(nm.navigable_area), 4),
    }


def render_map(nm: NavMesh, out: str | Path, path: np.ndarray | None = None, dpi: int = 100) -> int:
    """Draw a top-down PNG, one panel per floor, cells coloured by island, optional (K, 3) path in red.

    Cells on no floor (below the lowest) join the lowest floor. Returns the number of panels.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import ListedColormap

    x0, y0, cs, nx, ny = nm.grid_shape()
    ix, iy = nm.cell_indices()
    floors = np.maximum(nm.cell_floor(), 0)
    islands = nm.cell_island()
    z = nm.cells()[:, 2]
    panels = max(len(nm.floors), 1)
    fig, axes = plt.subplots(1, panels, figsize=(6 * panels, 6 * ny / max(nx, 1) + 0.8), squeeze=False)
    colours = plt.get_cmap("tab20")(np.arange(20))
    cmap = ListedColormap(colours)
    extent = (x0, x0 + nx * cs, y0, y0 + ny * cs)
    path_floor = nm.floor_of(path) if path is not None and len(path) else None
    for k in range(panels):
        ax = axes[0, k]
        img = np.full((ny, nx), np.nan)
        sel = np.flatnonzero(floors == k)
        order = sel[np.argsort(z[sel])]  # the highest layer of a column on this floor is drawn
        img[iy[order], ix[order]] = islands[order] % 20
        ax.imshow(img, origin="lower", extent=extent, cmap=cmap, vmin=0, vmax=20, interpolation="nearest")
        title = f"floor {k}" + (f" (z = {nm.floors[k].z:.2f} m)" if nm.floors else "")
        ax.set_title(title)
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        if path is not None and len(path):
            on = np.maximum(path_floor, 0) == k
            if on.any():
                ax.plot(path[on, 0], path[on, 1], "r-", lw=2)
                if on[0]:
                    ax.plot(path[0, 0], path[0, 1], "go")
                if on[-1]:
                    ax.plot(path[-1, 0], path[-1, 1], "rx")
    fig.suptitle(f"{nm.scene_id}: {len(nm.islands)} islands, {nm.navigable_area:.1f} m^2 navigable")
    fig.tight_layout()
    with atomic_path(out, suffix=".png") as tmp:
        fig.savefig(tmp, dpi=dpi, format="png")
    plt.close(fig)
    return panels
