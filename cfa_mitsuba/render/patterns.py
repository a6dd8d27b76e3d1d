"""Procedural texture content: weight maps drawn in numpy.

Everything here is deterministic (explicit seeds) and works in texels:
arrays are (rows, cols), row 0 at the top of the printed surface as a
viewer reads it.  A :class:`Canvas` holds a (H, W, K) stack of palette
weights and paints coverage maps onto it, alpha-compositing like ink on
paper (the weights keep summing to 1).  Coverages are fractions of a texel's
area in [0, 1]: analytic patterns (star, rings, chirps) are computed on a
4 x 4 sub-texel grid and averaged, so a texel holds the true area mix of
the inks, never a point sample aliased at the texel scale.

The primitives: a 5 x 7 pixel font (:func:`text_mask`), bar groups of the
USAF-1951 kind (:func:`bar_group`), a Siemens star (:func:`siemens_star`), a
zone plate of rings (:func:`zone_rings`), a linear chirp of stripes
(:func:`chirp_stripes`), fur strands (:func:`fur_strands`) and a plain
weave (:func:`plain_weave`).
"""

from __future__ import annotations

__all__ = ["Canvas", "text_mask", "bar_group", "siemens_star", "zone_rings", "chirp_stripes", "fur_strands",
           "plain_weave", "smooth_noise"]

import numpy as np

#: Sub-texel samples per axis for analytic coverage.
SUPERSAMPLE = 4

# A 5 x 7 pixel font (rows top to bottom, '1' = ink): capitals, digits and a
# little punctuation.
_FONT = {
    "A": "01110 10001 10001 11111 10001 10001 10001", "B": "11110 10001 10001 11110 10001 10001 11110",
    "C": "01110 10001 10000 10000 10000 10001 01110", "D": "11100 10010 10001 10001 10001 10010 11100",
    "E": "11111 10000 10000 11110 10000 10000 11111", "F": "11111 10000 10000 11110 10000 10000 10000",
    "G": "01110 10001 10000 10111 10001 10001 01111", "H": "10001 10001 10001 11111 10001 10001 10001",
    "I": "01110 00100 00100 00100 00100 00100 01110", "J": "00111 00010 00010 00010 00010 10010 01100",
    "K": "10001 10010 10100 11000 10100 10010 10001", "L": "10000 10000 10000 10000 10000 10000 11111",
    "M": "10001 11011 10101 10101 10001 10001 10001", "N": "10001 10001 11001 10101 10011 10001 10001",
    "O": "01110 10001 10001 10001 10001 10001 01110", "P": "11110 10001 10001 11110 10000 10000 10000",
    "Q": "01110 10001 10001 10001 10101 10010 01101", "R": "11110 10001 10001 11110 10100 10010 10001",
    "S": "01111 10000 10000 01110 00001 00001 11110", "T": "11111 00100 00100 00100 00100 00100 00100",
    "U": "10001 10001 10001 10001 10001 10001 01110", "V": "10001 10001 10001 10001 10001 01010 00100",
    "W": "10001 10001 10001 10101 10101 10101 01010", "X": "10001 10001 01010 00100 01010 10001 10001",
    "Y": "10001 10001 01010 00100 00100 00100 00100", "Z": "11111 00001 00010 00100 01000 10000 11111",
    "0": "01110 10001 10011 10101 11001 10001 01110", "1": "00100 01100 00100 00100 00100 00100 01110",
    "2": "01110 10001 00001 00010 00100 01000 11111", "3": "11111 00010 00100 00010 00001 10001 01110",
    "4": "00010 00110 01010 10010 11111 00010 00010", "5": "11111 10000 11110 00001 00001 10001 01110",
    "6": "00110 01000 10000 11110 10001 10001 01110", "7": "11111 00001 00010 00100 01000 01000 01000",
    "8": "01110 10001 10001 01110 10001 10001 01110", "9": "01110 10001 10001 01111 00001 00010 01100",
    " ": "00000 00000 00000 00000 00000 00000 00000", ".": "00000 00000 00000 00000 00000 01100 01100",
    "-": "00000 00000 00000 11111 00000 00000 00000", "/": "00001 00010 00010 00100 01000 01000 10000",
    ":": "00000 01100 01100 00000 01100 01100 00000", ",": "00000 00000 00000 00000 01100 00100 01000",
}
_GLYPHS = {c: np.array([[ch == "1" for ch in row] for row in rows.split()], dtype=bool) for c, rows in _FONT.items()}


class Canvas:
    """A (H, W, K) weight stack, initially all palette entry ``background``."""

    def __init__(self, height: int, width: int, n_inks: int, background: int = 0):
        self.weights = np.zeros((int(height), int(width), int(n_inks)), dtype=np.float32)
        self.weights[..., background] = 1.0

    @property
    def shape(self) -> tuple[int, int]:
        return self.weights.shape[:2]

    def paint(self, coverage, ink: int, top: int = 0, left: int = 0) -> None:
        """Composite ``coverage`` (h, w) in [0, 1] of palette entry ``ink``
        with its top-left texel at (top, left); clipped to the canvas."""
        cov = np.asarray(coverage, dtype=np.float32)
        h, w = self.shape
        r0, c0 = max(top, 0), max(left, 0)
        r1, c1 = min(top + cov.shape[0], h), min(left + cov.shape[1], w)
        if r1 <= r0 or c1 <= c0:
            return
        cov = np.clip(cov[r0 - top:r1 - top, c0 - left:c1 - left], 0.0, 1.0)[..., None]
        region = self.weights[r0:r1, c0:c1]
        region *= 1.0 - cov
        region[..., ink] += cov[..., 0]


def text_mask(text: str, scale: int = 1) -> np.ndarray:
    """Coverage (7 s, 6 s n - s) of ``text`` in the 5 x 7 font, each font
    pixel ``scale`` x ``scale`` texels, one blank font column between
    letters.  Unknown characters print as blanks."""
    s = int(scale)
    cols = []
    for i, ch in enumerate(text.upper()):
        if i:
            cols.append(np.zeros((7, 1), dtype=bool))
        cols.append(_GLYPHS.get(ch, _GLYPHS[" "]))
    glyphs = np.concatenate(cols, axis=1) if cols else np.zeros((7, 0), dtype=bool)
    return np.kron(glyphs, np.ones((s, s), dtype=bool)).astype(np.float32)


def bar_group(bar: int, n_bars: int = 3, length_bars: int = 5, vertical: bool = True) -> np.ndarray:
    """Coverage of ``n_bars`` bars ``bar`` texels wide, period 2 ``bar``,
    ``length_bars`` x ``bar`` long (USAF 1951: 3 bars of length 5 widths);
    vertical bars (varying along columns) or horizontal ones."""
    b = int(bar)
    width = (2 * n_bars - 1) * b
    profile = ((np.arange(width) // b) % 2 == 0).astype(np.float32)
    out = np.tile(profile, (length_bars * b, 1))
    return out if vertical else out.T.copy()


def _subgrid(height: int, width: int):
    """Sub-texel sample coordinates (y, x) in texels, centred on the array,
    shape (H * S, W * S)."""
    s = SUPERSAMPLE
    y = (np.arange(height * s) + 0.5) / s - height / 2
    x = (np.arange(width * s) + 0.5) / s - width / 2
    return np.meshgrid(y, x, indexing="ij")


def _area(mask: np.ndarray) -> np.ndarray:
    """Mean of each S x S block of a sub-texel mask: texel coverage."""
    s = SUPERSAMPLE
    h, w = mask.shape[0] // s, mask.shape[1] // s
    return mask.reshape(h, s, w, s).mean(axis=(1, 3)).astype(np.float32)


def siemens_star(diameter: int, spokes: int = 36) -> np.ndarray:
    """Coverage of a Siemens star of ``spokes`` dark sectors in a disc of
    ``diameter`` texels (frequency rising towards the centre, every angle)."""
    y, x = _subgrid(diameter, diameter)
    r, theta = np.hypot(y, x), np.arctan2(y, x)
    return _area((np.sin(spokes * theta) > 0) & (r <= diameter / 2))


def zone_rings(diameter: int, max_cycles_per_texel: float) -> np.ndarray:
    """Coverage of a zone plate: rings cos(pi k r^2) > 0 in a disc of
    ``diameter`` texels, the local frequency k r rising linearly from 0 at
    the centre to ``max_cycles_per_texel`` at the rim."""
    y, x = _subgrid(diameter, diameter)
    r = np.hypot(y, x)
    k = max_cycles_per_texel / (diameter / 2)
    return _area((np.cos(np.pi * k * r * r) > 0) & (r <= diameter / 2))


def chirp_stripes(height: int, width: int, start_period: float, end_period: float) -> np.ndarray:
    """Coverage of vertical stripes whose period (texels) changes linearly in
    frequency from ``start_period`` at the left to ``end_period`` at the
    right: half of each period inked."""
    y, x = _subgrid(height, width)
    u = (x + width / 2) / width  # 0 .. 1
    f0, f1 = 1.0 / start_period, 1.0 / end_period
    phase = width * (f0 * u + 0.5 * (f1 - f0) * u * u)  # cycles
    return _area(np.cos(2 * np.pi * phase) > 0)


def chirp_grating(height: int, width: int, start_period: float, end_period: float, angle_deg: float = 0.0):
    """Coverage of straight stripes whose normal points ``angle_deg`` from
    the columns' direction (0: vertical stripes, 90: horizontal, 45 and -45:
    diagonal), the period (texels) running linearly in frequency from
    ``start_period`` to ``end_period`` along that normal across the patch:
    half of each period inked."""
    y, x = _subgrid(height, width)
    a = np.radians(angle_deg)
    s = x * np.cos(a) - y * np.sin(a)
    half = 0.5 * (abs(width * np.cos(a)) + abs(height * np.sin(a)))
    u = (s + half) / (2 * half)  # 0 .. 1 along the normal
    f0, f1 = 1.0 / start_period, 1.0 / end_period
    phase = 2 * half * (f0 * u + 0.5 * (f1 - f0) * u * u)  # cycles
    return _area(np.cos(2 * np.pi * phase) > 0)


def smooth_noise(shape, scale: float, seed: int) -> np.ndarray:
    """Tileable Gaussian-filtered white noise, scaled to [0, 1]; ``scale``
    is the filter's standard deviation in texels (the blotch size)."""
    rng = np.random.default_rng(seed)
    h, w = shape
    white = rng.standard_normal((h, w))
    fy, fx = np.fft.fftfreq(h)[:, None], np.fft.fftfreq(w)[None, :]
    g = np.exp(-2 * (np.pi * scale) ** 2 * (fy ** 2 + fx ** 2))
    n = np.real(np.fft.ifft2(np.fft.fft2(white) * g))
    return ((n - n.min()) / (n.max() - n.min())).astype(np.float32)


def fur_strands(size: int, n_strands: int, length: tuple[float, float], angle_deg: float, seed: int,
                density=None, width: int = 1, lane: int = 0) -> np.ndarray:
    """Count of hair strands per texel on a tileable ``size`` x ``size``
    tile: straight strands ``width`` texels wide, lengths uniform in ``length``
    (texels), running along the rows' direction (down the tile) within
    +-``angle_deg``, start points drawn with probability ``density`` (a
    (size, size) map; uniform if None).  ``lane`` > 0 combs the strands:
    each start column is moved down to a multiple of ``lane``, so that
    strands lie in parallel lanes ``lane`` texels apart."""
    rng = np.random.default_rng(seed)
    if density is None:
        starts = rng.integers(0, size, size=(n_strands, 2))
    else:
        p = np.asarray(density, dtype=np.float64).ravel()
        idx = rng.choice(p.size, size=n_strands, p=p / p.sum())
        starts = np.stack(np.unravel_index(idx, (size, size)), axis=1)
    if lane:
        starts[:, 1] = (starts[:, 1] // lane) * lane
    lengths = rng.uniform(length[0], length[1], n_strands)
    angle = np.radians(rng.uniform(-angle_deg, angle_deg, n_strands))
    steps = int(np.ceil(length[1])) * 2
    t = np.linspace(0.0, 1.0, steps)[None, :] * lengths[:, None]
    rows = np.floor(starts[:, :1] + t * np.cos(angle)[:, None]).astype(np.int64) % size
    cols = np.floor(starts[:, 1:] + t * np.sin(angle)[:, None]).astype(np.int64) % size
    # One count per strand per texel, however many of its points fall there:
    # a straight strand visits each texel in one run of consecutive points.
    idx = rows * size + cols
    keep = np.ones(idx.shape, dtype=bool)
    keep[:, 1:] = idx[:, 1:] != idx[:, :-1]
    counts = np.bincount(idx[keep], minlength=size * size).reshape(size, size)
    return sum(np.roll(counts, k, axis=1) for k in range(int(width))).astype(np.float32)


def plain_weave(threads_per_tile: int, thread: int, colours_warp, colours_weft) -> tuple[np.ndarray, np.ndarray]:
    """A plain weave: ``threads_per_tile`` warp (vertical) and weft
    (horizontal) threads of ``thread`` texels, each crossing showing the
    thread on top (warp where row + column thread index is even).  Returns
    the colour index of the visible thread per texel (from the per-thread
    lists ``colours_warp``, ``colours_weft``) and the shading (0 inside a
    thread, 1 on its edge texels: the groove between threads)."""
    n, t = int(threads_per_tile), int(thread)
    idx = np.arange(n * t) // t
    ti, tj = np.meshgrid(idx, idx, indexing="ij")  # weft thread (row), warp thread (column)
    warp_on_top = (ti + tj) % 2 == 0
    cw, cf = np.asarray(colours_warp), np.asarray(colours_weft)
    colour = np.where(warp_on_top, cw[tj], cf[ti])
    pos = np.arange(n * t) % t
    edge_c, edge_r = (pos == 0) | (pos == t - 1), (pos == 0) | (pos == t - 1)
    groove = np.where(warp_on_top, edge_c[None, :], edge_r[:, None])
    return colour.astype(np.int64), groove.astype(np.float32)
