"""Layouts: every distinct tile of an alphabet, once.

A layout is a (h, w) tile of letter indices 0..k-1, stored flat (row by
row) as uint8, and coded as the integer sum_i d_i k^i (pixel i = r w + c).
Two tiles that differ by a translation (a shifted phase of the same
periodic mosaic) or by a horizontal or vertical mirror are the same CFA
for the search: the **canonical** tile of a class is its smallest code.
Enumeration runs over all k^(h w) codes in chunks, drops tiles outside the
density bounds first (cheap), then keeps a tile only if no symmetry of it
has a smaller code; symmetries are tried one at a time on the survivors, so
most tiles are rejected after a few (the canonical fraction is about one
in h w x 4).  Tiles whose true period is a smaller tile that is searched
too are dropped (a 4x4 made of a repeated 2x2 is evaluated at 2x2).
"""

from __future__ import annotations

__all__ = ["symmetries", "canonical", "enumerate_layouts", "density_limits", "letter_counts", "tile_text",
           "raw_count", "CHUNK"]

import functools

import numpy as np

#: Raw codes per enumeration chunk (one chunk: about 40 MB of digits at 4x4).
CHUNK = 1 << 20


def raw_count(h: int, w: int, k: int) -> int:
    return int(k) ** (int(h) * int(w))


@functools.lru_cache(maxsize=64)
def symmetries(h: int, w: int, mirrors: bool = True) -> np.ndarray:
    """(G, h w) pixel maps of the symmetry group, identity first: tile
    ``t[perm]`` is the image of ``t``.  Translations, and with ``mirrors``
    the horizontal and vertical flips and both."""
    r, c = np.divmod(np.arange(h * w), w)
    flips = [(False, False)] + ([(True, False), (False, True), (True, True)] if mirrors else [])
    out = []
    for fr, fc in flips:
        rr = (h - 1 - r) if fr else r
        cc = (w - 1 - c) if fc else c
        for dr in range(h):
            for dc in range(w):
                out.append(((rr + dr) % h) * w + (cc + dc) % w)
    perms = np.unique(np.array(out), axis=0)
    ident = np.arange(h * w)
    rest = [p for p in perms if not np.array_equal(p, ident)]
    return np.array([ident, *rest], dtype=np.intp)


def _powers(n: int, k: int) -> np.ndarray:
    return (np.int64(k) ** np.arange(n, dtype=np.int64)).astype(np.int64)


def _encode(digits: np.ndarray, k: int) -> np.ndarray:
    return digits.astype(np.int64) @ _powers(digits.shape[1], k)


def canonical(layouts: np.ndarray, h: int, w: int, k: int, mirrors: bool = True) -> np.ndarray:
    """The canonical tile (smallest code over the symmetry group) of each of
    ``layouts`` (N, h w)."""
    layouts = np.atleast_2d(np.asarray(layouts, dtype=np.uint8))
    best = layouts.copy()
    best_code = _encode(best, k)
    for perm in symmetries(h, w, mirrors)[1:]:
        img = layouts[:, perm]
        code = _encode(img, k)
        better = code < best_code
        best[better], best_code[better] = img[better], code[better]
    return best


def letter_counts(layouts: np.ndarray, k: int) -> np.ndarray:
    """(N, k) pixels per letter."""
    return np.stack([(layouts == j).sum(axis=1) for j in range(k)], axis=1)


def density_limits(density: dict, alphabet, n: int) -> tuple[np.ndarray, np.ndarray]:
    """(min, max) pixels per letter of an n-pixel tile: every letter at least
    once unless its bounds say otherwise (a density of 0 allowed by a lower
    bound of 0)."""
    import math

    lo, hi = [], []
    for a in alphabet:
        d = density.get(a)
        lo.append(max(1, math.ceil(d[0] * n - 1e-9)) if d else 1)
        if d and d[0] == 0.0:
            lo[-1] = 0
        hi.append(int(d[1] * n + 1e-9) if d else n)
    return np.array(lo), np.array(hi)


def _smaller_period(digits: np.ndarray, h: int, w: int, sizes) -> np.ndarray:
    """True where a tile repeats with a smaller period that is searched too."""
    drop = np.zeros(len(digits), bool)
    grid = digits.reshape(-1, h, w)
    for ph in (d for d in range(1, h + 1) if h % d == 0):
        for pw in (d for d in range(1, w + 1) if w % d == 0):
            if (ph, pw) == (h, w) or (ph, pw) not in sizes:
                continue
            same = np.all(grid == np.roll(grid, ph, axis=1), axis=(1, 2)) & np.all(
                grid == np.roll(grid, pw, axis=2), axis=(1, 2))
            drop |= same
    return drop


def enumerate_chunk(index: int, h: int, w: int, k: int, lo, hi, mirrors: bool = True, sizes=()) -> np.ndarray:
    """The canonical layouts (M, h w) uint8 whose codes lie in chunk
    ``index`` ([index CHUNK, (index + 1) CHUNK)) and meet the bounds."""
    n = h * w
    total = raw_count(h, w, k)
    start, stop = index * CHUNK, min(total, (index + 1) * CHUNK)
    codes = np.arange(start, stop, dtype=np.int64)
    digits = ((codes[:, None] // _powers(n, k)[None, :]) % k).astype(np.uint8)
    counts = letter_counts(digits, k)
    ok = np.all((counts >= lo) & (counts <= hi), axis=1)
    digits, codes = digits[ok], codes[ok]
    for perm in symmetries(h, w, mirrors)[1:]:
        if not len(codes):
            break
        keep = _encode(digits[:, perm], k) >= codes
        digits, codes = digits[keep], codes[keep]
    if sizes:
        digits = digits[~_smaller_period(digits, h, w, set(sizes))]
    return digits


def n_chunks(h: int, w: int, k: int) -> int:
    return -(-raw_count(h, w, k) // CHUNK)


def enumerate_layouts(h: int, w: int, k: int, lo, hi, mirrors: bool = True, sizes=()) -> np.ndarray:
    """Every canonical layout of an h x w tile of k letters within the
    per-letter pixel bounds ``lo``, ``hi`` (arrays of k)."""
    parts = [enumerate_chunk(i, h, w, k, lo, hi, mirrors, sizes) for i in range(n_chunks(h, w, k))]
    return np.concatenate(parts) if parts else np.zeros((0, h * w), np.uint8)


def tile_text(layout, h: int, w: int, alphabet) -> str:
    """A layout as ``"G R / B G"``."""
    d = np.asarray(layout).reshape(h, w)
    return " / ".join(" ".join(alphabet[int(x)] for x in row) for row in d)
