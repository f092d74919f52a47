"""Numba kernels for any-angle distance fields ("source propagation") and point look-ups.

A propagation is `seed`, `seed_ring`, then `settle` (resumable: it stops once given nodes are done).

Every reached node v keeps an anchor s(v): a target or a corner node that v sees in a straight line, and
g(v) = D(s) + |v - s| (3D, with smoothed heights). Anchors are numbered 0..N-1 for nodes, N+j for target j.
Visibility is decided by induction: v sees s if its neighbour w one step towards s (both neighbours bracketing
the direction to s, if it lies between two) is linked, settled and anchored at s (or is s), and the heights
along the way stay within `ztol` of one straight line (a slope interval [klo, khi] carried from node to node), so
lines do not cut through floors, stairs or ramps.
"""

from __future__ import annotations

import numpy as np

from ..jit import NO_REFCOUNTS, njit, uix
from ._graph import _heap4_pop, _heap4_push


@njit(inline="always")
def _anchor_pos(a, n, px, py, pz, tpos):
    if a >= n:
        return tpos[a - n, 0], tpos[a - n, 1], tpos[a - n, 2]
    return px[a], py[a], pz[a]


@njit(inline="always")
def _bracket(dx, dy):
    """The one or two directions (0..7: E, N, W, S, NE, NW, SW, SE) between which (dx, dy) points.

    Returns (d1, d2) with d2 = -1 when (dx, dy) is along an axis or a diagonal.
    """
    ax = abs(dx)
    ay = abs(dy)
    tiny = 1e-9 * (ax + ay)
    if dx > 0:
        diag = 4 if dy > 0 else 7
    else:
        diag = 5 if dy > 0 else 6
    if abs(ax - ay) <= tiny:
        return diag, -1
    if ax > ay:
        orth = 0 if dx > 0 else 2
        return orth, (-1 if ay <= tiny else diag)
    orth = 1 if dy > 0 else 3
    return orth, (-1 if ax <= tiny else diag)


@njit(cache=True, **NO_REFCOUNTS)
def _line_of_sight(v, goal, sx, sy, sz, nbr, px, py, pz, cs, ztol, cx, cy, steps, offsets):
    """Walk the cells the segment from node v's point to (sx, sy, sz) crosses (goal = node of that point).

    (px, py): the nodes' points, (cx, cy): their cell centres (a point lies within its cell).
    steps, offsets: `FieldSpace.steps` and `FieldSpace.offsets` (a step by an offset needs no load of `nbr`).

    True when each crossed cell is linked to the previous one and its height stays within ztol of the line.
    """
    x = px[uix(v)]
    y = py[uix(v)]
    dx = sx - x
    dy = sy - y
    dz = sz - pz[uix(v)]
    len2 = dx * dx + dy * dy
    inv_len2 = 1.0 / len2 if len2 > 0.0 else 0.0
    stepx = 1 if dx > 0 else -1
    stepy = 1 if dy > 0 else -1
    # parameter t in [0, 1] along the segment where the next x / y cell boundary is crossed
    tdx = cs / abs(dx) if dx != 0 else np.inf
    tdy = cs / abs(dy) if dy != 0 else np.inf
    tmx = (0.5 - stepx * (x - cx[uix(v)]) / cs) * tdx if dx != 0 else np.inf
    tmy = (0.5 - stepy * (y - cy[uix(v)]) / cs) * tdy if dy != 0 else np.inf
    cur = v
    limit = int(abs(dx) / cs + abs(dy) / cs) + 3
    for _ in range(limit):
        if cur == goal:
            return True
        tie = 1e-9 * (tmx + tmy) if np.isfinite(tmx + tmy) else 0.0
        if abs(tmx - tmy) <= tie:
            if stepx > 0:
                d = 4 if stepy > 0 else 7
            else:
                d = 5 if stepy > 0 else 6
            t = tmx
            tmx += tdx
            tmy += tdy
        elif tmx < tmy:
            d = 0 if stepx > 0 else 2
            t = tmx
            tmx += tdx
        else:
            d = 1 if stepy > 0 else 3
            t = tmy
            tmy += tdy
        if t > 1.0 + 1e-9:
            return cur == goal
        if (steps[uix(cur)] >> d) & 1:
            cur += offsets[uix(d)]  # the same cell as nbr[cur, d], without waiting for that load
        else:
            cur = nbr[uix(cur), uix(d)]
            if cur < 0:
                return False
        # height of the line at the point nearest this cell's centre
        tc = ((px[uix(cur)] - x) * dx + (py[uix(cur)] - y) * dy) * inv_len2
        tc = min(max(tc, 0.0), 1.0)
        if abs(pz[uix(cur)] - (pz[uix(v)] + tc * dz)) > ztol:
            return False
    return cur == goal


@njit(cache=True)
def seed(nbr, px, py, pz, tnode, tpos, ztol):
    """Start a propagation from the targets: (g, anchor, root, klo, khi, done, hk, hv, pos, size), the state
    that `settle` advances. g and anchor hold tentative values until a node is done; anchor and root are -1 where
    unreached; (hk, hv, pos, size) is the queue (`_graph._heap4_push`)."""
    n = nbr.shape[0]
    g = np.full(n, np.inf)
    anchor = np.full(n, -1, np.int32)
    root = np.full(n, -1, np.int32)
    klo = np.full(n, -np.inf)
    khi = np.full(n, np.inf)
    done = np.zeros(n, np.bool_)
    pos = np.full(n, -1, np.int32)
    cap = 9 * tnode.shape[0] + 1024
    hk = np.empty(cap)
    hv = np.empty(cap, np.int64)
    size = 0
    for j in range(tnode.shape[0]):
        u = tnode[j]
        if u < 0:
            continue
        dx = px[u] - tpos[j, 0]
        dy = py[u] - tpos[j, 1]
        dz = pz[u] - tpos[j, 2]
        d = np.sqrt(dx * dx + dy * dy + dz * dz)
        if d < g[u]:
            g[u] = d
            anchor[u] = n + j
            dh = np.sqrt(dx * dx + dy * dy)
            if dh > 1e-9:
                klo[u] = (dz - ztol) / dh
                khi[u] = (dz + ztol) / dh
            else:
                klo[u] = -np.inf
                khi[u] = np.inf
            size = _heap4_push(hk, hv, pos, size, d, u)
    return g, anchor, root, klo, khi, done, hk, hv, pos, size


@njit(cache=True)
def seed_ring(nbr, px, py, pz, tnode, tpos, ztol, cs, cx, cy, steps, offsets, g, anchor, klo, khi, hk, hv, pos,
              size):
    """Seed the targets' first ring of neighbours (after `seed`); returns the queue's new size.

    The target node's centre is not the target: its neighbours cannot use the bracket test against it (which
    needs settled neighbours anchored at the target), so the first ring is seeded by walking each segment.
    """
    n = nbr.shape[0]
    for j in range(tnode.shape[0]):
        u = tnode[j]
        if u < 0:
            continue
        for dd in range(8):
            v = nbr[u, dd]
            if v < 0:
                continue
            dx = px[v] - tpos[j, 0]
            dy = py[v] - tpos[j, 1]
            dz = pz[v] - tpos[j, 2]
            dh = np.sqrt(dx * dx + dy * dy)
            d = np.sqrt(dh * dh + dz * dz)
            if d >= g[v] or dh <= 1e-9:
                continue
            tx, ty, tz = tpos[j, 0], tpos[j, 1], tpos[j, 2]
            if not _line_of_sight(v, u, tx, ty, tz, nbr, px, py, pz, cs, ztol, cx, cy, steps, offsets):
                continue
            g[v] = d
            anchor[v] = n + j
            klo[v] = (dz - ztol) / dh
            khi[v] = (dz + ztol) / dh
            size = _heap4_push(hk, hv, pos, size, d, v)
    return size


@njit(cache=True, **NO_REFCOUNTS)
def settle(nbr, px, py, pz, tnode, tpos, ztol, cs, cx, cy, steps, offsets, g, anchor, root, klo, khi, done, hk, hv,
           pos, size, stops, stats):
    """Advance a propagation (state from `seed` and `seed_ring`) until every node in `stops` (-1 entries
    ignored) is done, or to the end when `stops` is empty. Returns (size, full): the queue's size (0 when every
    reachable node is done) and whether it stopped early because the queue (hk, hv) needs more room.

    Nodes are settled in the same order however the work is split between calls, so a node's (g, anchor, root)
    once done are those of one uninterrupted run.

    stats: (4,) int64 counters, added to (segment walks, cells walked, walks that saw, nodes settled).
    """
    n = nbr.shape[0]
    nstops = stops.shape[0]
    k = 0
    while size > 0:
        if nstops > 0:
            while k < nstops and (stops[uix(k)] < 0 or done[uix(stops[uix(k)])]):
                k += 1
            if k == nstops:
                break
        if size + 8 > hk.shape[0]:
            return size, True  # the caller grows the queue and calls again (arrays are not reassigned here:
            # a kernel that reassigns them runs about a tenth slower)
        _, u, size = _heap4_pop(hk, hv, pos, size)
        done[uix(u)] = True
        stats[3] += 1
        s = anchor[uix(u)]
        root[uix(u)] = s - n if s >= n else root[uix(s)]
        sx, sy, sz = _anchor_pos(s, n, px, py, pz, tpos)
        ds = 0.0 if s >= n else g[uix(s)]
        for d in range(8):
            v = nbr[uix(u), uix(d)]
            if v < 0 or done[uix(v)]:
                continue
            best = g[uix(v)]
            banchor = -1
            blo = 0.0
            bhi = 0.0
            # 1. through u's anchor, if v sees it (a v anchored at s already holds exactly that distance)
            far = anchor[uix(v)] == s  # v is already as near as a path through s makes it
            if not far:
                hx = sx - px[uix(v)]
                hy = sy - py[uix(v)]
                hz = pz[uix(v)] - sz
                dh = np.sqrt(hx * hx + hy * hy)
                cand = ds + np.sqrt(dh * dh + hz * hz)
                far = cand >= best
                if dh > 1e-9 and cand < best:
                    d1, d2 = _bracket(hx, hy)
                    lo = (hz - ztol) / dh
                    hi = (hz + ztol) / dh
                    own = max(abs(hx), abs(hy)) <= 0.5 * cs * (1.0 + 1e-9)  # s lies in v's own cell
                    ok = True
                    blocked = False  # no need to walk the segment: it is blocked, or a later relaxation decides
                    if not own:
                        for dd in (d1, d2):
                            if dd < 0:
                                continue
                            w = nbr[uix(v), uix(dd)]
                            if w < 0:
                                ok = False
                                blocked = dd == d1  # the first cell the segment enters is not linked
                                break
                            if w != s and not done[uix(w)]:
                                ok = False
                                blocked = True  # w settles later and relaxes v again
                                break
                            if not (w == s or anchor[uix(w)] == s):
                                ok = False
                                break
                            if w != s:
                                lo = max(lo, klo[uix(w)])
                                hi = min(hi, khi[uix(w)])
                    if not (ok and lo <= hi) and not blocked:
                        # the cheap test fails near shadow edges and ties: walk the segment cell by cell
                        goal = s if s < n else tnode[s - n]
                        stats[0] += 1
                        ok = _line_of_sight(v, goal, sx, sy, sz, nbr, px, py, pz, cs, ztol, cx, cy, steps, offsets)
                        stats[1] += int(dh / cs)
                        stats[2] += ok
                        lo = (hz - ztol) / dh
                        hi = (hz + ztol) / dh
                    if ok and lo <= hi:
                        best = cand
                        banchor = s
                        blo = lo
                        bhi = hi
            # 2. through u itself as a corner: never shorter than through u's anchor s (the triangle inequality),
            # so only worth it where v does not see s; a v anchored at u already holds exactly that distance
            if banchor < 0 and not far and anchor[uix(v)] != u:
                ex = px[uix(v)] - px[uix(u)]
                ey = py[uix(v)] - py[uix(u)]
                ez = pz[uix(v)] - pz[uix(u)]
                eh = np.sqrt(ex * ex + ey * ey)
                c = g[uix(u)] + np.sqrt(eh * eh + ez * ez)
                if c < best:
                    best = c
                    banchor = u
                    blo = (ez - ztol) / eh
                    bhi = (ez + ztol) / eh
            if banchor >= 0:
                g[uix(v)] = best
                anchor[uix(v)] = banchor
                klo[uix(v)] = blo
                khi[uix(v)] = bhi
                size = _heap4_push(hk, hv, pos, size, best, v)
    return size, False


@njit(cache=True)
def locate(points, x0, y0, cs, nx, ny, col_start, z, below, above):
    """Node of each point: same column, surface within [p.z - above, p.z + below], nearest in height; -1 if none."""
    m = points.shape[0]
    out = np.full(m, -1, np.int64)
    for i in range(m):
        fx = (points[i, 0] - x0) / cs
        fy = (points[i, 1] - y0) / cs
        if not (fx >= 0.0 and fy >= 0.0 and fx < nx and fy < ny):
            continue
        c = int(fy) * nx + int(fx)
        best = -1
        bestdz = np.inf
        pz = points[i, 2]
        for v in range(col_start[c], col_start[c + 1]):
            dz = z[v] - pz
            if dz > below or -dz > above:
                continue
            if abs(dz) < bestdz:
                bestdz = abs(dz)
                best = v
        out[i] = best
    return out


@njit(cache=True)
def locate_near(points, nodes, x0, y0, cs, nx, ny, col_start, z, below, above, radius, allowed):
    """For points with node -1, the nearest node (horizontally) within `radius` m on the same level.

    `allowed[node]` restricts the candidates (e.g. to reached nodes or one island).
    """
    m = points.shape[0]
    out = nodes.copy()
    r = int(np.ceil(radius / cs))
    for i in range(m):
        if out[i] >= 0 and allowed[out[i]]:
            continue
        out[i] = -1
        px = points[i, 0]
        py = points[i, 1]
        pz = points[i, 2]
        if not (np.isfinite(px) and np.isfinite(py) and np.isfinite(pz)):
            continue
        cx = int(np.floor((px - x0) / cs))
        cy = int(np.floor((py - y0) / cs))
        best = -1
        bestd = radius * radius
        for jy in range(max(cy - r, 0), min(cy + r, ny - 1) + 1):
            for jx in range(max(cx - r, 0), min(cx + r, nx - 1) + 1):
                c = jy * nx + jx
                if col_start[c] == col_start[c + 1]:
                    continue
                qx = min(max(px, x0 + jx * cs), x0 + (jx + 1) * cs) - px
                qy = min(max(py, y0 + jy * cs), y0 + (jy + 1) * cs) - py
                dd = qx * qx + qy * qy
                if dd > bestd:
                    continue
                for v in range(col_start[c], col_start[c + 1]):
                    dz = z[v] - pz
                    if dz > below or -dz > above or not allowed[v]:
                        continue
                    if dd < bestd or best < 0:
                        bestd = dd
                        best = v
        out[i] = best
    return out


@njit(cache=True)
def _ring_column(jx, jy, px, py, pz, z, col_start, allowed, x0, y0, cs, nx, best, bestd):
    # the nearest allowed node of column (jx, jy) (cell centres at surface height) if nearer than bestd (squared)
    hx = x0 + (jx + 0.5) * cs - px
    hy = y0 + (jy + 0.5) * cs - py
    h2 = hx * hx + hy * hy
    c = jy * nx + jx
    for v in range(col_start[c], col_start[c + 1]):
        if not allowed[v]:
            continue
        dz = z[v] - pz
        d2 = h2 + dz * dz
        if d2 < bestd:
            bestd = d2
            best = v
    return best, bestd


@njit(cache=True)
def nearest_cells(points, x0, y0, cs, nx, col_start, z, allowed, box, bound):
    """For each point, the node whose cell centre (at surface height) is nearest in 3D among `allowed[node]`,
    strictly within `bound` m; -1 where none is (or the point is not finite). `box`: (ix0, ix1, iy0, iy1), the
    columns that hold every allowed node.

    Square rings of columns around the point's column (clamped into the box), outwards: a centre in ring r lies
    at least sqrt(ox^2 + oy^2 + ((r - 1/2) cells)^2) away, (ox, oy) being the point's offset outside the box,
    so the search stops once that exceeds the best distance found.
    """
    m = points.shape[0]
    out = np.full(m, -1, np.int64)
    bx0, bx1, by0, by1 = box[0], box[1], box[2], box[3]
    for i in range(m):
        px = points[i, 0]
        py = points[i, 1]
        pz = points[i, 2]
        if not (np.isfinite(px) and np.isfinite(py) and np.isfinite(pz)) or bx1 < bx0 or by1 < by0:
            continue
        cx = int(min(max(np.floor((px - x0) / cs), float(bx0)), float(bx1)))
        cy = int(min(max(np.floor((py - y0) / cs), float(by0)), float(by1)))
        ox = max(x0 + bx0 * cs - px, px - (x0 + (bx1 + 1) * cs), 0.0)
        oy = max(y0 + by0 * cs - py, py - (y0 + (by1 + 1) * cs), 0.0)
        out2 = ox * ox + oy * oy
        best = -1
        bestd = bound * bound
        rmax = max(max(cx - bx0, bx1 - cx), max(cy - by0, by1 - cy))
        for r in range(rmax + 1):
            lb = max(r - 0.5, 0.0) * cs
            if out2 + lb * lb >= bestd:
                break
            for jy in (cy - r, cy + r):  # the ring's bottom and top rows
                if jy < by0 or jy > by1:
                    continue
                for jx in range(max(cx - r, bx0), min(cx + r, bx1) + 1):
                    best, bestd = _ring_column(jx, jy, px, py, pz, z, col_start, allowed, x0, y0, cs, nx, best, bestd)
                if r == 0:
                    break
            if r == 0:
                continue
            for jx in (cx - r, cx + r):  # its left and right columns, corners done above
                if jx < bx0 or jx > bx1:
                    continue
                for jy in range(max(cy - r + 1, by0), min(cy + r - 1, by1) + 1):
                    best, bestd = _ring_column(jx, jy, px, py, pz, z, col_start, allowed, x0, y0, cs, nx, best, bestd)
        out[i] = best
    return out


@njit(cache=True)
def field_index(index, cells):
    """The propagation index of each cell (`FieldSpace.index`); -1 stays -1."""
    out = np.empty(cells.shape[0], np.int64)
    for i in range(cells.shape[0]):
        c = cells[i]
        out[i] = index[c] if c >= 0 else -1
    return out


@njit(cache=True)
def lookup(points, cells, nodes, g, anchor, root, px, py, pz, z, tpos, tsurf, x0, y0, cs, ix, iy):
    """Distance from each point through its node's anchor; inf for nodes -1 or unreached.

    cells: each point's cell (indexes z, ix, iy); nodes: the same cell's propagation index (indexes g, anchor,
    root and the anchor points px, py, pz), -1 where none.

    Never less than the straight line from the point (clamped into its cell, at its surface height z) to the
    target its path ends at (tsurf): smoothed heights on stairs must not make a path shorter than that.
    """
    m = points.shape[0]
    n = g.shape[0]
    out = np.full(m, np.inf)
    for i in range(m):
        v = nodes[i]
        if v < 0:
            continue
        s = anchor[v]
        if s < 0:
            continue
        c = cells[i]
        # the point, clamped into its node's cell, at the node's (smoothed) height
        qx = min(max(points[i, 0], x0 + ix[c] * cs), x0 + (ix[c] + 1) * cs)
        qy = min(max(points[i, 1], y0 + iy[c] * cs), y0 + (iy[c] + 1) * cs)
        sx, sy, sz = _anchor_pos(s, n, px, py, pz, tpos)
        ds = 0.0 if s >= n else g[s]
        dx = qx - sx
        dy = qy - sy
        dz = pz[v] - sz
        d = ds + np.sqrt(dx * dx + dy * dy + dz * dz)
        j = root[v]
        ex = qx - tsurf[j, 0]
        ey = qy - tsurf[j, 1]
        ez = z[c] - tsurf[j, 2]
        out[i] = max(d, np.sqrt(ex * ex + ey * ey + ez * ez))
    return out
