"""Compiled per-pixel loops for the colour formulas a study evaluates
hundreds of millions of times: CIE 1976 L*a*b*, CIEDE2000 and 8-bit sRGB
codes.

Written by hand (with Numba) for speed only: scikit-image's
``deltaE_ciede2000`` and colour-science's ``XYZ_to_Lab`` compute the same
numbers but as a chain of whole-array numpy operations, each writing a
temporary the size of the image.  Both agree with those libraries to 1e-12
(tests/test_colour_kernels.py, with Sharma's 34 published pairs);
:mod:`cfa_mitsuba.colorimetry` is the public interface and calls these.

The transcendental functions (the cube roots of CIELAB; the atan2, exp and
tan of CIEDE2000's rotation term) are left to numpy's ufuncs, which have
SIMD implementations (SVML where the CPU has AVX-512): 5 to 11 times the
speed of the scalar libm calls a Numba loop makes (``np.arctan2`` 3.5 ns
against 40 ns a value, ``np.cbrt`` 1.9 ns against ``pow(t, 1/3)`` 21 ns,
measured on this project's machine).  The arithmetic around them is in
compiled loops that vectorise, and the work goes in blocks of
:data:`BLOCK` pixels so that the intermediate arrays stay in cache.  The
values are the scalar formulas' to a few units in the last place (the two
libms differ there).

The loops compile on first use (about a second) and are cached on disk
beside this module by Numba (``cache=True``), so later processes load them.
"""

from __future__ import annotations

__all__ = ["ciede2000", "lab_cie", "opponent_lab", "realisable_first_pass", "srgb8_codes"]

import math

import numba as nb
import numpy as np

from .io.jit_cache import tolerate_cache_write_errors

tolerate_cache_write_errors()  # the kernel cache is a write that may fail (a full disk): io/jit_cache.py

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
def _from_hue_terms(L1, L2, C1, C2, sin_half, c, s, rot_sin):
    """CIEDE2000 from the lightnesses, the chromas C', sin(dh'/2), cos and
    sin of the mean hue and ``rot_sin`` = sin(2 dtheta), dtheta = 30 deg
    exp(-((h' - 275 deg) / 25 deg)^2) the rotation angle: Sharma eqs 8-9 and
    12-22."""
    # lightness and chroma terms (eqs 8-9, 17-18); S_L = (s + 0.015 t) / s, s = sqrt(20 + t), so
    # l_term = dL s / (s + 0.015 t): one division where the formula as written takes two
    lm = 0.5 * (L1 + L2) - 50.0
    t = lm * lm
    root = math.sqrt(20.0 + t)
    l_term = (L2 - L1) * root / (root + 0.015 * t)
    cbar = 0.5 * (C1 + C2)
    s_c = 1.0 + 0.045 * cbar
    # T by the multiple-angle identities from one cos/sin pair (eq. 15)
    c2 = 2.0 * c * c - 1.0
    s2 = 2.0 * s * c
    c3 = c * (4.0 * c * c - 3.0)
    s3 = s * (3.0 - 4.0 * s * s)
    c4 = 2.0 * c2 * c2 - 1.0
    s4 = 2.0 * s2 * c2
    T = (1.0 - 0.17 * (c * _C30 + s * _S30) + 0.24 * c2
         + 0.32 * (c3 * _C6 - s3 * _S6) - 0.20 * (c4 * _C63 + s4 * _S63))
    s_h = 1.0 + 0.015 * cbar * T
    # dC' / S_C and dH' / S_H over one division by S_C S_H (square roots and divisions bound this loop's time)
    inv = 1.0 / (s_c * s_h)
    c_term = (C2 - C1) * s_h * inv
    h_term = 2.0 * math.sqrt(C1 * C2) * sin_half * s_c * inv
    # rotation term (eqs 19-22)
    c7 = _pow7(cbar)
    r_term = -rot_sin * 2.0 * math.sqrt(c7 / (c7 + _P25_7)) * c_term * h_term
    e = l_term * l_term + c_term * c_term + h_term * h_term + r_term
    return 0.0 if e < 0.0 else math.sqrt(e)  # NaN stays NaN


@nb.njit(inline="always")
def _rotation_exponent(hbar):
    """-((h' - 275 deg) / 25 deg)^2 of a mean hue ``hbar`` in (-pi, 2 pi)
    (radians; a negative one is taken modulo 2 pi): the exponent of eq. 21's
    dtheta."""
    h = hbar + _TWO_PI if hbar < 0.0 else hbar
    z = (math.degrees(h) - 275.0) / 25.0
    return -z * z


@nb.njit(inline="always")
def _de00(L1, a1, b1, L2, a2, b2):
    """CIEDE2000 of one pair (Sharma et al. 2005, eqs 1-22), the hue terms by
    angles and scalar libm calls: the pairs :func:`_hue_vectors` flags."""
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
    rot_sin = math.sin(2.0 * _D30 * math.exp(_rotation_exponent(hbar)))
    return _from_hue_terms(L1, L2, C1, C2, math.sin(0.5 * dh), math.cos(hbar), math.sin(hbar), rot_sin)


@nb.njit(cache=True, nogil=True, error_model="numpy")
def _hue_vectors(lab1, lab2, ux_out, uy_out, c1_out, c2_out, half_out, flag):  # pragma: no cover - compiled
    """First pass of :func:`ciede2000`: the hue terms from the (a', b')
    vectors instead of their angles.  cos and sin of the mean hue are the
    unit bisector's components (``ux_out``, ``uy_out``: the mean on the
    shorter arc, Sharma's eq. 14 and its wrap); sin(dh/2) (``half_out``)
    follows from the cross and dot products by the half-angle formulas (dh
    wrapped to [-pi, pi], eq. 10).  ``flag`` marks the pairs where that
    construction is degenerate (a zero chroma, hues equal or opposite) or
    loses digits (hues within 1.15 degrees of opposite): :func:`_de00`
    takes those.  No branch that stops the loop vectorising."""
    for i in range(flag.shape[0]):
        b1 = lab1[i, 2]
        b2 = lab2[i, 2]
        x1, x2, C1, C2 = _primed(lab1[i, 1], b1, lab2[i, 1], b2)
        cc = C1 * C2
        cross = x1 * b2 - b1 * x2  # C1 C2 sin(h2 - h1)
        dot = x1 * x2 + b1 * b2  # C1 C2 cos(h2 - h1)
        ux = x1 * C2 + x2 * C1  # C1 C2 (u1 + u2), u the unit hue vectors: along the mean hue
        uy = b1 * C2 + b2 * C1
        nrm = math.sqrt(ux * ux + uy * uy)
        # |u1 + u2| = 2 cos(dh / 2): below 1e-2, hues within 1.15 deg of opposite
        flag[i] = (cc == 0.0) | (cross == 0.0) | (nrm <= 1e-2 * cc)
        inv_nrm = 1.0 / nrm
        cs = dot / cc
        # sin(dh / 2), of the sign of dh = the sign of sin(dh); both halves made, one kept: near
        # = sin(dh) / sqrt(2 (1 + cos dh)) = cross / nrm (nrm = C1 C2 sqrt(2 (1 + cos dh)))
        near = cross * inv_nrm
        far = math.sqrt(0.5 * (1.0 - cs))
        far = -far if cross < 0.0 else far
        half_out[i] = near if cs >= 0.0 else far
        ux_out[i] = ux * inv_nrm
        uy_out[i] = uy * inv_nrm
        c1_out[i] = C1
        c2_out[i] = C2


@nb.njit(cache=True, nogil=True, error_model="numpy")
def _rotation_exponents(h):  # pragma: no cover - compiled
    """In place: mean hues (atan2's (-pi, pi]) -> :func:`_rotation_exponent`."""
    for i in range(h.shape[0]):
        h[i] = _rotation_exponent(h[i])


@nb.njit(cache=True, nogil=True, error_model="numpy")
def _ciede2000_terms(lab1, lab2, out, ux, uy, c1, c2, half, tan_theta):  # pragma: no cover - compiled
    """Last pass of :func:`ciede2000`: eqs 8-22 from the first pass's
    arrays and tan(dtheta) (sin(2 dtheta) = 2 tan / (1 + tan^2))."""
    for i in range(out.shape[0]):
        t = tan_theta[i]
        out[i] = _from_hue_terms(lab1[i, 0], lab2[i, 0], c1[i], c2[i], half[i], ux[i], uy[i],
                                 2.0 * t / (1.0 + t * t))


@nb.njit(cache=True, nogil=True, error_model="numpy")
def _ciede2000_flagged(lab1, lab2, out, flag):  # pragma: no cover - compiled
    for i in range(out.shape[0]):
        if flag[i]:
            out[i] = _de00(lab1[i, 0], lab1[i, 1], lab1[i, 2], lab2[i, 0], lab2[i, 1], lab2[i, 2])


@nb.njit(inline="always")
def _lab_f(t, root):
    """CIE 015's f(t) from t and its cube root ``root``."""
    return root if t > _LAB_EPS else _LAB_KAPPA * t + 16.0 / 116.0


@nb.njit(cache=True, nogil=True, error_model="numpy")
def _lab_from_roots(t, roots):  # pragma: no cover - compiled
    """In place: (N, 3) XYZ / white ratios ``t`` -> L*, a*, b*, given their
    cube roots ``roots``."""
    for i in range(t.shape[0]):
        fx = _lab_f(t[i, 0], roots[i, 0])
        fy = _lab_f(t[i, 1], roots[i, 1])
        fz = _lab_f(t[i, 2], roots[i, 2])
        t[i, 0] = 116.0 * fy - 16.0
        t[i, 1] = 500.0 * (fx - fy)
        t[i, 2] = 200.0 * (fy - fz)


@nb.njit(cache=True, nogil=True, error_model="numpy")
def _ratio_rows(xyz, white, out):  # pragma: no cover - compiled
    for i in range(out.shape[0]):
        out[i, 0] = xyz[i, 0] / white[0]
        out[i, 1] = xyz[i, 1] / white[1]
        out[i, 2] = xyz[i, 2] / white[2]


@nb.njit(cache=True, nogil=True, error_model="numpy")
def _opponent_ratios(planes, base, to_xyz, white, out):  # pragma: no cover - compiled
    """(rows, W, 3) XYZ / white of (3, rows, W) opponent planes (plus ``base``)."""
    for r in range(out.shape[0]):
        for c in range(out.shape[1]):
            o0 = planes[0, r, c]
            o1 = planes[1, r, c]
            o2 = planes[2, r, c]
            if base is not None:  # pruned at compile time when there is none
                o0 = base[0, r, c] + o0
                o1 = base[1, r, c] + o1
                o2 = base[2, r, c] + o2
            out[r, c, 0] = (to_xyz[0, 0] * o0 + to_xyz[0, 1] * o1 + to_xyz[0, 2] * o2) / white[0]
            out[r, c, 1] = (to_xyz[1, 0] * o0 + to_xyz[1, 1] * o1 + to_xyz[1, 2] * o2) / white[1]
            out[r, c, 2] = (to_xyz[2, 0] * o0 + to_xyz[2, 1] * o1 + to_xyz[2, 2] * o2) / white[2]


#: pixels a block: the intermediate arrays of a block (about 1 MB) stay in
#: the core's cache; 2k to 32k ran at one speed, the whole image 1.6x slower (measured)
BLOCK = 16384


def _rows(a: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(a, dtype=np.float64).reshape(-1, 3)


def _lab_of_ratios(t: np.ndarray, roots: np.ndarray) -> None:
    """In place: (m, 3) ratios -> CIELAB, the cube roots by numpy into ``roots``."""
    r = roots[: t.shape[0]]
    np.cbrt(t, out=r)
    _lab_from_roots(t, r)


def ciede2000(lab1, lab2) -> np.ndarray:
    """CIEDE2000 (kL = kC = kH = 1) between two broadcastable (..., 3) CIELAB
    arrays: shape ``broadcast(...)``, float64.

    Sharma, Wu & Dalal, "The CIEDE2000 color-difference formula:
    implementation notes, supplementary test data, and mathematical
    observations", Color Res. Appl. 30 (2005) 21-30, eqs 1-22; the
    zero-chroma conventions are theirs (and scikit-image's).  Per block:
    :func:`_hue_vectors`, then the mean hue's atan2, exp and tan by numpy,
    then :func:`_ciede2000_terms`; the flagged pairs by :func:`_de00`.
    """
    a, b = np.broadcast_arrays(np.asarray(lab1, dtype=np.float64), np.asarray(lab2, dtype=np.float64))
    out = np.empty(a.shape[:-1], dtype=np.float64)
    if not out.size:
        return out
    rows1, rows2, flat = _rows(a), _rows(b), out.reshape(-1)
    n = min(BLOCK, flat.shape[0])
    ux, uy, c1, c2, half, h = np.empty((6, n))
    flag = np.empty(n, dtype=np.bool_)
    with np.errstate(invalid="ignore", divide="ignore"):  # the flagged pairs' NaNs, replaced
        for start in range(0, flat.shape[0], n):
            stop = min(start + n, flat.shape[0])
            m = stop - start
            p, q, o = rows1[start:stop], rows2[start:stop], flat[start:stop]
            _hue_vectors(p, q, ux[:m], uy[:m], c1[:m], c2[:m], half[:m], flag[:m])
            hb = h[:m]
            np.arctan2(uy[:m], ux[:m], out=hb)
            _rotation_exponents(hb)
            np.exp(hb, out=hb)
            hb *= _D30
            np.tan(hb, out=hb)
            _ciede2000_terms(p, q, o, ux[:m], uy[:m], c1[:m], c2[:m], half[:m], hb)
            _ciede2000_flagged(p, q, o, flag[:m])
    return out


def lab_cie(xyz, white) -> np.ndarray:
    """CIE 1976 L*a*b* (CIE 015:2018 eqs 8.1-8.3, exact 216/24389 and
    24389/27 in their (24/116)^3 and 841/108 form) of (..., 3) XYZ relative to
    ``white`` (3,) on the same scale."""
    a = np.asarray(xyz, dtype=np.float64)
    out = np.empty(a.shape, dtype=np.float64)
    if out.size:
        rows, flat = _rows(a), out.reshape(-1, 3)
        white = np.ascontiguousarray(white, dtype=np.float64)
        roots = np.empty((min(BLOCK, flat.shape[0]), 3))
        for start in range(0, flat.shape[0], BLOCK):
            t = flat[start:start + BLOCK]
            _ratio_rows(rows[start:start + BLOCK], white, t)
            _lab_of_ratios(t, roots)
    return out


def opponent_lab(planes, to_xyz, white, base=None) -> np.ndarray:
    """(H, W, 3) CIELAB of (3, H, W) opponent planes: XYZ by the (3, 3)
    matrix ``to_xyz``, then :func:`lab_cie` relative to ``white``, in blocks
    of rows (no (H, W, 3) XYZ in memory).

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
        to_xyz = np.ascontiguousarray(to_xyz, dtype=np.float64)
        white = np.ascontiguousarray(white, dtype=np.float64)
        rows = max(1, BLOCK // out.shape[1])
        roots = np.empty((rows * out.shape[1], 3))
        for r in range(0, out.shape[0], rows):
            block = out[r:r + rows]
            _opponent_ratios(planes[:, r:r + rows], None if base is None else base[:, r:r + rows],
                             to_xyz, white, block)
            _lab_of_ratios(block.reshape(-1, 3), roots)
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
