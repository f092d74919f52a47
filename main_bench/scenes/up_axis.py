"""Which axis of a scene file is up: the rule that decides it and the evidence for each candidate frame.

In: the file's vertices and faces (file units), its format and metres per unit for each candidate. Out: "y" or
"z", the rule that decided (`UpRule`) and a sentence saying on what evidence, or a `SceneError` naming the file.

The rules, in order: a given `--up`; an objects sidecar's `up_axis` (`loader`); a format's own convention (glTF
is +Y up by its specification), overruled only where the +Z reading is a plausible indoor scene and the +Y
reading is none or clearly less enclosed by its walls (a Z-up file exported against the specification); for
formats without a convention (OBJ, PLY), the geometric test below.

A candidate frame (file +Y or +Z up) is judged as an indoor scene would be:

- its floor is the lowest large horizontal surface (at least `FLOOR_MIN_M2` within one `LEVEL_BAND_M` band, and
  `FLOOR_SHARE` of the largest such band: a pit or a lift shaft's bottom below the ground floor is none) with
  room to stand on it (`STANDABLE_MIN` of its points clear of any surface by `CLEARANCE_M`);
- the walls (vertical surfaces) start there: at most `WALLS_BELOW_MAX` of their area lies more than
  `FLOOR_TOL_M` below the floor without standing on a horizontal surface of its own (a shaft, a basement);
- where there are walls (vertical area rising from the floor at least `WALLED_RATIO` times the floor's area),
  they enclose it: of horizontal rays cast `RAY_HEIGHT_M` above sample points of the floor, at least
  `ENCLOSED_MIN` hit a surface. Exported scenes often lack a ceiling, never most of their walls: turning a
  ceiling-less room on its side leaves one side open, a room of walls only two sides.

A frame that fails is never accepted. When both pass, a frame clearly more enclosed than the other wins (unless
its floor is much the smaller), then one whose floor is `FLOOR_WIN_RATIO` times the other's, then one with
`FLAT_MARGIN` times the other's flat area; otherwise the evidence is ambiguous and `--up` must be given.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np

from ..errors import SceneError

Axis = Literal["y", "z"]
#: A face is horizontal when its normal is within ~18 deg of up, vertical within ~12 deg of horizontal.
HORIZONTAL_COS, VERTICAL_COS = 0.95, 0.2
#: Height band (m) of one floor level; least floor area (m^2) in one band.
LEVEL_BAND_M, FLOOR_MIN_M2 = 0.15, 1.0
#: A floor has room to stand: this share of its sample points is at least `CLEARANCE_M` from any surface at
#: `RAY_HEIGHT_M` above it (the bottom faces of walls are no floor). Only levels holding `FLOOR_SHARE` of the
#: largest level's area are floors (a pit, a lift shaft's bottom or a landing is not the building's floor).
STANDABLE_MIN, CLEARANCE_M, FLOOR_SHARE = 0.25, 0.2, 0.25
#: Walls may start this far (m) below the floor (slab thickness, skirting), and this share of wall area lower.
FLOOR_TOL_M, WALLS_BELOW_MAX = 0.3, 0.05
#: A frame has walls when the vertical area within `STOREY_M` above its floor is this many times the floor's.
WALLED_RATIO, STOREY_M = 0.3, 2.0
#: Rays are cast this high above the floor (m), in `RAY_DIRECTIONS` directions from `RAY_POINTS` floor points.
RAY_HEIGHT_M, RAY_DIRECTIONS, RAY_POINTS = 1.0, 16, 48
#: Least share of rays that must hit a wall in a walled frame; a frame this much more enclosed wins outright
#: unless its floor is less than `FLOOR_RATIO_MIN` times the other frame's (a small enclosed patch).
ENCLOSED_MIN, ENCLOSED_MARGIN, FLOOR_RATIO_MIN = 0.6, 0.15, 0.5
#: A frame whose floor is this many times the other's wins when the walls do not decide: a building's floors
#: span its footprint, its outer walls its height (a building 1.5 times as deep as it is tall).
FLOOR_WIN_RATIO = 1.5
#: Flat-area ratio needed for the flat-area comparison to count as clear evidence.
FLAT_MARGIN = 1.5


@dataclass(frozen=True)
class FrameEvidence:
    """What the geometry says about one candidate up axis (metres, in that frame)."""

    axis: Axis
    flat_area: float
    floor_z: float | None
    floor_area: float
    walls_below: float
    walled: bool
    enclosure: float | None
    problem: str

    @property
    def ok(self) -> bool:
        """Whether the frame is a plausible indoor scene."""
        return not self.problem

    def describe(self) -> str:
        """One clause: floor, walls and enclosure of this frame."""
        if self.floor_z is None:
            return f"+{self.axis.upper()}: {self.problem}"
        text = f"+{self.axis.upper()}: floor {self.floor_area:.1f} m^2 at {self.floor_z:.2f} m"
        if self.enclosure is not None:
            text += f", walls enclose {100 * self.enclosure:.0f}% of it"
        elif not self.walled:
            text += ", no walls around it"
        return text + (f" ({self.problem})" if self.problem else "")


#: What decided a scene's up axis (`Scene.up_rule`, `scenes info --json` "up_rule").
UpRule = Literal["given", "sidecar", "gltf-convention", "geometry"]
#: Formats whose specification fixes the up axis: glTF is +Y up.
GLTF_FORMATS = ("glb", "gltf")


def decide_up(vertices: np.ndarray, faces: np.ndarray, up: str, fmt: str, path: Path,
              metres: Callable[[Axis], float]) -> tuple[Axis, UpRule, str]:
    """The file's up axis, the rule that decided it and a sentence saying why.

    `up` y or z is checked for a floor and kept. With auto, a glTF file (`fmt` glb or gltf) is +Y up by its
    specification; the geometry overrules that only where the +Z reading is a plausible indoor scene and the +Y
    one is none or clearly less enclosed (module doc). Other formats (OBJ, PLY) say nothing: the geometry
    decides. `metres(axis)`: metres per file unit when `axis` is up. Raises `SceneError` naming the
    file for a scene with no floor in the given frame, with no plausible frame, or (geometry) with ambiguous
    evidence.
    """
    tri = vertices[faces]
    cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    area2 = np.linalg.norm(cross, axis=1)
    keep = area2 > 0
    tri, normals, area = tri[keep], cross[keep] / area2[keep, None], area2[keep] / 2

    def floor_as_given(axis: Axis) -> FrameEvidence:
        """The frame's lowest large horizontal band, as a given --up takes it (no room to stand asked)."""
        return frame_evidence(tri, normals, area, axis, metres(axis), standing=False)

    def has_floor(ev: FrameEvidence) -> bool:
        return ev.floor_z is not None and ev.walls_below <= WALLS_BELOW_MAX

    if up in ("y", "z"):
        ev = floor_as_given(up)  # type: ignore[arg-type]
        if not has_floor(ev):
            raise SceneError(f"no floor with --up {up}: {ev.describe()}; check the file or its --up", path=path)
        return up, "given", "given"  # type: ignore[return-value]
    name = fmt.upper()
    y = frame_evidence(tri, normals, area, "y", metres("y"))
    z = frame_evidence(tri, normals, area, "z", metres("z"))
    both = f"{y.describe()}; {z.describe()}"
    if fmt in GLTF_FORMATS:
        if z.ok and (not y.ok or _better_enclosed(z, y)):
            return "z", "geometry", (f"geometric test on {name}: read +Y up as glTF specifies, the file is no "
                                     f"indoor scene ({both})")
        if y.ok or has_floor(floor_as_given("y")):
            return "y", "gltf-convention", "glTF convention: +Y up"
    if not y.ok and not z.ok:
        raise SceneError(f"no floor in either frame ({both}); a scene needs a floor under its walls, "
                         "or give --up y|z if the file is right", path=path)
    axis, why = _by_geometry(y, z, both, path)
    return axis, "geometry", f"geometric test on {name}: {why}"


def _by_geometry(y: FrameEvidence, z: FrameEvidence, both: str, path: Path) -> tuple[Axis, str]:
    """The up axis the evidence of both frames points to (at least one is plausible), and why."""
    if y.ok != z.ok:
        pick = y if y.ok else z
        return pick.axis, f"{pick.describe()}; the other frame fails ({(z if y.ok else y).describe()})"
    for pick, other in ((y, z), (z, y)):
        if _better_enclosed(pick, other):
            return pick.axis, f"walls enclose the floor best with +{pick.axis.upper()} up ({both})"
    big, small = (y, z) if y.floor_area >= z.floor_area else (z, y)
    if small.floor_area * FLOOR_WIN_RATIO <= big.floor_area:
        return big.axis, f"the floor is largest with +{big.axis.upper()} up ({both})"
    if y.flat_area > FLAT_MARGIN * z.flat_area or z.flat_area > FLAT_MARGIN * y.flat_area:
        axis: Axis = "y" if y.flat_area > z.flat_area else "z"
        return axis, f"most flat surface area faces along {axis.upper()} ({both})"
    raise SceneError(f"cannot tell the up axis ({both}; flat area {y.flat_area:.1f} along Y, {z.flat_area:.1f} "
                     "along Z); give --up y or --up z", path=path)


def _better_enclosed(a: FrameEvidence, b: FrameEvidence) -> bool:
    """Whether walls enclose frame `a`'s floor clearly more than `b`'s, on a floor not much the smaller."""
    return (a.enclosure is not None and b.enclosure is not None and a.enclosure - b.enclosure >= ENCLOSED_MARGIN
            and a.floor_area >= FLOOR_RATIO_MIN * b.floor_area)


def frame_evidence(tri: np.ndarray, normals: np.ndarray, area: np.ndarray, axis: Axis, metres: float,
                   standing: bool = True) -> FrameEvidence:
    """Floor, walls and enclosure of the frame where file axis `axis` is up (faces in file units).

    `standing` False takes the lowest large horizontal band as the floor without asking for room to stand
    (a given --up: a narrow floor is then the navmesh's to report, with the agent radius to change)."""
    k = 1 if axis == "y" else 2
    h = [i for i in range(3) if i != k]
    tri = tri * metres
    area = area * metres**2
    ups = np.abs(normals[:, k])
    horizontal, vertical = ups > HORIZONTAL_COS, ups < VERTICAL_COS
    flat = float(area[horizontal].sum())
    heights = tri[:, :, k]
    tri2 = tri[:, :, h]
    centre = heights.mean(axis=1)
    levels = _levels(centre[horizontal], area[horizontal])
    largest = max((a for _, a in levels), default=0.0)

    def room_to_stand(level_z: float) -> tuple[np.ndarray, np.ndarray]:
        """(wall segments at `RAY_HEIGHT_M` above the level, its sample points clear of them)."""
        in_level = horizontal & (centre >= level_z) & (centre <= level_z + LEVEL_BAND_M)
        segs = _slice(tri2, heights, level_z + RAY_HEIGHT_M)
        points = _sample(tri2[in_level], area[in_level])
        return segs, points[_clearance(points, segs) >= CLEARANCE_M]

    floor = None
    for floor_z, floor_area in levels:
        if floor_area < FLOOR_SHARE * largest:  # a pit, a shaft's bottom, a step: not the building's floor
            continue
        segs, points = room_to_stand(floor_z)
        if not standing or len(points) >= STANDABLE_MIN * RAY_POINTS:
            floor = (floor_z, floor_area, segs, points)
            break
    if floor is None:
        return FrameEvidence(axis, flat, None, 0.0, 0.0, False, None, f"no horizontal surface of {FLOOR_MIN_M2:g} "
                             "m^2 or more" + (" with room to stand" if standing else ""))
    floor_z, floor_area, segs, points = floor
    wall_lo = heights[vertical].min(axis=1)
    wall_area = area[vertical]
    total_walls = float(wall_area.sum())
    # Walls below the floor count against it unless they rise from a lower level with room to stand (a pit, a
    # lift shaft's bottom, a basement).
    hanging = wall_lo < floor_z - FLOOR_TOL_M
    for level_z, _ in levels:
        if level_z < floor_z - FLOOR_TOL_M and len(room_to_stand(level_z)[1]) >= STANDABLE_MIN * RAY_POINTS:
            hanging &= np.abs(wall_lo - level_z) > FLOOR_TOL_M
    below = float(wall_area[hanging].sum()) / total_walls if total_walls else 0.0
    rising = float(wall_area[(wall_lo >= floor_z - FLOOR_TOL_M) & (wall_lo <= floor_z + STOREY_M)].sum())
    walled = rising >= WALLED_RATIO * floor_area
    if below > WALLS_BELOW_MAX:
        return FrameEvidence(axis, flat, floor_z, floor_area, below, walled, None,
                             f"{100 * below:.0f}% of the walls reach below the floor")
    if not walled:
        return FrameEvidence(axis, flat, floor_z, floor_area, below, False, None, "")
    enclosure = _enclosure(points, segs)
    problem = "" if enclosure >= ENCLOSED_MIN else "open on the sides: walls on a floor that was a wall?"
    return FrameEvidence(axis, flat, floor_z, floor_area, below, True, enclosure, problem)


def _levels(heights: np.ndarray, area: np.ndarray) -> list[tuple[float, float]]:
    """(height, area) of the bands of horizontal faces holding at least FLOOR_MIN_M2, lowest first."""
    if len(heights) == 0:
        return []
    order = np.argsort(heights, kind="stable")
    hs, ar = heights[order], area[order]
    # Area within one band above each face's height; bands holding enough start a level, one per band.
    ends = np.searchsorted(hs, hs + LEVEL_BAND_M, side="right")
    csum = np.concatenate([[0.0], np.cumsum(ar)])
    band = csum[ends] - csum[np.arange(len(hs))]
    out: list[tuple[float, float]] = []
    for i in np.flatnonzero(band >= FLOOR_MIN_M2):
        if not out or hs[i] > out[-1][0] + LEVEL_BAND_M:
            out.append((float(hs[i]), float(band[i])))
    return out


def _sample(tri2: np.ndarray, area: np.ndarray) -> np.ndarray:
    """`RAY_POINTS` points (2D) on the triangles, area-weighted, from a fixed seed (deterministic)."""
    rng = np.random.default_rng(0)
    pick = rng.choice(len(tri2), size=RAY_POINTS, p=area / area.sum())
    u, v = rng.random(RAY_POINTS), rng.random(RAY_POINTS)
    flip = u + v > 1
    u[flip], v[flip] = 1 - u[flip], 1 - v[flip]
    t = tri2[pick]
    return t[:, 0] + u[:, None] * (t[:, 1] - t[:, 0]) + v[:, None] * (t[:, 2] - t[:, 0])


def _clearance(points: np.ndarray, segs: np.ndarray) -> np.ndarray:
    """Distance (m) from each 2D point to the nearest segment (inf without segments)."""
    if len(segs) == 0:
        return np.full(len(points), np.inf)
    a, e = segs[:, 0], segs[:, 1] - segs[:, 0]
    ee = np.maximum((e * e).sum(axis=1), 1e-18)
    out = np.empty(len(points))
    for i, p in enumerate(points):
        r = np.clip(((p - a) * e).sum(axis=1) / ee, 0.0, 1.0)
        out[i] = float(np.sqrt((((a + r[:, None] * e) - p) ** 2).sum(axis=1).min()))
    return out


def _enclosure(points: np.ndarray, segs: np.ndarray) -> float:
    """Share of horizontal rays from the 2D `points` (in `RAY_DIRECTIONS` directions) that hit a segment."""
    if len(segs) == 0 or len(points) == 0:
        return 0.0
    angles = 2 * np.pi * (np.arange(RAY_DIRECTIONS) + 0.5) / RAY_DIRECTIONS
    dirs = np.stack([np.cos(angles), np.sin(angles)], axis=1)
    a, e = segs[:, 0], segs[:, 1] - segs[:, 0]
    hits = 0
    for p in points:
        # Ray p + s*d against segment a + r*e: solve with 2D cross products, all directions and segments at once.
        w = a - p
        den = dirs[:, None, 0] * e[None, :, 1] - dirs[:, None, 1] * e[None, :, 0]
        with np.errstate(divide="ignore", invalid="ignore"):
            s = (w[None, :, 0] * e[None, :, 1] - w[None, :, 1] * e[None, :, 0]) / den
            r = (w[None, :, 0] * dirs[:, None, 1] - w[None, :, 1] * dirs[:, None, 0]) / den
        hit = (np.abs(den) > 1e-12) & (s > 1e-3) & (r >= 0) & (r <= 1)
        hits += int(hit.any(axis=1).sum())
    return hits / (len(points) * RAY_DIRECTIONS)


def _slice(tri2: np.ndarray, heights: np.ndarray, z: float) -> np.ndarray:
    """(S, 2, 2) segments where the plane at height `z` cuts the triangles."""
    lo, hi = heights.min(axis=1), heights.max(axis=1)
    m = (lo < z) & (hi > z)
    t, hz = tri2[m], heights[m]
    pts = []
    for i, j in ((0, 1), (1, 2), (2, 0)):
        zi, zj = hz[:, i], hz[:, j]
        cut = (zi - z) * (zj - z) < 0
        with np.errstate(divide="ignore", invalid="ignore"):
            f = np.where(cut, (z - zi) / (zj - zi), np.nan)
        pts.append(t[:, i] + f[:, None] * (t[:, j] - t[:, i]))
    stacked = np.stack(pts, axis=1)  # (S, 3, 2): two finite points per cut triangle (one edge is not cut)
    ok = np.isfinite(stacked[:, :, 0])
    two = ok.sum(axis=1) == 2
    stacked, ok = stacked[two], ok[two]
    order = np.argsort(~ok, axis=1, kind="stable")[:, :2]
    return np.take_along_axis(stacked, order[:, :, None], axis=1)
