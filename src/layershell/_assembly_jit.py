"""Compiled loops for the reduced scatter map of :mod:`layershell.assembly` (Numba, ``cache=True``).

K_r = Tᵀ K T (3.69)-(3.72): the symbolic pattern of K_r (Gustavson's row-by-row product with a
marker array) and, for every entry p = (i, j) of K, the positions in K_r of its contributions
T[i, a] T[j, b] K_p. Imported lazily; :mod:`layershell.assembly` has a NumPy fallback.
"""
from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, nogil=True)
def reduced_pattern(n_red, ttp, tti, kp, ki, tp, ti):  # pragma: no cover - compiled
    """CSR pattern (indptr, sorted indices) of Tᵀ K T from Tᵀ (ttp, tti), K (kp, ki), T (tp, ti)."""
    marker = np.full(n_red, -1, np.int64)
    counts = np.zeros(n_red + 1, np.int64)
    for a in range(n_red):  # pass 1: row lengths
        c = 0
        for s in range(ttp[a], ttp[a + 1]):
            i = tti[s]
            for p in range(kp[i], kp[i + 1]):
                j = ki[p]
                for t in range(tp[j], tp[j + 1]):
                    b = ti[t]
                    if marker[b] != a:
                        marker[b] = a
                        c += 1
        counts[a + 1] = c
    indptr = np.cumsum(counts)
    indices = np.empty(indptr[-1], ti.dtype)
    marker[:] = -1
    for a in range(n_red):  # pass 2: columns, sorted per row
        pos = indptr[a]
        for s in range(ttp[a], ttp[a + 1]):
            i = tti[s]
            for p in range(kp[i], kp[i + 1]):
                j = ki[p]
                for t in range(tp[j], tp[j + 1]):
                    b = ti[t]
                    if marker[b] != a:
                        marker[b] = a
                        indices[pos] = b
                        pos += 1
        indices[indptr[a]:indptr[a + 1]] = np.sort(indices[indptr[a]:indptr[a + 1]])
    return indptr, indices


@njit(cache=True, nogil=True)
def _find(bi, lo, hi, b):  # pragma: no cover - compiled
    """Position of b in the sorted bi[lo:hi] (binary search; b is known to be there)."""
    while lo < hi:
        mid = (lo + hi) >> 1
        if bi[mid] < b:
            lo = mid + 1
        else:
            hi = mid
    return lo


@njit(cache=True, nogil=True)
def reduced_map(n_red, kp, ki, tp, ti, tv, bp, bi, col_ptr, q, w):  # pragma: no cover - compiled
    """Contributions of K's entries (P's columns, in K's CSR order starting at ``col_ptr[p]``):
    position q in K_r and weight w. Row a of K_r is spread into a dense position table while
    the rows i of K with T[i, a] ≠ 0 are processed, so each lookup is O(1)."""
    pos_of = np.full(n_red, -1, np.int64)
    for i in range(kp.size - 1):
        for s in range(tp[i], tp[i + 1]):
            a = ti[s]
            for x in range(bp[a], bp[a + 1]):
                pos_of[bi[x]] = x
            ds = s - tp[i]
            ws = tv[s]
            for p in range(kp[i], kp[i + 1]):
                j = ki[p]
                nj = tp[j + 1] - tp[j]
                base = col_ptr[p] + ds * nj
                for t in range(tp[j], tp[j + 1]):
                    q[base + t - tp[j]] = pos_of[ti[t]]
                    w[base + t - tp[j]] = ws * tv[t]


@njit(cache=True, nogil=True)
def mirror_positions(bp, bi, upper_pos, rows):  # pragma: no cover - compiled
    """For each upper entry (a, b) the position of (b, a), or -1 where the pattern lacks it."""
    out = np.empty(upper_pos.size, np.int64)
    for k in range(upper_pos.size):
        x = upper_pos[k]
        a, b = rows[k], bi[x]
        y = _find(bi, bp[b], bp[b + 1], a)
        out[k] = y if (y < bp[b + 1] and bi[y] == a) else -1
    return out


@njit(cache=True, nogil=True)
def full_pattern(n, dofs, estart, vstart, scatter):  # pragma: no cover - compiled
    """Full-space CSR pattern of the element matrices and the scatter index of every element
    entry. ``dofs``: all elements' DOFs one after the other (element g owns
    ``dofs[estart[g]:estart[g+1]]``, its m×m entries start at ``vstart[g]``, row-major); the
    scatter index is written into ``scatter`` (size ``vstart[-1]``)."""
    n_el = estart.size - 1
    # incidence DOF -> (element, local index)
    cnt = np.zeros(n + 1, np.int64)
    for x in range(dofs.size):
        cnt[dofs[x] + 1] += 1
    inc_ptr = np.cumsum(cnt)
    fill = inc_ptr[:-1].copy()
    inc_el = np.empty(dofs.size, np.int64)
    inc_k = np.empty(dofs.size, np.int64)
    for g in range(n_el):
        for k in range(estart[g + 1] - estart[g]):
            r = dofs[estart[g] + k]
            inc_el[fill[r]] = g
            inc_k[fill[r]] = k
            fill[r] += 1
    marker = np.full(n, -1, np.int64)
    counts = np.zeros(n + 1, np.int64)
    for r in range(n):  # pass 1: row lengths
        c = 0
        for x in range(inc_ptr[r], inc_ptr[r + 1]):
            g = inc_el[x]
            for y in range(estart[g], estart[g + 1]):
                col = dofs[y]
                if marker[col] != r:
                    marker[col] = r
                    c += 1
        counts[r + 1] = c
    indptr = np.cumsum(counts)
    indices = np.empty(indptr[-1], dofs.dtype)
    marker[:] = -1
    pos_of = marker  # reused after the row's columns are sorted
    for r in range(n):  # pass 2: sorted columns, then the scatter of the row's element entries
        pos = indptr[r]
        for x in range(inc_ptr[r], inc_ptr[r + 1]):
            g = inc_el[x]
            for y in range(estart[g], estart[g + 1]):
                col = dofs[y]
                if marker[col] != -2 - r:
                    marker[col] = -2 - r
                    indices[pos] = col
                    pos += 1
        indices[indptr[r]:indptr[r + 1]] = np.sort(indices[indptr[r]:indptr[r + 1]])
        for z in range(indptr[r], indptr[r + 1]):
            pos_of[indices[z]] = z
        for x in range(inc_ptr[r], inc_ptr[r + 1]):
            g = inc_el[x]
            k = inc_k[x]
            m = estart[g + 1] - estart[g]
            base = vstart[g] + k * m
            for l in range(m):
                scatter[base + l] = pos_of[dofs[estart[g] + l]]
    return indptr, indices


@njit(cache=True, nogil=True)
def scatter_add(data, scatter, start, values):  # pragma: no cover - compiled
    """data[scatter[start + k]] += values[k]: element entries summed into the CSR data of K."""
    for k in range(values.size):
        data[scatter[start + k]] += values[k]


@njit(cache=True, nogil=True)
def scatter_add_elements(data, scatter, start, values, elements, m2):  # pragma: no cover - compiled
    """The same for a subset of a block's elements: element ``elements[s]`` owns the m2 entries
    from ``start + elements[s] * m2``, its values are ``values[s * m2:(s + 1) * m2]``."""
    for s in range(elements.size):
        base = start + elements[s] * m2
        for k in range(m2):
            data[scatter[base + k]] += values[s * m2 + k]


@njit(cache=True, nogil=True)
def max_mirror_difference(data, upper_pos, mirror_pos):  # pragma: no cover - compiled
    """max |K_ab - K_ba| over the upper entries (the symmetry check of the reduced tangent)."""
    m = 0.0
    for k in range(upper_pos.size):
        d = abs(data[upper_pos[k]] - data[mirror_pos[k]])
        if d > m:
            m = d
    return m


@njit(cache=True, nogil=True)
def mirror_difference_and_max(data, upper_pos, mirror_pos):  # pragma: no cover - compiled
    """(max |K_ab - K_ba|, max |K_ab|) over the upper entries and their mirrors in one pass (every
    entry is one of them where each upper entry has its mirror)."""
    m = 0.0
    a = 0.0
    for k in range(upper_pos.size):
        x = data[upper_pos[k]]
        y = data[mirror_pos[k]]
        d = abs(x - y)
        if d > m:
            m = d
        if abs(x) > a:
            a = abs(x)
        if abs(y) > a:
            a = abs(y)
    return m, a


@njit(cache=True, nogil=True)
def gather(data, pos):  # pragma: no cover - compiled
    """data[pos] for an int32 ``pos`` (NumPy would first convert the index array to int64)."""
    out = np.empty(pos.size, data.dtype)
    for k in range(pos.size):
        out[k] = data[pos[k]]
    return out


@njit(cache=True, nogil=True)
def max_abs(data):  # pragma: no cover - compiled
    """max |data| without a temporary array."""
    m = 0.0
    for k in range(data.size):
        d = abs(data[k])
        if d > m:
            m = d
    return m
