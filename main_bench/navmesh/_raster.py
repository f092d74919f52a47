"""Numba kernels that turn triangles into a 2.5D heightfield of walkable nodes and their links.

Grid: column (ix, iy) covers x in [x0 + ix*cs, x0 + (ix+1)*cs), y likewise (half-open, so a zero-thickness
wall lying on a cell boundary belongs to exactly one column). Directions 0..7: E, N, W, S, NE, NW, SW, SE.
"""

from __future__ import annotations

import numpy as np

from ..jit import njit

DX = np.array([1, 0, -1, 0, 1, -1, -1, 1], dtype=np.int64)
DY = np.array([0, 1, 0, -1, 1, 1, -1, -1], dtype=np.int64)


@njit(cache=True)
def _clip(px, py, pz, n, axis, bound, keep_ge, ox, oy, oz):
    """Sutherland-Hodgman step: clip polygon (px,py,pz)[:n] against axis >= bound (or <=); returns count."""
    m = 0
    for i in range(n):
        j = (i + 1) % n
        a = px[i] if axis == 0 else py[i]
        b = px[j] if axis == 0 else py[j]
        ina = a >= bound if keep_ge else a <= bound
        inb = b >= bound if keep_ge else b <= bound
        if ina:
            ox[m] = px[i]
            oy[m] = py[i]
            oz[m] = pz[i]
            m += 1
        if ina != inb:
            t = (bound - a) / (b - a)
            ox[m] = px[i] + t * (px[j] - px[i])
            oy[m] = py[i] + t * (py[j] - py[i])
            oz[m] = pz[i] + t * (pz[j] - pz[i])
            m += 1
    return m


@njit(cache=True)
def rasterize(verts, faces, x0, y0, cs, nx, ny, min_normal_z):
    """Clip every triangle to every column it touches; returns spans (col, zlo, zhi, kind, rect).

    kind: 1 flat enough to walk on (facing up), 2 flat facing down, 0 anything else.
    rect: (S, 4) x and y extent of the clipped piece (xmin, ymin, xmax, ymax, m): where in its column it lies.
    """
    nf = faces.shape[0]
    eps = 1e-6 * cs
    total = 0
    for f in range(nf):
        xs = (verts[faces[f, 0], 0], verts[faces[f, 1], 0], verts[faces[f, 2], 0])
        ys = (verts[faces[f, 0], 1], verts[faces[f, 1], 1], verts[faces[f, 2], 1])
        ix0 = max(int(np.floor((min(xs) - x0 - eps) / cs)), 0)
        ix1 = min(int(np.floor((max(xs) - x0 + eps) / cs)), nx - 1)
        iy0 = max(int(np.floor((min(ys) - y0 - eps) / cs)), 0)
        iy1 = min(int(np.floor((max(ys) - y0 + eps) / cs)), ny - 1)
        if ix1 >= ix0 and iy1 >= iy0:
            total += (ix1 - ix0 + 1) * (iy1 - iy0 + 1)
    col = np.empty(total, np.int64)
    zlo = np.empty(total, np.float64)
    zhi = np.empty(total, np.float64)
    kind = np.empty(total, np.int8)
    rect = np.empty((total, 4))
    ax = np.empty(16)
    ay = np.empty(16)
    az = np.empty(16)
    bx = np.empty(16)
    by = np.empty(16)
    bz = np.empty(16)
    k = 0
    for f in range(nf):
        a = verts[faces[f, 0]]
        b = verts[faces[f, 1]]
        c = verts[faces[f, 2]]
        ux, uy, uz = b[0] - a[0], b[1] - a[1], b[2] - a[2]
        vx, vy, vz = c[0] - a[0], c[1] - a[1], c[2] - a[2]
        nxx = uy * vz - uz * vy
        nyy = uz * vx - ux * vz
        nzz = ux * vy - uy * vx
        norm = np.sqrt(nxx * nxx + nyy * nyy + nzz * nzz)
        if norm <= 1e-14:
            continue
        # 1: walkable (flat enough, facing up), 2: flat facing down (a lid or the bottom of a solid), 0: other
        tkind = 1 if nzz / norm >= min_normal_z else (2 if -nzz / norm >= min_normal_z else 0)
        ix0 = max(int(np.floor((min(a[0], b[0], c[0]) - x0 - eps) / cs)), 0)
        ix1 = min(int(np.floor((max(a[0], b[0], c[0]) - x0 + eps) / cs)), nx - 1)
        iy0 = max(int(np.floor((min(a[1], b[1], c[1]) - y0 - eps) / cs)), 0)
        iy1 = min(int(np.floor((max(a[1], b[1], c[1]) - y0 + eps) / cs)), ny - 1)
        for iy in range(iy0, iy1 + 1):
            cy0 = y0 + iy * cs
            cy1 = cy0 + cs
            for ix in range(ix0, ix1 + 1):
                cx0 = x0 + ix * cs
                cx1 = cx0 + cs
                ax[0], ay[0], az[0] = a[0], a[1], a[2]
                ax[1], ay[1], az[1] = b[0], b[1], b[2]
                ax[2], ay[2], az[2] = c[0], c[1], c[2]
                n = _clip(ax, ay, az, 3, 0, cx0 - eps, True, bx, by, bz)
                if n == 0:
                    continue
                n = _clip(bx, by, bz, n, 0, cx1 + eps, False, ax, ay, az)
                if n == 0:
                    continue
                n = _clip(ax, ay, az, n, 1, cy0 - eps, True, bx, by, bz)
                if n == 0:
                    continue
                n = _clip(bx, by, bz, n, 1, cy1 + eps, False, ax, ay, az)
                if n == 0:
                    continue
                lo = np.inf
                hi = -np.inf
                minx = np.inf
                miny = np.inf
                maxx = -np.inf
                maxy = -np.inf
                for i in range(n):
                    lo = min(lo, az[i])
                    hi = max(hi, az[i])
                    minx = min(minx, ax[i])
                    miny = min(miny, ay[i])
                    maxx = max(maxx, ax[i])
                    maxy = max(maxy, ay[i])
                # geometry lying on a cell boundary belongs to the cell on its solid side (behind its normal),
                # so a zero-thickness wall blocks exactly one column and a box face does not leak outwards
                if maxx <= cx0 + eps and not nxx < 0:
                    continue
                if minx >= cx1 - eps and not nxx > 0:
                    continue
                if maxy <= cy0 + eps and not nyy < 0:
                    continue
                if miny >= cy1 - eps and not nyy > 0:
                    continue
                col[k] = iy * nx + ix
                zlo[k] = lo
                zhi[k] = hi
                kind[k] = tkind
                rect[k, 0] = max(minx, cx0)
                rect[k, 1] = max(miny, cy0)
                rect[k, 2] = min(maxx, cx1)
                rect[k, 3] = min(maxy, cy1)
                k += 1
    return col[:k], zlo[:k], zhi[:k], kind[:k], rect[:k]


@njit(cache=True)
def make_nodes(col, zlo, zhi, kind, merge_gap, flag_tol, agent_height):
    """Merge sorted spans per column and keep walkable tops with agent_height of free space above.

    A top is walkable when a walkable triangle reaches it (within flag_tol) and no steeper one rises above.
    A top that is both covered by a downward face (the bottom of a solid resting on it) and roofed by a span
    whose lowest face looks up lies inside a closed solid and is dropped. Returns node (col, z, ceiling)
    sorted by column then height.
    """
    n = col.shape[0]
    mcol = np.empty(n, np.int64)
    mlo = np.empty(n)
    mhi = np.empty(n)
    mw = np.empty(n, np.bool_)
    mcap = np.empty(n, np.bool_)
    mup = np.empty(n, np.bool_)
    m = -1
    for i in range(n):
        w = kind[i] == 1
        cap = kind[i] == 2
        if m >= 0 and col[i] == mcol[m] and zlo[i] <= mhi[m] + merge_gap:
            if zhi[i] > mhi[m] + flag_tol:
                mw[m] = w
                mcap[m] = cap
            elif zhi[i] >= mhi[m] - flag_tol:
                mw[m] = mw[m] or w
                mcap[m] = mcap[m] or cap
            mhi[m] = max(mhi[m], zhi[i])
        else:
            m += 1
            mcol[m] = col[i]
            mlo[m] = zlo[i]
            mhi[m] = zhi[i]
            mw[m] = w
            mcap[m] = cap
            mup[m] = w
    m += 1
    ncol = np.empty(m, np.int64)
    nz = np.empty(m)
    nceil = np.empty(m)
    k = 0
    for i in range(m):
        if not mw[i]:
            continue
        ceil = np.inf
        roof_up = False
        if i + 1 < m and mcol[i + 1] == mcol[i]:
            ceil = mlo[i + 1]
            roof_up = mup[i + 1]
        if mcap[i] and roof_up:
            continue
        if ceil - mhi[i] >= agent_height:
            ncol[k] = mcol[i]
            nz[k] = mhi[i]
            nceil[k] = ceil
            k += 1
    return ncol[:k], nz[:k], nceil[:k]


@njit(cache=True)
def link_nodes(col_start, ix, iy, z, ceil, nx, ny, max_climb, agent_height):
    """Orthogonal links (N, 8) with -1 where absent; diagonals are filled by `diagonals`."""
    n = z.shape[0]
    nbr = np.full((n, 8), -1, np.int64)
    for u in range(n):
        for d in range(4):
            jx = ix[u] + DX[d]
            jy = iy[u] + DY[d]
            if jx < 0 or jy < 0 or jx >= nx or jy >= ny:
                continue
            c2 = jy * nx + jx
            best = -1
            bestdz = np.inf
            for v in range(col_start[c2], col_start[c2 + 1]):
                dz = abs(z[v] - z[u])
                if dz > max_climb or dz >= bestdz:
                    continue
                if min(ceil[u], ceil[v]) - max(z[u], z[v]) < agent_height:
                    continue
                best = v
                bestdz = dz
            nbr[u, d] = best
    for u in range(n):  # keep only symmetric links
        for d in range(4):
            v = nbr[u, d]
            if v >= 0 and nbr[v, (d + 2) % 4] != u:
                nbr[u, d] = -1
    return nbr


@njit(cache=True)
def diagonals(nbr):
    """Fill diagonal links where both orthogonal routes reach the same node (no corner cutting)."""
    n = nbr.shape[0]
    for u in range(n):
        for q in range(4):
            a_dir = q  # E, N, W, S paired with the next orthogonal direction
            b_dir = (q + 1) % 4
            a = nbr[u, a_dir]
            b = nbr[u, b_dir]
            v = -1
            if a >= 0 and b >= 0:
                va = nbr[a, b_dir]
                vb = nbr[b, a_dir]
                if va >= 0 and va == vb:
                    v = va
            nbr[u, 4 + q] = v
    return nbr
