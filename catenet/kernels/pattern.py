"""The CSR sparsity pattern of a system from its terms' entries, without sorting them all.

Entries come either as element blocks (``elems`` (E, k) node ids: every element's values
are the row-major (3k x 3k) block of its nodes' DOFs, as the stretching of an edge gives
them, never materialised as row and column arrays) or as DOF pairs (``rows``, ``cols``).
Kept entries (both DOFs free; with ``upper``, row <= col) are bucketed by their reduced
row (a counting sort, O(entries)), then each row's columns are made unique and sorted:
the same CSR arrays, and the same position for every entry, as ``np.unique`` of the keys
row * n + col, in linear time and with one small sort per row.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def pattern_entries(elems, rows, cols, reduced, upper, cursor, colbuf, srcbuf, offset, fill):
    """Counts (``fill`` False: cursor[r + 1] += 1) or buckets (``fill`` True: at
    cursor[r], the column and the entry's number ``offset + k``) the kept entries of one
    term: of its element blocks when ``elems`` has rows, else of its (rows, cols) pairs."""
    n_elem = elems.shape[0]
    if n_elem > 0:
        k = elems.shape[1]
        m = 3 * k
        dofs = np.empty(m, dtype=np.int64)
        for e in range(n_elem):
            for a in range(m):
                dofs[a] = reduced[3 * elems[e, a // 3] + a % 3]
            base = offset + e * m * m
            for a in range(m):
                r = dofs[a]
                if r < 0:
                    continue
                for b in range(m):
                    c = dofs[b]
                    if c < 0 or (upper and c < r):
                        continue
                    if fill:
                        p = cursor[r]
                        colbuf[p] = c
                        srcbuf[p] = base + a * m + b
                        cursor[r] = p + 1
                    else:
                        cursor[r + 1] += 1
        return
    for j in range(rows.shape[0]):
        r = reduced[rows[j]]
        c = reduced[cols[j]]
        if r < 0 or c < 0 or (upper and c < r):
            continue
        if fill:
            p = cursor[r]
            colbuf[p] = c
            srcbuf[p] = offset + j
            cursor[r] = p + 1
        else:
            cursor[r + 1] += 1


@njit(cache=True)
def pattern_csr(start, colbuf, srcbuf, n_entries):
    """(indptr, indices, pos) from the bucketed entries (row r's entries at
    start[r]:start[r + 1]): each row's unique columns in ascending order, and for every
    entry number its position in the CSR data (-1 for entries that were not kept)."""
    n = start.shape[0] - 1
    indptr = np.zeros(n + 1, dtype=np.int32)
    indices = np.empty(colbuf.shape[0], dtype=np.int32)
    pos = np.full(n_entries, -1, dtype=np.int64)
    seen = np.full(max(n, 1), -1, dtype=np.int64)  # last row in which a column was seen
    slot = np.empty(max(n, 1), dtype=np.int64)  # its position in that row
    w = 0
    for r in range(n):
        w0 = w
        for p in range(start[r], start[r + 1]):
            c = colbuf[p]
            if seen[c] != r:
                seen[c] = r
                indices[w] = c
                w += 1
        indices[w0:w].sort()
        for q in range(w0, w):
            slot[indices[q]] = q
        for p in range(start[r], start[r + 1]):
            pos[srcbuf[p]] = slot[colbuf[p]]
        indptr[r + 1] = w
    return indptr, indices[:w].copy(), pos


@njit(cache=True)
def pattern_locate(indptr, indices, rows, cols, reduced, upper, out):
    """out[j] = position of entry j in the CSR pattern, -1 when it is not kept (a
    support, or below the diagonal), -2 when the pattern lacks it. Returns the count of
    missing entries."""
    missing = 0
    for j in range(rows.shape[0]):
        r = reduced[rows[j]]
        c = reduced[cols[j]]
        out[j] = -1
        if r < 0 or c < 0 or (upper and c < r):
            continue
        lo = indptr[r]
        hi = indptr[r + 1]
        while lo < hi:  # binary search: the columns of a row are sorted
            mid = (lo + hi) // 2
            if indices[mid] < c:
                lo = mid + 1
            else:
                hi = mid
        if lo < indptr[r + 1] and indices[lo] == c:
            out[j] = lo
        else:
            out[j] = -2
            missing += 1
    return missing


@njit(cache=True)
def block_pattern(edges, rank, n_nodes, upper):
    """The pattern of the edges' 6x6 blocks built at node level, for a net whose free
    nodes (``rank`` >= 0: their order among the free nodes, DOFs 3 rank + 0..2) each
    have an edge: node adjacency, then every node's neighbours as 3x3 blocks. Returns
    (indptr, indices, target, diag): the CSR arrays (the same as ``pattern_csr`` gives for
    the edges' entries and the diagonal), the position of each of the 36 values of every
    edge (-1: dropped) and of every diagonal entry."""
    start, nbr = _adjacency(edges, rank, n_nodes)
    lo, hi = _unique_neighbours(start, nbr, n_nodes, upper)
    indptr, indices = _node_blocks(nbr, lo, hi, n_nodes, upper)
    diag = _block_diagonal(nbr, lo, indptr, n_nodes, upper)
    target = _edge_targets(edges, rank, nbr, lo, hi, indptr, upper)
    return indptr, indices, target, diag


@njit(cache=True)
def _adjacency(edges, rank, n_nodes):
    """(start, nbr): node i's neighbours through the edges between free nodes, itself
    first, at nbr[start[i]:start[i + 1]] (repeated where edges are)."""
    m = edges.shape[0]
    start = np.zeros(n_nodes + 1, dtype=np.int64)
    for e in range(m):
        a = rank[edges[e, 0]]
        b = rank[edges[e, 1]]
        if a >= 0 and b >= 0 and a != b:
            start[a + 1] += 1
            start[b + 1] += 1
    for i in range(n_nodes):
        start[i + 1] += start[i] + 1  # and the node itself
    cursor = start[:-1].copy()
    nbr = np.empty(start[n_nodes], dtype=np.int64)
    for i in range(n_nodes):
        nbr[cursor[i]] = i
        cursor[i] += 1
    for e in range(m):
        a = rank[edges[e, 0]]
        b = rank[edges[e, 1]]
        if a >= 0 and b >= 0 and a != b:
            nbr[cursor[a]] = b
            cursor[a] += 1
            nbr[cursor[b]] = a
            cursor[b] += 1
    return start, nbr


@njit(cache=True)
def _unique_neighbours(start, nbr, n_nodes, upper):
    """(lo, hi): node i's unique neighbours, sorted, at nbr[lo[i]:hi[i]] (``nbr``
    compacted in place; with ``upper`` from the first >= i)."""
    # unique, sorted neighbours per node (repeated edges: parallel cables)
    seen = np.full(max(n_nodes, 1), -1, dtype=np.int64)
    lo = np.empty(n_nodes, dtype=np.int64)  # first neighbour kept in the rows (upper: >= i)
    hi = np.empty(n_nodes, dtype=np.int64)
    w = 0
    for i in range(n_nodes):
        w0 = w
        for p in range(start[i], start[i + 1]):
            j = nbr[p]
            if seen[j] != i:
                seen[j] = i
                nbr[w] = j
                w += 1
        for p in range(w0 + 1, w):  # insertion sort: a node has few neighbours, and
            j = nbr[p]  # it compiles in a fraction of the time of ndarray.sort
            q = p - 1
            while q >= w0 and nbr[q] > j:
                nbr[q + 1] = nbr[q]
                q -= 1
            nbr[q + 1] = j
        lo[i] = w0
        hi[i] = w
        if upper:
            while nbr[lo[i]] < i:
                lo[i] += 1
    return lo, hi


@njit(cache=True)
def _node_blocks(nbr, lo, hi, n_nodes, upper):
    """(indptr, indices): the CSR arrays of every node's 3x3 blocks with its kept
    neighbours (with ``upper``, the diagonal block's upper triangle)."""
    n = 3 * n_nodes
    indptr = np.zeros(n + 1, dtype=np.int32)
    for i in range(n_nodes):
        width = 3 * (hi[i] - lo[i])
        for d in range(3):
            indptr[3 * i + d + 1] = indptr[3 * i + d] + width - (d if upper else 0)
    indices = np.empty(indptr[n], dtype=np.int32)
    for i in range(n_nodes):
        for d in range(3):
            q = indptr[3 * i + d]
            for p in range(lo[i], hi[i]):
                j = nbr[p]
                for d2 in range(3):
                    if upper and j == i and d2 < d:
                        continue
                    indices[q] = 3 * j + d2
                    q += 1
    return indptr, indices


@njit(cache=True)
def _block_diagonal(nbr, lo, indptr, n_nodes, upper):
    """The position of every diagonal entry in the CSR data."""
    n = 3 * n_nodes
    diag = np.empty(n, dtype=np.int64)
    for i in range(n_nodes):
        k = 0
        if not upper:
            while nbr[lo[i] + k] != i:
                k += 1
        for d in range(3):
            diag[3 * i + d] = indptr[3 * i + d] + (0 if upper else 3 * k + d)
    return diag


@njit(cache=True)
def _edge_targets(edges, rank, nbr, lo, hi, indptr, upper):
    """The position in the CSR data of each of the 36 values of every edge's block
    (-1: dropped, a support's or, with ``upper``, below the diagonal)."""
    m = edges.shape[0]
    target = np.full(36 * m, -1, dtype=np.int64)
    ends = np.empty(2, dtype=np.int64)
    for e in range(m):
        ends[0] = rank[edges[e, 0]]
        ends[1] = rank[edges[e, 1]]
        for s in range(2):
            i = ends[s]
            if i < 0:
                continue
            for t in range(2):
                j = ends[t]
                if j < 0 or (upper and j < i):
                    continue
                # k: place of j among node i's kept neighbours (binary search)
                a = lo[i]
                b = hi[i]
                while a < b:
                    mid = (a + b) // 2
                    if nbr[mid] < j:
                        a = mid + 1
                    else:
                        b = mid
                k = a - lo[i]
                for d in range(3):
                    row = indptr[3 * i + d]
                    for d2 in range(3):
                        if upper and j == i and d2 < d:
                            continue
                        if upper:
                            col = d2 - d if j == i else 3 - d + 3 * (k - 1) + d2
                        else:
                            col = 3 * k + d2
                        target[36 * e + 6 * (3 * s + d) + 3 * t + d2] = row + col
    return target
