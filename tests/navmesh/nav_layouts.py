"""Analytic test layouts (boxes in the canonical +Z-up frame) and their exact shortest-path lengths.

A flat layout is a rectangular room (walls outside it) with axis-aligned rectangular obstacles inside. For an
agent of radius r the free space is the room shrunk by r minus each obstacle grown by r (rounded corners), and
the exact shortest path is found on a visibility graph of points on those rounded corners (polygons that
circumscribe the arcs, so lengths are exact to about 1e-4 relative). The staircase is a straight corridor
whose shortest paths are straight lines once the stair ramp is unfolded into the floor plane.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import trimesh
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra

WALL_HEIGHT = 2.5
WALL = 0.1
SLAB = 0.1


def boxes_mesh(boxes: list[tuple[float, float, float, float, float, float]]) -> tuple[np.ndarray, np.ndarray]:
    """Triangles of closed boxes (x0, y0, z0, x1, y1, z1), concatenated."""
    verts, faces = [], []
    offset = 0
    for x0, y0, z0, x1, y1, z1 in boxes:
        b = trimesh.creation.box(bounds=[[x0, y0, z0], [x1, y1, z1]])
        verts.append(np.asarray(b.vertices))
        faces.append(np.asarray(b.faces) + offset)
        offset += len(b.vertices)
    return np.concatenate(verts), np.concatenate(faces)


@dataclass(frozen=True)
class FlatLayout:
    """A room [x0, x1] x [y0, y1] with floor top at z = 0, walls around it, and rectangular obstacles."""

    name: str
    room: tuple[float, float, float, float]
    obstacles: tuple[tuple[float, float, float, float], ...] = field(default=())

    def mesh(self) -> tuple[np.ndarray, np.ndarray]:
        """Vertices and faces: floor slab, four walls, obstacles as tall boxes."""
        x0, y0, x1, y1 = self.room
        w, h = WALL, WALL_HEIGHT
        boxes = [
            (x0 - w, y0 - w, -SLAB, x1 + w, y1 + w, 0.0),
            (x0 - w, y0 - w, 0.0, x0, y1 + w, h),
            (x1, y0 - w, 0.0, x1 + w, y1 + w, h),
            (x0, y0 - w, 0.0, x1, y0, h),
            (x0, y1, 0.0, x1, y1 + w, h),
        ]
        boxes += [(a, b, 0.0, c, d, h) for a, b, c, d in self.obstacles]
        return boxes_mesh(boxes)

    def clearance(self, p: np.ndarray) -> np.ndarray:
        """(N,) horizontal distance from each point to the nearest wall or obstacle (m)."""
        x0, y0, x1, y1 = self.room
        d = np.minimum.reduce([p[:, 0] - x0, x1 - p[:, 0], p[:, 1] - y0, y1 - p[:, 1]])
        for rect in self.obstacles:
            d = np.minimum(d, _point_rect_dist(p[:, :2], rect))
        return d

    def exact_distances(self, sources: np.ndarray, target: np.ndarray, r: float) -> np.ndarray:
        """(N,) exact shortest-path length (m) from each source to target for an agent of radius r."""
        nodes = self._corner_nodes(r)
        pts = np.vstack([nodes, target[None, :2]])
        m = len(pts)
        ii, jj = np.triu_indices(m, 1)
        ok = self._visible(pts[ii], pts[jj], r)
        w = np.linalg.norm(pts[ii] - pts[jj], axis=1)
        graph = csr_matrix(
            (np.r_[w[ok], w[ok]], (np.r_[ii[ok], jj[ok]], np.r_[jj[ok], ii[ok]])), shape=(m, m)
        )
        dist = dijkstra(graph, indices=m - 1)
        src = sources[:, :2]
        best = np.full(len(src), np.inf)
        for k in range(m):
            a = np.broadcast_to(pts[k], src.shape)
            vis = self._visible(src, a, r)
            cand = dist[k] + np.linalg.norm(src - a, axis=1)
            best = np.where(vis, np.minimum(best, cand), best)
        return best

    def _corner_nodes(self, r: float, per_quarter: int = 24) -> np.ndarray:
        step = (np.pi / 2) / per_quarter
        radius = r / np.cos(step / 2) * (1 + 1e-9)
        out = []
        for a, b, c, d in self.obstacles:
            for cx, cy, sx, sy in ((a, b, -1, -1), (c, b, 1, -1), (c, d, 1, 1), (a, d, -1, 1)):
                start = np.arctan2(sy, sx) - np.pi / 4
                for k in range(per_quarter + 1):
                    t = start + k * step
                    out.append((cx + radius * np.cos(t), cy + radius * np.sin(t)))
        if not out:
            return np.zeros((0, 2))
        p = np.array(out)
        return p[self.clearance(p) >= r - 1e-9]

    def _visible(self, a: np.ndarray, b: np.ndarray, r: float) -> np.ndarray:
        x0, y0, x1, y1 = self.room
        ok = np.ones(len(a), bool)
        for p in (a, b):
            ok &= (p[:, 0] >= x0 + r - 1e-9) & (p[:, 0] <= x1 - r + 1e-9)
            ok &= (p[:, 1] >= y0 + r - 1e-9) & (p[:, 1] <= y1 - r + 1e-9)
        for rect in self.obstacles:
            ok &= _segment_rect_dist(a, b, rect) >= r - 1e-7
        return ok


def _point_rect_dist(p: np.ndarray, rect: tuple[float, float, float, float]) -> np.ndarray:
    a, b, c, d = rect
    dx = np.maximum.reduce([a - p[:, 0], np.zeros(len(p)), p[:, 0] - c])
    dy = np.maximum.reduce([b - p[:, 1], np.zeros(len(p)), p[:, 1] - d])
    return np.hypot(dx, dy)


def _point_segment_dist(q: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    ab = b - a
    den = np.maximum((ab * ab).sum(axis=1), 1e-18)
    t = np.clip(((q - a) * ab).sum(axis=1) / den, 0.0, 1.0)
    return np.linalg.norm(a + t[:, None] * ab - q, axis=1)


def _segment_rect_dist(a: np.ndarray, b: np.ndarray, rect: tuple[float, float, float, float]) -> np.ndarray:
    """(N,) distance between segments a-b and a solid rectangle (0 when they meet)."""
    x0, y0, x1, y1 = rect
    d = np.minimum(_point_rect_dist(a, rect), _point_rect_dist(b, rect))
    for cx, cy in ((x0, y0), (x1, y0), (x1, y1), (x0, y1)):
        d = np.minimum(d, _point_segment_dist(np.broadcast_to([cx, cy], a.shape), a, b))
    # Liang-Barsky: does the segment cross the rectangle?
    t0 = np.zeros(len(a))
    t1 = np.ones(len(a))
    dirv = b - a
    hit = np.ones(len(a), bool)
    for k, lo, hi in ((0, x0, x1), (1, y0, y1)):
        dk = dirv[:, k]
        with np.errstate(divide="ignore", invalid="ignore"):
            ta = (lo - a[:, k]) / dk
            tb = (hi - a[:, k]) / dk
        par = np.abs(dk) < 1e-15
        hit &= ~par | ((a[:, k] >= lo) & (a[:, k] <= hi))
        tmin = np.where(par, -np.inf, np.minimum(ta, tb))
        tmax = np.where(par, np.inf, np.maximum(ta, tb))
        t0 = np.maximum(t0, tmin)
        t1 = np.minimum(t1, tmax)
    hit &= t0 <= t1
    return np.where(hit, 0.0, d)


FLAT_LAYOUTS = (
    FlatLayout("open_room", (0.0, 0.0, 6.0, 5.0)),
    FlatLayout("l_corridor", (0.0, 0.0, 6.0, 6.0), ((1.5, 1.5, 6.0, 6.0),)),
    FlatLayout("pillar", (0.0, 0.0, 6.0, 5.0), ((2.7, 2.2, 3.3, 2.8),)),
    FlatLayout("two_rooms_door", (0.0, 0.0, 9.0, 5.0), ((4.45, 0.0, 4.55, 2.0), (4.45, 3.0, 4.55, 5.0))),
)


@dataclass(frozen=True)
class Staircase:
    """A 2 m wide corridor along x: lower landing (z = 0) for x < 4, a straight stair of `steps` steps up to
    z = 3 over 4 m, upper landing (z = 3) for 8 <= x <= 12. Under the upper landing lies a closed room (z = 0)
    with no way in: a second storey stacked over the first, unreachable from it."""

    width: float = 2.0
    rise: float = 3.0
    run: float = 4.0
    steps: int = 20
    name: str = "staircase"

    def mesh(self) -> tuple[np.ndarray, np.ndarray]:
        """Vertices and faces: landings, steps, side walls, the closed room under the upper landing."""
        w, t, h = self.width, WALL, WALL_HEIGHT
        top = self.rise
        step_run = self.run / self.steps
        step_rise = self.rise / self.steps
        boxes = [
            (-t, -t, -SLAB, 4.0, w + t, 0.0),  # lower landing
            (8.0, -t, top - SLAB, 12.0 + t, w + t, top),  # upper landing (its slab is the room's ceiling)
            (8.0, -t, -SLAB, 12.0 + t, w + t, 0.0),  # the closed room's floor
            (-t, -t, 0.0, 0.0, w + t, h),  # end wall, lower
            (12.0, -t, 0.0, 12.0 + t, w + t, top + h),  # end wall, upper
            (8.0 - t, 0.0, 0.0, 8.0, w, top - SLAB),
        ]  # the closed room's wall under the stair top
        for i in range(self.steps):
            xa = 4.0 + i * step_run
            boxes.append((xa, 0.0, -SLAB, xa + step_run, w, (i + 1) * step_rise))
        for y0, y1 in ((-t, 0.0), (w, w + t)):  # side walls, full length and height
            boxes.append((-t, y0, 0.0, 12.0 + t, y1, top + h))
        return boxes_mesh(boxes)

    def _unfold(self, x: np.ndarray) -> np.ndarray:
        """Unfolded along-corridor coordinate: the stair is a ramp through the tread centres."""
        a = 4.0 - 0.5 * self.run / self.steps  # where the ramp through the tread centres meets z = 0
        b = a + self.run
        stretch = np.hypot(self.run, self.rise) / self.run
        return np.where(x <= a, x, np.where(x <= b, a + (x - a) * stretch, a + self.run * stretch + (x - b)))

    def exact_distances(self, sources: np.ndarray, target: np.ndarray, r: float) -> np.ndarray:
        """(N,) exact lengths for sources and target on the landings, radius r (the free space is convex)."""
        del r
        dx = self._unfold(sources[:, 0]) - self._unfold(np.array([target[0]]))[0]
        return np.hypot(dx, sources[:, 1] - target[1])

    def clearance(self, p: np.ndarray) -> np.ndarray:
        """(N,) distance to the side and end walls (m), for points in the corridor."""
        return np.minimum.reduce([p[:, 1], self.width - p[:, 1], p[:, 0], 12.0 - p[:, 0]])


def accuracy_report(
    offsets=((0.0, 0.0), (0.013, 0.031), (0.037, 0.004), (0.025, 0.025)), seed: int = 1
) -> list[dict]:
    """Relative error of navmesh geodesics against exact lengths, per layout and grid offset (paths >= 2 m).

    Run `python tests/navmesh/nav_layouts.py` to print it (the figures of docs/navmesh.md).
    """
    from main_bench.navmesh import NavMesh, NavMeshSettings

    s = NavMeshSettings()
    rows = []
    for layout in (*FLAT_LAYOUTS, Staircase()):
        for off in offsets:
            shift = np.array([off[0], off[1], 0.0])
            v, f = layout.mesh()
            nm = NavMesh.from_triangles(v + shift, f, s)
            island = int(nm.island_of(np.array([[0.6, 0.6, 0.0]]) + shift)[0])
            pts = nm.sample(1000, np.random.default_rng(seed), island=island) - shift
            ok = layout.clearance(pts) >= s.agent_radius + 0.03
            if isinstance(layout, Staircase):
                ok &= (pts[:, 0] < 3.8) | (pts[:, 0] > 8.1)
            pts = pts[ok]
            rel, below = [], []
            for t in pts[:8]:
                got = nm.distance_field(t + shift).distance(pts[8:] + shift)
                exact = layout.exact_distances(pts[8:], t, s.agent_radius)
                long = exact >= 2.0
                rel.append((got[long] - exact[long]) / exact[long])
                below.append(got - np.linalg.norm(pts[8:] - t, axis=1))
            r = np.concatenate(rel)
            rows.append(
                {
                    "layout": layout.name,
                    "offset": off,
                    "pairs": len(r),
                    "max_abs": float(np.abs(r).max()),
                    "mean_abs": float(np.abs(r).mean()),
                    "most_below_straight_m": float(-np.concatenate(below).min()),
                }
            )
    return rows


if __name__ == "__main__":
    for row in accuracy_report():
        print(
            f"{row['layout']:15s} offset {row['offset']}: {row['pairs']:5d} pairs, "
            f"max {100 * row['max_abs']:.2f}%, mean {100 * row['mean_abs']:.3f}%, "
            f"below straight line by at most {row['most_below_straight_m']:.4f} m"
        )
