"""The geometry of a periodic mosaic, shared by every demosaicing method.

A CFA repeats a (th, tw) tile, so every quantity a linear demosaicing step
needs (which channel a neighbour carries, the weights of an interpolation)
depends only on the pixel's *phase* (row mod th, column mod tw).  The
methods here are therefore written as per-phase *stencils*: for each phase,
a short list of (row offset, column offset, weight) applied to the strided
sub-image of that phase.  A normalised convolution evaluated this way is
exactly the normalised convolution (same numbers), but it touches only the
taps that carry samples and needs no division image.

Borders: an image is extended by :func:`extend`, a mirror that keeps the
CFA phase (each added pixel copies the nearest-to-mirror pixel of the same
phase), so that the extension is itself a valid mosaic and no method ever
shifts the image by a pixel at a border (ISETCam's ``mosaicConverter``
does, research/isetcam.md s. 4.3).  For a period-2 axis it is scipy's
``mode='mirror'`` (d c b | a b c d) exactly.

Written by hand: no library handles arbitrary periodic CFAs (colour-demosaicing
is Bayer-only, research/cfa-demosaic.md s. 4).
"""

from __future__ import annotations

__all__ = [
    "Mosaic",
    "Stencil",
    "geometry",
    "extend",
    "phase_view",
    "tent_radius",
    "tent_stencil",
    "diamond_radius",
    "diamond_stencil",
    "evaluate_stencil",
    "apply_stencils",
    "directional_samples",
    "tile_across",
]

import functools
import math
from dataclasses import dataclass

import numpy as np

from ..errors import CfaMitsubaError

#: The four directions an edge-directed step looks along: (row step, col step).
DIRECTIONS = ((0, 1), (1, 0), (1, 1), (1, -1))


@dataclass(frozen=True, eq=False)
class Mosaic:
    """A CFA tile reduced to what demosaicing needs.

    Attributes
    ----------
    pattern : (th, tw) array of filter names.
    channels : channel names, the output order.
    index : (th, tw) int, the channel index of each phase.
    """

    pattern: np.ndarray
    channels: tuple[str, ...]
    index: np.ndarray

    @property
    def tile_shape(self) -> tuple[int, int]:
        return int(self.index.shape[0]), int(self.index.shape[1])

    @property
    def densities(self) -> np.ndarray:
        """(C,) fraction of pixels carrying each channel."""
        return np.bincount(self.index.ravel(), minlength=len(self.channels)) / self.index.size

    def has(self, c: int, i: int, j: int) -> bool:
        th, tw = self.tile_shape
        return bool(self.index[i % th, j % tw] == c)

    def phases(self, c: int) -> list[tuple[int, int]]:
        """Phases (i, j) where channel ``c`` is sampled."""
        return [tuple(map(int, p)) for p in np.argwhere(self.index == c)]

    def gaps(self, c: int) -> list[tuple[int, int]]:
        """Phases (i, j) where channel ``c`` is missing."""
        return [tuple(map(int, p)) for p in np.argwhere(self.index != c)]

    def masks(self, shape) -> np.ndarray:
        """(C, H, W) bool: where each channel is sampled."""
        h, w = int(shape[0]), int(shape[1])
        th, tw = self.tile_shape
        idx = self.index[np.arange(h)[:, None] % th, np.arange(w)[None, :] % tw]
        return np.stack([idx == c for c in range(len(self.channels))])


@functools.lru_cache(maxsize=64)
def _geometry(pattern: tuple, channels: tuple) -> Mosaic:
    pat = np.array(pattern, dtype=str)
    lut = {c: i for i, c in enumerate(channels)}
    missing = sorted({str(p) for p in pat.ravel()} - set(lut))
    if missing:
        raise CfaMitsubaError(f"CFA tile has filter {missing[0]!r} that is not among its channels {channels}")
    unused = [c for c in channels if c not in set(pat.ravel().tolist())]
    if unused:
        raise CfaMitsubaError(f"CFA channel {unused[0]!r} has no sample in the tile")
    index = np.vectorize(lut.__getitem__, otypes=[np.intp])(pat)
    index.flags.writeable = False
    return Mosaic(pattern=pat, channels=tuple(channels), index=index)


def geometry(cfa) -> Mosaic:
    """The :class:`Mosaic` of a CFA object (anything with ``pattern`` and
    ``channels``), cached by tile."""
    pattern = np.asarray(cfa.pattern)
    if pattern.ndim != 2 or pattern.size == 0:
        raise CfaMitsubaError(f"CFA pattern must be a non-empty 2-D tile, got shape {pattern.shape}")
    return _geometry(tuple(map(tuple, pattern.tolist())), tuple(cfa.channels))


def tile_across(tile, width: int) -> np.ndarray:
    """A tile's (th, tw) array (a mask, the channel index) repeated across
    ``width`` columns: (th, width), its dtype kept, C-contiguous, so that a
    compiled loop over a row reads row ``r % th`` of it without a modulo
    per pixel."""
    tile = np.asarray(tile)
    reps = -(-width // tile.shape[1])
    return np.ascontiguousarray(np.tile(tile, (1, reps))[:, :width])


# --- borders ------------------------------------------------------------------


def _mirror_index(n: int, period: int, pad: int) -> np.ndarray:
    """Source index for each of ``n + 2 pad`` positions -pad..n+pad-1: the
    mirror image (no edge repeat), moved by less than a period to the
    nearest index of the same phase (index mod period) inside 0..n-1."""
    i = np.arange(-pad, n + pad)
    if n == 1:
        m = np.zeros_like(i)
    else:
        cycle = 2 * (n - 1)
        m = np.mod(i, cycle)
        m = np.where(m >= n, cycle - m, m)
    d = np.mod(i - m, period)  # 0..period-1: shift up to reach the same phase
    up, down = m + d, m + d - period
    use_up = (up <= n - 1) & ((d <= period - d) | (down < 0))
    out = np.where(use_up, up, down)
    return out


def extend(image: np.ndarray, mosaic: Mosaic, radius: int) -> tuple[np.ndarray, int, int]:
    """Extend a (H, W) or (H, W, ...) image by at least ``radius`` pixels on
    every side with the phase-preserving mirror.

    Returns ``(extended, ph, pw)``: the pads ph, pw are whole tiles, so the
    phase of extended pixel (r, c) is (r mod th, c mod tw).
    """
    th, tw = mosaic.tile_shape
    h, w = image.shape[:2]
    ph = th * math.ceil(max(radius, 0) / th)
    pw = tw * math.ceil(max(radius, 0) / tw)
    rows = _mirror_index(h, th, ph)
    cols = _mirror_index(w, tw, pw)
    # The mirror leaves the inside where it is: the image is copied in as a
    # block and only the border bands are gathered (the whole extended image
    # by one 2-D fancy index took 2-3x as long, the same values).
    out = np.empty((h + 2 * ph, w + 2 * pw, *image.shape[2:]), dtype=image.dtype)
    out[ph:ph + h, pw:pw + w] = image
    out[ph:ph + h, :pw] = image[:, cols[:pw]]
    out[ph:ph + h, pw + w:] = image[:, cols[pw + w:]]
    rows %= h  # an image smaller than its tile may mirror to -1 (the last row, as numpy indexes)
    out[:ph] = out[ph + rows[:ph]]
    out[ph + h:] = out[ph + rows[ph + h:]]
    return out, ph, pw


def phase_view(ext: np.ndarray, ph: int, pw: int, shape, tile, i: int, j: int, dr: int = 0, dc: int = 0):
    """The sub-image of phase (i, j) of the original (H, W) image, read from
    the extended array at offset (dr, dc)."""
    h, w = shape
    th, tw = tile
    return ext[ph + i + dr: ph + h + dr: th, pw + j + dc: pw + w + dc: tw]


# --- stencils -----------------------------------------------------------------


@dataclass(frozen=True)
class Stencil:
    """A per-phase linear estimate: ``sum(weights * x[p + offsets])``."""

    offsets: tuple[tuple[int, int], ...]
    weights: tuple[float, ...]

    @property
    def radius(self) -> int:
        return max((max(abs(a), abs(b)) for a, b in self.offsets), default=0)

    @property
    def second_moment(self) -> float:
        """sum w |q|^2 (pixels^2): twice the smoothing a quadratic sees."""
        return float(sum(w * (a * a + b * b) for (a, b), w in zip(self.offsets, self.weights)))


def _surrounds(points, strict: bool) -> bool:
    """Whether the origin lies in the convex hull of the integer ``points``
    (none of them the origin): inside or on its boundary, or, if ``strict``,
    in its interior (so not all points on one line)."""
    if not points:
        return False
    ang = np.sort(np.arctan2([p[0] for p in points], [p[1] for p in points]))
    gaps = np.diff(np.concatenate([ang, [ang[0] + 2 * np.pi]]))
    widest = float(gaps.max())
    if strict:
        return widest < np.pi - 1e-9
    return widest <= np.pi + 1e-9


def _window(mosaic: Mosaic, c: int, i: int, j: int, radius: int, norm: str):
    """Offsets within ``radius`` (Chebyshev for 'tent', L1 for 'diamond') of
    phase (i, j), other than (0, 0), where channel ``c`` is sampled."""
    out = []
    for dr in range(-radius, radius + 1):
        for dc in range(-radius, radius + 1):
            if (dr, dc) == (0, 0):
                continue
            if norm == "diamond" and abs(dr) + abs(dc) > radius:
                continue
            if mosaic.has(c, i + dr, j + dc):
                out.append((dr, dc))
    return out


def _smallest_radius(mosaic: Mosaic, c: int, phases, norm: str, strict: bool) -> int:
    th, tw = mosaic.tile_shape
    limit = 2 * (th + tw) + 2
    for r in range(1, limit + 1):
        if all(_surrounds(_window(mosaic, c, i, j, r, norm), strict) for i, j in phases):
            return r
    raise CfaMitsubaError(f"channel {mosaic.channels[c]!r} of the CFA has no surrounding samples")  # pragma: no cover


@functools.lru_cache(maxsize=256)
def tent_radius(mosaic: Mosaic, c: int) -> int:
    """Half-width of channel ``c``'s bilinear tent: the smallest r whose
    (2r+1)^2 window holds samples of ``c`` that surround every gap of ``c``
    (so the estimate interpolates, never extrapolates).  1 for every Bayer
    channel; 2 for the stripes' channels and for R and B of the Kodak
    RGBW tiles."""
    return _smallest_radius(mosaic, c, mosaic.gaps(c), "tent", strict=False)


@functools.lru_cache(maxsize=1024)
def tent_stencil(mosaic: Mosaic, c: int, i: int, j: int) -> Stencil:
    """Normalised separable-tent weights of channel ``c`` at gap phase (i, j).

    The tent of half-width r is w(d) = (r + 1 - |d|) / (r + 1) per axis
    (r = 1 is [1/2, 1, 1/2]); normalised convolution divides by the sum of
    the weights that land on samples of ``c``.
    """
    r = tent_radius(mosaic, c)
    offs = _window(mosaic, c, i, j, r, "tent")
    w = np.array([(r + 1 - abs(a)) * (r + 1 - abs(b)) for a, b in offs], dtype=np.float64)
    return Stencil(tuple(offs), tuple((w / w.sum()).tolist()))


@functools.lru_cache(maxsize=256)
def diamond_radius(mosaic: Mosaic, c: int) -> int:
    """L1 radius of channel ``c``'s own-neighbourhood average: the smallest R
    whose diamond holds other samples of ``c`` surrounding each sample of
    ``c`` in two dimensions.  2 for Bayer's R and B (the four axial samples
    two pixels away: Malvar-He-Cutler's Laplacian)."""
    return _smallest_radius(mosaic, c, mosaic.phases(c), "diamond", strict=True)


@functools.lru_cache(maxsize=1024)
def diamond_stencil(mosaic: Mosaic, c: int, i: int, j: int) -> Stencil:
    """Weights of the local average of channel ``c`` around its own sample
    at phase (i, j), the sample itself excluded: a diamond tent
    w(q) = R + 1 - |q|_1 over the other samples of ``c``, normalised."""
    r = diamond_radius(mosaic, c)
    offs = _window(mosaic, c, i, j, r, "diamond")
    w = np.array([r + 1 - abs(a) - abs(b) for a, b in offs], dtype=np.float64)
    keep = w > 0
    offs = [o for o, k in zip(offs, keep) if k]
    w = w[keep]
    return Stencil(tuple(offs), tuple((w / w.sum()).tolist()))


def evaluate_stencil(ext: np.ndarray, ph: int, pw: int, shape, tile, i: int, j: int, stencil: Stencil) -> np.ndarray:
    """The stencil's estimate on the sub-image of phase (i, j) (taps with
    equal weights are summed first, to save multiplications)."""
    groups: dict[float, list] = {}
    for off, w in zip(stencil.offsets, stencil.weights):
        groups.setdefault(w, []).append(off)
    acc = None
    for w, offs in groups.items():
        s = phase_view(ext, ph, pw, shape, tile, i, j, *offs[0]).copy()
        for off in offs[1:]:
            s += phase_view(ext, ph, pw, shape, tile, i, j, *off)
        if w != 1.0:
            s *= w
        acc = s if acc is None else np.add(acc, s, out=acc)
    if acc is None:
        acc = np.zeros_like(phase_view(ext, ph, pw, shape, tile, i, j))
    return acc


def apply_stencils(ext: np.ndarray, ph: int, pw: int, shape, tile, stencils: dict, out: np.ndarray) -> np.ndarray:
    """Evaluate per-phase stencils into ``out`` (H, W): for each phase
    (i, j) -> Stencil in ``stencils``, ``out[i::th, j::tw] = sum w ext[...]``."""
    for (i, j), st in stencils.items():
        out[i::tile[0], j::tile[1]] = evaluate_stencil(ext, ph, pw, shape, tile, i, j, st)
    return out


@functools.lru_cache(maxsize=1024)
def directional_samples(mosaic: Mosaic, c: int, i: int, j: int, limit: int):
    """For each of :data:`DIRECTIONS` in which channel ``c`` has a sample on
    both sides of phase (i, j) within ``limit`` steps: ``(direction, t_plus,
    t_minus)``, the step counts (t_plus > 0 > t_minus) of the nearest sample
    on each side."""
    out = []
    for d in DIRECTIONS:
        tp = next((t for t in range(1, limit + 1) if mosaic.has(c, i + t * d[0], j + t * d[1])), None)
        tm = next((-t for t in range(1, limit + 1) if mosaic.has(c, i - t * d[0], j - t * d[1])), None)
        if tp is not None and tm is not None:
            out.append((d, tp, tm))
    return tuple(out)
