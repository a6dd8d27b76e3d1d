"""Compiled per-pixel loops for the colour formulas a study evaluates
hundreds of millions of times: CIE 1976 L*a*b*, CIEDE2000 and 8-bit sRGB
codes.

Written by hand (with Numba) for speed only: scikit-image's
``deltaE_ciede2000`` and colour-science's ``XYZ_to_Lab`` compute the same
numbers but as a chain of whole-array numpy operations, each writing a
temporary the size of the image; one pass per pixel is 2.3x (CIEDE2000) and
more than 1.5x (CIELAB) faster on a camera image (benchmarks/bench_colour.py).
Both agree with those libraries to 1e-12 (tests/test_colour_kernels.py, with
Sharma's 34 published pairs); :mod:`cfa_mitsuba.colorimetry` is the public
interface and calls these.

The loops compile on first use (about a second) and are cached on disk
beside this module by Numba (``cache=True``), so later processes load them.
"""

from __future__ import annotations

__all__ = ["ciede2000", "lab_cie", "opponent_lab", "realisable_first_pass", "srgb8_codes"]

import math

import numba as nb
import numpy as np

_P25_7 = 25.0 ** 7
_TWO_PI = 2.0 * math.pi
_D30 = math.radians(30.0)
# T's four cosines by the multiple-angle identities from one cos/sin pair:
# cos(h - 30), cos(2h), cos(3h + 6), cos(4h - 63) (degrees)
_C30, _S30 = math.cos(math.radians(30.0)), math.sin(math.radians(30.0))
_C6, _S6 = math.cos(math.radians(6.0)), math.sin(math.radians(6.0))
_C63, _S63 = math.cos(math.radians(63.0)), math.sin(math.radians(63.0))
# CIE 015: f(t) = t^(1/3) above (24/116)^3, else (841/108) t + 16/116
_LAB_EPS = (24.0 / 116.0) ** 3
_LAB_KAPPA = 841.0 / 108.0


@nb.njit(inline="always")
def _pow7(x):
    x2 = x * x
    return x2 * x2 * x2 * x


@nb.njit(inline="always")
def _primed(a1, b1, a2, b2):
    """a' = (1 + G) a, G from the mean chroma, and C' (Sharma eqs 2-3, 6): (a1', a2', C1', C2')."""
    c7 = _pow7(0.5 * (math.sqrt(a1 * a1 + b1 * b1) + math.sqrt(a2 * a2 + b2 * b2)))
    scale = 1.0 + 0.5 * (1.0 - math.sqrt(c7 / (c7 + _P25_7)))
    x1 = a1 * scale
    x2 = a2 * scale
    return x1, x2, math.sqrt(x1 * x1 + b1 * b1), math.sqrt(x2 * x2 + b2 * b2)


@nb.njit(inline="always")
def _from_hue_terms(L1, L2, C1, C2, sin_half, c, s, hbar):
    """CIEDE2000 from the lightnesses, the chromas C', sin(dh'/2), cos and
    sin of the mean hue and the mean hue itself (radians in [0, 2 pi)):
    Sharma eqs 8-9 and 12-22."""
    # lightness and chroma terms (eqs 8-9, 17-18)
    t = (0.5 * (L1 + L2) - 50.0) ** 2
    l_term = (L2 - L1) / (1.0 + 0.015 * t / math.sqrt(20.0 + t))
    cbar = 0.5 * (C1 + C2)
    c_term = (C2 - C1) / (1.0 + 0.045 * cbar)
    # T by the multiple-angle identities from one cos/sin pair (eq. 15)
    c2 = 2.0 * c * c - 1.0
    s2 = 2.0 * s * c
    c3 = c * (4.0 * c * c - 3.0)
    s3 = s * (3.0 - 4.0 * s * s)
    c4 = 2.0 * c2 * c2 - 1.0
    s4 = 2.0 * s2 * c2
    T = (1.0 - 0.17 * (c * _C30 + s * _S30) + 0.24 * c2
         + 0.32 * (c3 * _C6 - s3 * _S6) - 0.20 * (c4 * _C63 + s4 * _S63))
    h_term = 2.0 * math.sqrt(C1 * C2) * sin_half / (1.0 + 0.015 * cbar * T)
    # rotation term (eqs 19-22)
    c7 = _pow7(cbar)
    z = (math.degrees(hbar) - 275.0) / 25.0
    r_term = -math.sin(2.0 * _D30 * math.exp(-z * z)) * 2.0 * math.sqrt(c7 / (c7 + _P25_7)) * c_term * h_term
    e = l_term * l_term + c_term * c_term + h_term * h_term + r_term
    return 0.0 if e < 0.0 else math.sqrt(e)  # NaN stays NaN


@nb.njit(inline="always")
def _de00(L1, a1, b1, L2, a2, b2):
    """CIEDE2000 of one pair (Sharma et al. 2005, eqs 1-22), the hue terms by angles."""
    x1, x2, C1, C2 = _primed(a1, b1, a2, b2)
    h1 = math.atan2(b1, x1)
    if h1 < 0.0:
        h1 += _TWO_PI
    h2 = math.atan2(b2, x2)
    if h2 < 0.0:
        h2 += _TWO_PI
    # hue difference and mean hue (eqs 10-11, 14); zero chroma: dh = 0, mean = sum
    hd = h2 - h1
    hbar = h1 + h2
    if C1 * C2 == 0.0:
        dh = 0.0
    else:
        dh = hd
        if hd > math.pi:
            dh -= _TWO_PI
        elif hd < -math.pi:
            dh += _TWO_PI
        if abs(hd) > math.pi:
            hbar += _TWO_PI if hbar < _TWO_PI else -_TWO_PI
        hbar *= 0.5
    return _from_hue_terms(L1, L2, C1, C2, math.sin(0.5 * dh), math.cos(hbar), math.sin(hbar), hbar)


@nb.njit(inline="always")
def _de00_by_vectors(L1, a1, b1, L2, a2, b2):
    """CIEDE2000 of one pair, the hue terms from the (a', b') vectors instead
    of their angles: cos and sin of the mean hue are the unit bisector's
    components (the mean on the shorter arc, Sharma's eq. 14 and its wrap),
    sin(dh/2) follows from the cross and dot products by the half-angle
    formulas (dh wrapped to [-pi, pi], Sharma's eq. 10), and one atan2 of
    the bisector gives the mean hue for the rotation term.  Where that
    construction is degenerate (a zero chroma, hues equal or opposite) or
    loses digits (hues within 1.15 degrees of opposite) it returns
    :func:`_de00`'s value; elsewhere the two agree to about 1e-13 relative
    (tests/test_colour_kernels.py), with two fewer trigonometric calls per
    pixel (21 % faster, measured)."""
    x1, x2, C1, C2 = _primed(a1, b1, a2, b2)
    cc = C1 * C2
    cross = x1 * b2 - b1 * x2  # C1 C2 sin(h2 - h1)
    dot = x1 * x2 + b1 * b2  # C1 C2 cos(h2 - h1)
    ux = x1 * C2 + x2 * C1  # C1 C2 (u1 + u2), u the unit hue vectors: along the mean hue
    uy = b1 * C2 + b2 * C1
    nrm = math.sqrt(ux * ux + uy * uy)
    if cc == 0.0 or cross == 0.0 or nrm <= 1e-2 * cc:  # |u1 + u2| = 2 cos(dh / 2): hues within 1.15 deg of opposite
        return _de00(L1, a1, b1, L2, a2, b2)
    sn = cross / cc
    cs = dot / cc
    # sin(dh / 2), of the sign of dh = the sign of sin(dh)
    if cs >= 0.0:
        half = sn / math.sqrt(2.0 * (1.0 + cs))
    else:
        half = math.sqrt(0.5 * (1.0 - cs))
        if sn < 0.0:
            half = -half
    hbar = math.atan2(uy, ux)
    if hbar < 0.0:
        hbar += _TWO_PI
    return _from_hue_terms(L1, L2, C1, C2, half, ux / nrm, uy / nrm, hbar)


@nb.njit(cache=True, nogil=True, error_model="numpy")
def _ciede2000_rows(lab1, lab2, out):  # pragma: no cover - compiled
    for i in range(out.shape[0]):
        out[i] = _de00_by_vectors(lab1[i, 0], lab1[i, 1], lab1[i, 2], lab2[i, 0], lab2[i, 1], lab2[i, 2])


@nb.njit(inline="always")
def _lab_f(t):
    return t ** (1.0 / 3.0) if t > _LAB_EPS else _LAB_KAPPA * t + 16.0 / 116.0


@nb.njit(inline="always")
def _lab_of(x, y, z, white):
    """L*, a*, b* of one XYZ relative to ``white``."""
    fx = _lab_f(x / white[0])
    fy = _lab_f(y / white[1])
    fz = _lab_f(z / white[2])
    return 116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)


@nb.njit(cache=True, nogil=True, error_model="numpy")
def _lab_rows(xyz, white, out):  # pragma: no cover - compiled
    for i in range(out.shape[0]):
        out[i, 0], out[i, 1], out[i, 2] = _lab_of(xyz[i, 0], xyz[i, 1], xyz[i, 2], white)


@nb.njit(cache=True, nogil=True, error_model="numpy")
def _opponent_lab_map(planes, base, to_xyz, white, out):  # pragma: no cover - compiled
    for r in range(out.shape[0]):
        for c in range(out.shape[1]):
            o0 = planes[0, r, c]
            o1 = planes[1, r, c]
            o2 = planes[2, r, c]
            if base is not None:  # pruned at compile time when there is none
                o0 = base[0, r, c] + o0
                o1 = base[1, r, c] + o1
                o2 = base[2, r, c] + o2
            out[r, c, 0], out[r, c, 1], out[r, c, 2] = _lab_of(
                to_xyz[0, 0] * o0 + to_xyz[0, 1] * o1 + to_xyz[0, 2] * o2,
                to_xyz[1, 0] * o0 + to_xyz[1, 1] * o1 + to_xyz[1, 2] * o2,
                to_xyz[2, 0] * o0 + to_xyz[2, 1] * o1 + to_xyz[2, 2] * o2, white)


def _rows(a: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(a, dtype=np.float64).reshape(-1, 3)


def ciede2000(lab1, lab2) -> np.ndarray:
    """CIEDE2000 (kL = kC = kH = 1) between two broadcastable (..., 3) CIELAB
    arrays: shape ``broadcast(...)``, float64.

    Sharma, Wu & Dalal, "The CIEDE2000 color-difference formula:
    implementation notes, supplementary test data, and mathematical
    observations", Color Res. Appl. 30 (2005) 21-30, eqs 1-22; the
    zero-chroma conventions are theirs (and scikit-image's).
    """
    a, b = np.broadcast_arrays(np.asarray(lab1, dtype=np.float64), np.asarray(lab2, dtype=np.float64))
    out = np.empty(a.shape[:-1], dtype=np.float64)
    if out.size:
        _ciede2000_rows(_rows(a), _rows(b), out.reshape(-1))
    return out


def lab_cie(xyz, white) -> np.ndarray:
    """CIE 1976 L*a*b* (CIE 015:2018 eqs 8.1-8.3, exact 216/24389 and
    24389/27 in their (24/116)^3 and 841/108 form) of (..., 3) XYZ relative to
    ``white`` (3,) on the same scale."""
    a = np.asarray(xyz, dtype=np.float64)
    out = np.empty(a.shape, dtype=np.float64)
    if out.size:
        _lab_rows(_rows(a), np.ascontiguousarray(white, dtype=np.float64), out.reshape(-1, 3))
    return out


def opponent_lab(planes, to_xyz, white, base=None) -> np.ndarray:
    """(H, W, 3) CIELAB of (3, H, W) opponent planes: XYZ by the (3, 3)
    matrix ``to_xyz``, then :func:`lab_cie` relative to ``white``.  One pass
    (no (H, W, 3) XYZ in between); a separate loop from :func:`ciede2000`
    because the two fused into one ran slower (measured).

    ``base`` (optional, (3, H, W) float64): the planes are ``base + planes``
    (``planes`` then float32 or float64), added in the same pass with
    numpy's promotion (the same bits as ``opponent_lab(base + planes, ...)``,
    without the (3, H, W) sum in memory)."""
    planes = np.asarray(planes)
    if planes.dtype != np.float32 or base is None:
        planes = np.asarray(planes, dtype=np.float64)
    if base is not None:
        base = np.asarray(base, dtype=np.float64)
        if base.shape != planes.shape:
            raise ValueError(f"opponent_lab: base {base.shape} and planes {planes.shape} differ")
    out = np.empty(planes.shape[1:] + (3,), dtype=np.float64)
    if out.size:
        _opponent_lab_map(planes, base, np.ascontiguousarray(to_xyz, dtype=np.float64),
                          np.ascontiguousarray(white, dtype=np.float64), out)
    return out


_SRGB8_BINS = 8192
_SRGB8_TABLES: dict = {}


def _srgb8_tables(encode):
    """(thresholds (255,), first code per bin (BINS + 1,)) for the sRGB
    encoding ``encode`` (linear 0..1 -> encoded 0..1; the project passes
    :func:`cfa_mitsuba.colorimetry.linear_to_srgb`): threshold k - 1 is the
    smallest float64 v in [0, 1] whose code round(255 x encode(v)) (rounding
    half to even) is at least k, found by bisection over the floats' bit
    patterns; bin b starts at v = b / BINS."""
    if encode not in _SRGB8_TABLES:
        def code(v):
            return np.round(255.0 * encode(v))

        k = np.arange(1, 256, dtype=np.float64)
        lo = np.zeros(255, dtype=np.int64)  # bits of 0.0: code 0 < k
        hi = np.full(255, np.float64(1.0).view(np.int64))  # bits of 1.0: code 255 >= k
        while np.any(hi - lo > 1):
            mid = lo + (hi - lo) // 2
            up = code(mid.view(np.float64)) >= k
            hi = np.where(up, mid, hi)
            lo = np.where(up, lo, mid)
        thresholds = hi.view(np.float64).copy()
        starts = np.searchsorted(thresholds, np.arange(_SRGB8_BINS + 1) / _SRGB8_BINS, side="right").astype(np.int64)
        _SRGB8_TABLES[encode] = (thresholds, starts)
    return _SRGB8_TABLES[encode]


@nb.njit(cache=True, nogil=True)
def _srgb8_values(lin, thresholds, starts, out):  # pragma: no cover - compiled
    for i in range(out.shape[0]):
        v = lin[i]
        if v != v:
            out[i] = v
            continue
        v = min(max(v, 0.0), 1.0)
        c = starts[int(v * _SRGB8_BINS)]
        while c < 255 and v >= thresholds[c]:
            c += 1
        out[i] = c


def srgb8_codes(linear, encode) -> np.ndarray:
    """8-bit sRGB code values (float64) of linear sRGB: exactly
    ``np.round(255 * encode(np.clip(linear, 0, 1)))`` (NaN stays NaN) for a
    non-decreasing ``encode`` (:func:`cfa_mitsuba.colorimetry.linear_to_srgb`),
    by table: the code is the number of thresholds at or below the value
    (:func:`_srgb8_tables`), where the formula costs a power per value.  The
    test checks it on every threshold's neighbours and ten million values."""
    a = np.asarray(linear, dtype=np.float64)
    out = np.empty(a.shape, dtype=np.float64)
    if out.size:
        thresholds, starts = _srgb8_tables(encode)
        _srgb8_values(np.ascontiguousarray(a).reshape(-1), thresholds, starts, out.reshape(-1))
    return out


@nb.njit(cache=True, nogil=True)
def _realisable_rows(xyz, to_rgb, tolerance, tiny, out, rest):  # pragma: no cover - compiled
    for i in range(out.shape[0]):
        x = xyz[i, 0]
        y = xyz[i, 1]
        z = xyz[i, 2]
        s = x + y + z
        floor = -tolerance * max(abs(s), tiny)
        nonneg = x >= floor and y >= floor and z >= floor
        inside = (to_rgb[0, 0] * x + to_rgb[0, 1] * y + to_rgb[0, 2] * z >= 0.0
                  and to_rgb[1, 0] * x + to_rgb[1, 1] * y + to_rgb[1, 2] * z >= 0.0
                  and to_rgb[2, 0] * x + to_rgb[2, 1] * y + to_rgb[2, 2] * z >= 0.0)
        out[i] = nonneg and (s <= 0.0 or inside)
        rest[i] = nonneg and s > 0.0 and not inside


def realisable_first_pass(xyz, to_rgb, tolerance: float):
    """The per-pixel half of :func:`cfa_mitsuba.colorimetry.realisable` in
    one pass: (the answer where the sign and sRGB-triangle tests decide it,
    the pixels whose answer the spectral locus decides), both (N,) bool for
    (N, 3) ``xyz``; the same expressions in the same order as numpy's."""
    rows = _rows(xyz)
    out = np.empty(rows.shape[0], dtype=np.bool_)
    rest = np.empty(rows.shape[0], dtype=np.bool_)
    if out.size:
        _realisable_rows(rows, np.ascontiguousarray(to_rgb, dtype=np.float64), float(tolerance),
                         float(np.finfo(float).tiny), out, rest)
    return out, rest
