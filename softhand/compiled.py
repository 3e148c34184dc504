"""Compiled helpers for the per-step kernels of the envs and sensors: numpy's reductions, bit for
bit.

An env step's Python is many small computations on a few dozen numbers (18 regions, 6 motors,
10 contact slots), where numpy's per-call overhead (about a microsecond each) costs more than the
arithmetic. The per-step code therefore runs in numba kernels (loops over the worlds, one world in
the single env); to keep every result equal to the numpy code it replaced, a kernel sums as numpy
does: `pairwise_sum` is numpy's pairwise summation (``numpy/_core/src/umath/loops_utils.h.src``:
a plain loop below 8 entries, 8 interleaved partial sums up to 128, halves above), which
``ndarray.sum`` uses along a reduced axis.

This module imports nothing from the stages, so each of them may use it.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["count_above", "interp", "pairwise_sum", "row_sums", "within"]

_BLOCK = 128  # numpy's PW_BLOCKSIZE


@njit(cache=True)
def pairwise_sum(a: np.ndarray) -> float:
    """Sum of the 1-D float array ``a`` in numpy's order (``a.sum()`` bit for bit)."""
    n = a.size
    if n < 8:
        res = 0.0
        for i in range(n):
            res += a[i]
        return res
    if n <= _BLOCK:
        r0, r1, r2, r3 = a[0], a[1], a[2], a[3]
        r4, r5, r6, r7 = a[4], a[5], a[6], a[7]
        i = 8
        while i < n - n % 8:
            r0 += a[i]
            r1 += a[i + 1]
            r2 += a[i + 2]
            r3 += a[i + 3]
            r4 += a[i + 4]
            r5 += a[i + 5]
            r6 += a[i + 6]
            r7 += a[i + 7]
            i += 8
        res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
        while i < n:
            res += a[i]
            i += 1
        return res
    half = n // 2
    half -= half % 8
    return pairwise_sum(a[:half]) + pairwise_sum(a[half:])


@njit(cache=True)
def within(a: np.ndarray, lo: float, hi: float) -> bool:
    """Whether every entry of the 1-D array ``a`` is in [lo, hi] (False for a NaN), without
    numpy's two reductions."""
    for x in a:  # noqa: SIM110 (numba compiles the loop, not a generator in all())
        if not (lo <= x <= hi):
            return False
    return True


@njit(cache=True)
def count_above(a: np.ndarray, lo: float) -> int:
    """How many entries of the 1-D array ``a`` are above ``lo`` (``int((a > lo).sum())``)."""
    n = 0
    for x in a:
        n += x > lo
    return n


@njit(cache=True)
def row_sums(a: np.ndarray) -> np.ndarray:
    """``a.sum(axis=1)`` of a 2-D float array, bit for bit."""
    out = np.empty(a.shape[0])
    for i in range(a.shape[0]):
        out[i] = pairwise_sum(a[i])
    return out


@njit(cache=True)
def interp(x: float, xp: np.ndarray, fp: np.ndarray) -> float:
    """``np.interp(x, xp, fp)`` of one number, bit for bit (numpy's ``arr_interp``: the last
    knot at or below ``x``, where numpy's search with a guess lands too, then its slope formula;
    the ends' values outside). Numba's own np.interp gives the same numbers but takes seconds
    to compile; this takes a fraction of one."""
    n = xp.size
    if x != x:
        return x
    if x < xp[0]:
        return fp[0]
    if x > xp[n - 1]:
        return fp[n - 1]
    lo, hi = 0, n  # the first knot above x, by bisection
    while lo < hi:
        mid = lo + ((hi - lo) >> 1)
        if x >= xp[mid]:
            lo = mid + 1
        else:
            hi = mid
    j = lo - 1
    if j == n - 1 or xp[j] == x:
        return fp[j]
    slope = (fp[j + 1] - fp[j]) / (xp[j + 1] - xp[j])
    out = slope * (x - xp[j]) + fp[j]
    if out != out:  # numpy: from the other end, then the flat value
        out = slope * (x - xp[j + 1]) + fp[j + 1]
        if out != out and fp[j] == fp[j + 1]:
            out = fp[j]
    return out
