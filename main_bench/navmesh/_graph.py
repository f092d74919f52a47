"""Numba kernels on the node graph: erosion by the agent radius, compaction, components, height smoothing."""

from __future__ import annotations

import numpy as np
from numba import njit

from ._raster import DX, DY


@njit(cache=True)
def _heap_push(hk, hv, size, key, val):
    i = size
    hk[i] = key
    hv[i] = val
    while i > 0:
        p = (i - 1) >> 1
        if hk[p] <= hk[i]:
            break
        hk[p], hk[i] = hk[i], hk[p]
        hv[p], hv[i] = hv[i], hv[p]
        i = p
    return size + 1


@njit(cache=True)
def _heap_pop(hk, hv, size):
    key = hk[0]
    val = hv[0]
    size -= 1
    hk[0] = hk[size]
    hv[0] = hv[size]
    i = 0
    while True:
        lft = 2 * i + 1
        if lft >= size:
            break
        c = lft
        if lft + 1 < size and hk[lft + 1] < hk[lft]:
            c = lft + 1
        if hk[i] <= hk[c]:
            break
        hk[c], hk[i] = hk[i], hk[c]
        hv[c], hv[i] = hv[i], hv[c]
        i = c
    return key, val, size


@njit(cache=True)
def clearance(nbr, ix, iy, limit):
    """Distance in cells from each node centre to the nearest blocked cell square (capped at `limit`).

    A direction without a link counts as a blocked cell there; the nearest blocked cell is carried along
    the graph (vector propagation), so distances are Euclidean to within a fraction of a cell.
    """
    n = nbr.shape[0]
    dist = np.full(n, np.inf)
    ox = np.zeros(n, np.int64)
    oy = np.zeros(n, np.int64)
    done = np.zeros(n, np.bool_)
    cap = n * 9 + 1
    hk = np.empty(cap)
    hv = np.empty(cap, np.int64)
    size = 0
    for u in range(n):
        for d in range(8):
            if nbr[u, d] < 0:
                ex = max(abs(DX[d]) - 0.5, 0.0)
                ey = max(abs(DY[d]) - 0.5, 0.0)
                dd = np.sqrt(ex * ex + ey * ey)
                if dd < dist[u]:
                    dist[u] = dd
                    ox[u] = ix[u] + DX[d]
                    oy[u] = iy[u] + DY[d]
        if dist[u] < np.inf:
            size = _heap_push(hk, hv, size, dist[u], u)
    while size > 0:
        key, u, size = _heap_pop(hk, hv, size)
        if done[u]:
            continue
        done[u] = True
        if key > limit:
            continue
        for d in range(8):
            v = nbr[u, d]
            if v < 0 or done[v]:
                continue
            ex = max(abs(ix[v] - ox[u]) - 0.5, 0.0)
            ey = max(abs(iy[v] - oy[u]) - 0.5, 0.0)
            dd = np.sqrt(ex * ex + ey * ey)
            if dd < dist[v]:
                dist[v] = dd
                ox[v] = ox[u]
                oy[v] = oy[u]
                size = _heap_push(hk, hv, size, dd, v)
    return dist


@njit(cache=True)
def compact_links(nbr, keep):
    """Links among kept nodes, renumbered; diagonals must be recomputed afterwards."""
    n = nbr.shape[0]
    new_id = np.full(n, -1, np.int64)
    m = 0
    for u in range(n):
        if keep[u]:
            new_id[u] = m
            m += 1
    out = np.full((m, 8), -1, np.int64)
    for u in range(n):
        if not keep[u]:
            continue
        for d in range(4):
            v = nbr[u, d]
            if v >= 0 and keep[v]:
                out[new_id[u], d] = new_id[v]
    return out


@njit(cache=True)
def components(nbr):
    """Connected components (label per node, labels 0..k-1 in order of first node)."""
    n = nbr.shape[0]
    label = np.full(n, -1, np.int64)
    stack = np.empty(n, np.int64)
    k = 0
    for s in range(n):
        if label[s] >= 0:
            continue
        label[s] = k
        top = 0
        stack[0] = s
        top = 1
        while top > 0:
            top -= 1
            u = stack[top]
            for d in range(8):
                v = nbr[u, d]
                if v >= 0 and label[v] < 0:
                    label[v] = k
                    stack[top] = v
                    top += 1
        k += 1
    return label


@njit(cache=True)
def smooth_heights(nbr, z, iterations):
    """Heights averaged over linked 3x3 neighbourhoods, `iterations` times: stairs become ramps for distances."""
    n = nbr.shape[0]
    cur = z.copy()
    nxt = np.empty(n)
    for _ in range(iterations):
        for u in range(n):
            s = cur[u]
            c = 1
            for d in range(8):
                v = nbr[u, d]
                if v >= 0:
                    s += cur[v]
                    c += 1
            nxt[u] = s / c
        cur, nxt = nxt, cur
    return cur
