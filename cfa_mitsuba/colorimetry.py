"""The colour maths of every stage, in one module: sRGB code values, linear
RGB, CIE XYZ, CIELAB, chromaticity, the CIE 1976 / CIEDE2000 colour
differences and the one sRGB encoding used for metrics, previews, thumbnails
and the processed images (a shared leaf: it imports no stage).

The sRGB <-> XYZ conversion is IEC 61966-2-1 with its 4-digit matrix and the
white point given by the matrix's row sums, (95.05, 100, 108.9): the
convention ISETCam's reference values were produced with
(tests/data/reference/README.md).  The transfer functions, CIELAB and the
colour differences come from colour-science (exact CIE constants
216/24389 and 24389/27; ISETCam under Octave uses the rounded 0.008856 /
7.787, a 2e-7 relative difference).

XYZ here may be on any absolute scale (our camera images have Y in cd/m^2);
CIELAB is always taken relative to a white point given on the same scale.
"""

from __future__ import annotations

__all__ = [
    "SRGB_TO_XYZ",
    "XYZ_TO_SRGB",
    "SRGB_WHITE_XYZ",
    "RGB2GRAY_WEIGHTS",
    "srgb8_to_srgb",
    "srgb_to_linear",
    "linear_to_srgb",
    "linear_to_xyz",
    "xyz_to_linear",
    "srgb8_to_xyz",
    "xyz_to_srgb8",
    "xyz_to_lab",
    "xyz_to_xy",
    "lightness",
    "delta_e_1976",
    "delta_e_2000",
    "rgb_to_gray",
    "xyz_to_srgb",
    "delta_e00",
    "realisable",
]

import numpy as np

from .colour_science import colour_science as _colour  # colour-science, imported on first call
from .errors import require, require_finite

#: IEC 61966-2-1 linear sRGB -> XYZ (Y of white = 1), the standard's 4 digits.
SRGB_TO_XYZ = np.array([
    [0.4124, 0.3576, 0.1805],
    [0.2126, 0.7152, 0.0722],
    [0.0193, 0.1192, 0.9505],
])
XYZ_TO_SRGB = np.linalg.inv(SRGB_TO_XYZ)
#: The white of that matrix on the 0..100 scale: 100 x row sums = (95.05, 100, 108.9).
SRGB_WHITE_XYZ = 100.0 * SRGB_TO_XYZ.sum(axis=1)
#: MATLAB ``rgb2gray`` weights, unrounded (reference README s. 3).
RGB2GRAY_WEIGHTS = np.array([0.298936021293775, 0.587043074451121, 0.114020904255103])

# The transposes the per-pixel products of an image multiply by, stored contiguous: numpy hands a
# transposed view to a slower matrix-product path (5.9 against 2.4 ms on a 636 x 720 x 3 image), with
# the same sums for an image (tests/test_fast_paths.py checks them equal); a single colour or a list of
# colours keeps the transposed view (a vector product there rounds differently in the last bit).
_SRGB_TO_XYZ_T = np.ascontiguousarray(SRGB_TO_XYZ.T)
_XYZ_TO_SRGB_T = np.ascontiguousarray(XYZ_TO_SRGB.T)

for _a in (SRGB_TO_XYZ, XYZ_TO_SRGB, SRGB_WHITE_XYZ, RGB2GRAY_WEIGHTS, _SRGB_TO_XYZ_T, _XYZ_TO_SRGB_T):
    _a.flags.writeable = False


def as_white(white_xyz) -> np.ndarray:
    """A white point (Xw, Yw, Zw), finite and positive."""
    w = require_finite(white_xyz, "white point").reshape(-1)
    require(w.size == 3, f"white point must have 3 values (X, Y, Z), got {w.size}")
    require(bool(np.all(w > 0)), f"white point must be positive, got {w.tolist()}")
    return w


def srgb8_to_srgb(codes) -> np.ndarray:
    """8-bit sRGB code values (0..255) to encoded sRGB in 0..1."""
    return np.asarray(codes, dtype=np.float64) / 255.0


def srgb_to_linear(srgb) -> np.ndarray:
    """IEC 61966-2-1 decoding (EOTF; 0.04045, 12.92, 2.4): encoded 0..1 -> linear 0..1.

    Examples
    --------
    >>> float(srgb_to_linear(0.5))  # doctest: +ELLIPSIS
    0.2140...
    """
    colour = _colour()

    return np.asarray(colour.models.eotf_sRGB(np.asarray(srgb, dtype=np.float64)), dtype=np.float64)


def linear_to_srgb(linear) -> np.ndarray:
    """IEC 61966-2-1 encoding (inverse EOTF): linear 0..1 -> encoded 0..1 (not clipped)."""
    # colour-science's ``eotf_inverse_sRGB`` formula, term for term (its ``spow``: sign(L) |L|^(1/2.4)),
    # without its domain-range scaling and validation: the same float64 values (tests/test_fast_paths.py
    # checks them equal), at a fraction of the time on a camera image.
    lin = np.asarray(linear, dtype=np.float64)
    return np.where(lin <= 0.0031308, lin * 12.92, 1.055 * (np.sign(lin) * np.abs(lin) ** (1 / 2.4)) - 0.055)


def linear_to_xyz(rgb, *, scale: float = 100.0) -> np.ndarray:
    """Linear sRGB (white = 1) to XYZ with the 4-digit matrix; white Y = ``scale``."""
    rgb = np.asarray(rgb, dtype=np.float64)
    return scale * rgb @ (_SRGB_TO_XYZ_T if rgb.ndim >= 3 else SRGB_TO_XYZ.T)


def xyz_to_linear(xyz, *, scale: float = 100.0) -> np.ndarray:
    """XYZ (white Y = ``scale``) to linear sRGB (white = 1), not clipped."""
    xyz = np.asarray(xyz, dtype=np.float64)
    return (xyz / scale) @ (_XYZ_TO_SRGB_T if xyz.ndim >= 3 else XYZ_TO_SRGB.T)


def srgb8_to_xyz(codes, *, scale: float = 100.0) -> np.ndarray:
    """8-bit sRGB codes to XYZ (white (95.05, 100, 108.9) x ``scale`` / 100).

    Examples
    --------
    >>> srgb8_to_xyz([255, 255, 255]).round(4).tolist()
    [95.05, 100.0, 108.9]
    """
    return linear_to_xyz(srgb_to_linear(srgb8_to_srgb(codes)), scale=scale)


def xyz_to_srgb(xyz, white_xyz, *, adaptation: str | None = None) -> np.ndarray:
    """Absolute XYZ to encoded sRGB in 0..1: the project's one sRGB encoding.

    The white's luminance ``white_xyz[1]`` maps to 1; linear values (the
    4-digit IEC 61966-2-1 matrix) are clipped to 0..1 before encoding.
    ``adaptation`` None: no chromatic adaptation (the metrics' convention,
    meant for D65 scenes as in the paper, and ISETCam's); ``'Bradford'`` (or
    any colour-science transform name): the white's chromaticity is first
    adapted to sRGB's D65, so a scene under another light shows its white as
    white (previews, thumbnails, processed images).

    Examples
    --------
    >>> xyz_to_srgb([95.05, 100.0, 108.9], [95.05, 100.0, 108.9]).round(6).tolist()
    [1.0, 1.0, 1.0]
    """
    w = as_white(white_xyz)
    return linear_to_srgb(np.clip(_display_linear(xyz, w, adaptation), 0.0, 1.0))


def _display_linear(xyz, w: np.ndarray, adaptation: str | None) -> np.ndarray:
    """Linear sRGB (white Y = 1, not clipped) of absolute XYZ for the white
    ``w`` (checked), its chromaticity adapted to sRGB's D65 first when
    ``adaptation`` names a transform (:func:`xyz_to_srgb`)."""
    xyz = np.asarray(xyz, dtype=np.float64)
    if adaptation is not None:
        colour = _colour()
        d65 = SRGB_WHITE_XYZ / SRGB_WHITE_XYZ[1]
        # colour-science's von Kries matrix, applied as one (N, 3) x (3, 3) product rather than its
        # per-pixel batched 3 x 3 products (the same values to rounding; tests/test_fast_paths.py)
        cat = colour.adaptation.matrix_chromatic_adaptation_VonKries(w / w[1], d65, transform=adaptation)
        xyz = w[1] * ((xyz / w[1]) @ cat.T)
    return xyz_to_linear(xyz, scale=w[1])


def xyz_to_srgb8(xyz, white_xyz, *, quantize: bool = True, adaptation: str | None = None) -> np.ndarray:
    """Absolute XYZ to 8-bit sRGB code values (float64, 0..255):
    ``255 x`` :func:`xyz_to_srgb` (with its ``adaptation``, default none),
    rounded when ``quantize`` (an 8-bit image, as ISETCam's SSIM sees it).

    Examples
    --------
    >>> xyz_to_srgb8([[20.0, 21.0, 22.0]], [95.05, 100.0, 108.9]).tolist()
    [[128.0, 126.0, 124.0]]
    """
    if not quantize:
        return 255.0 * xyz_to_srgb(xyz, white_xyz, adaptation=adaptation)
    # exactly np.round(255 x xyz_to_srgb(...)), by a table of the code boundaries (tests/test_colour_kernels.py)
    from .colour_kernels import srgb8_codes

    return srgb8_codes(_display_linear(xyz, as_white(white_xyz), adaptation), linear_to_srgb)


def xyz_to_lab(xyz, white_xyz, *, constants: str = "cie") -> np.ndarray:
    """CIE 1976 L*a*b* of XYZ relative to ``white_xyz`` (same scale as ``xyz``).

    ``constants``: ``'cie'`` (default; CIE 015 exact 216/24389 and 24389/27,
    via colour-science) or ``'isetcam'`` (the rounded 0.008856 / 7.787 / 903.3
    of ISETCam's ``ieXYZ2LAB`` fallback, to reproduce its numbers; the two
    differ only for colours darker than about L* = 8).

    Examples
    --------
    >>> xyz_to_lab([95.05, 100.0, 108.9], [95.05, 100.0, 108.9]).round(10).tolist()
    [100.0, 0.0, 0.0]
    """
    require(constants in ("cie", "isetcam"), f"unknown CIELAB constants {constants!r} (expected 'cie' or 'isetcam')")
    w = as_white(white_xyz)
    xyz = np.asarray(xyz, dtype=np.float64)
    require(xyz.ndim >= 1 and xyz.shape[-1] == 3, f"XYZ must have 3 values in its last axis, got shape {xyz.shape}")
    if constants == "isetcam":
        t = xyz / w
        small = t <= 0.008856
        f = np.where(small, 7.787 * t + 16.0 / 116.0, np.cbrt(np.where(small, 1.0, t)))
        ty = t[..., 1]
        lum = np.where(ty > 0.008856, 116.0 * f[..., 1] - 16.0, 903.3 * ty)
        return np.stack([lum, 500.0 * (f[..., 0] - f[..., 1]), 200.0 * (f[..., 1] - f[..., 2])], axis=-1)
    # colour-science's ``XYZ_to_Lab`` gives the same values to 1e-12 (tests/test_colour_kernels.py);
    # the compiled loops take a fraction of its time on a camera image.
    from .colour_kernels import lab_cie

    return lab_cie(xyz, w)


def lightness(y, white_y: float) -> np.ndarray:
    """CIE 1976 L* of luminance ``y`` relative to the white's ``white_y``."""
    colour = _colour()

    require(white_y > 0, f"white luminance must be positive, got {white_y}")
    with colour.utilities.domain_range_scale("reference"):
        return np.asarray(colour.colorimetry.lightness_CIE1976(100.0 * np.asarray(y, dtype=np.float64) / white_y), dtype=np.float64)


def xyz_to_xy(xyz) -> np.ndarray:
    """CIE 1931 xy chromaticity (black maps to the D65-free convention of colour: (0, 0))."""
    colour = _colour()

    return np.asarray(colour.XYZ_to_xy(np.asarray(xyz, dtype=np.float64)), dtype=np.float64)


def delta_e_1976(lab1, lab2) -> np.ndarray:
    """CIE 1976 colour difference: Euclidean distance in L*a*b* (the paper's dE*ab)."""
    d = np.asarray(lab1, dtype=np.float64) - np.asarray(lab2, dtype=np.float64)
    return np.sqrt(np.sum(d * d, axis=-1))


def delta_e_2000(lab1, lab2) -> np.ndarray:
    """CIEDE2000 (Sharma, Wu & Dalal 2005; kL = kC = kH = 1) between
    broadcastable (..., 3) CIELAB arrays.

    Compiled loops and numpy's SIMD ufuncs
    (:func:`cfa_mitsuba.colour_kernels.ciede2000`): scikit-image's
    ``deltaE_ciede2000`` and colour-science's give the same numbers to
    1e-12 (tests/test_colour_kernels.py) in several times the time, and the
    S-CIELAB map of every CFA, demosaic and noise realisation goes through
    it.

    Examples
    --------
    >>> round(float(delta_e_2000([50, 2.6772, -79.7751], [50, 0, -82.7485])), 4)
    2.0425
    """
    from .colour_kernels import ciede2000

    return ciede2000(lab1, lab2)


def rgb_to_gray(rgb) -> np.ndarray:
    """Luma with MATLAB's ``rgb2gray`` weights, unrounded (ISETCam's SSIM input)."""
    return np.asarray(rgb, dtype=np.float64) @ RGB2GRAY_WEIGHTS


def delta_e00(xyz_a, xyz_b, white_xyz) -> np.ndarray:
    """CIEDE2000 between two absolute XYZ arrays (..., 3), CIELAB relative to
    ``white_xyz`` (same scale): :func:`delta_e_2000` of :func:`xyz_to_lab`."""
    return delta_e_2000(xyz_to_lab(xyz_a, white_xyz), xyz_to_lab(xyz_b, white_xyz))


_LOCUS_HALF_PLANES = None


def _half_planes(vertices) -> np.ndarray:
    """(n, 3) half-planes a x + b y + c <= 0 of the convex hull of ``vertices``."""
    from scipy.spatial import ConvexHull

    return ConvexHull(np.asarray(vertices, dtype=np.float64)).equations


def _locus_half_planes() -> np.ndarray:
    """(n, 3) half-planes a x + b y + c <= 0 of the convex hull of the CIE
    1931 2-degree spectral locus and the purple line (360-830 nm, 1 nm)."""
    global _LOCUS_HALF_PLANES
    if _LOCUS_HALF_PLANES is None:
        cmfs = _colour().MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].values
        _LOCUS_HALF_PLANES = _half_planes(cmfs[:, :2] / cmfs.sum(axis=1, keepdims=True))
    return _LOCUS_HALF_PLANES


def realisable(xyz, *, tolerance: float = 1e-6) -> np.ndarray:
    """Whether each XYZ is the colour of some light (the tristimulus values
    of a non-negative spectrum): Y >= 0, X, Z >= 0 and a chromaticity on or
    inside the spectral locus and the purple line.  Black (0, 0, 0) is
    realisable.  A camera's colour matrix can output values outside this
    cone (negative X, a chromaticity past the locus): no light has them and
    CIELAB's a*, b* of them are unbounded (C*ab of thousands).

    Parameters
    ----------
    xyz : (..., 3) CIE 1931 XYZ, any scale.
    tolerance : slack of the chromaticity test and of the sign test relative
        to the value's X + Y + Z (rounding).

    Returns
    -------
    (...) bool.

    Examples
    --------
    >>> realisable([[95.05, 100.0, 108.9], [0, 0, 0], [-5.0, 10.0, 10.0], [80.0, 10.0, 0.0]]).tolist()
    [True, True, False, False]
    """
    a = np.asarray(xyz, dtype=np.float64)
    require(a.ndim >= 1 and a.shape[-1] == 3, f"XYZ must have 3 values in its last axis, got shape {a.shape}")
    # Two stages, so a camera image costs little, not an (n_pixels, n_planes) product: sRGB's
    # triangle lies inside the locus, so a point inside it is realisable; only the points outside it
    # (saturated colours, errors) meet the locus's half-planes (:func:`_inside_locus`).
    # Inside the triangle of the 4-digit matrix's primaries <=> linear R, G, B all >= 0 (for X + Y + Z
    # > 0); those primaries lie within 1e-4 of IEC 61966-2-1's, well inside the locus.  A point that
    # fails the sign test (any of X, Y, Z below -tolerance x (X + Y + Z)) is not realisable whatever
    # its chromaticity.  The first stage is one compiled pass (colour_kernels.realisable_first_pass).
    from .colour_kernels import realisable_first_pass

    out, rest = realisable_first_pass(a, XYZ_TO_SRGB, tolerance)
    idx = np.flatnonzero(rest)
    if idx.size:
        flat = a.reshape(-1, 3)[idx]
        xy = flat[:, :2] / (flat[:, 0] + flat[:, 1] + flat[:, 2])[:, None]
        out[idx] = _inside_locus(xy, tolerance)
    return out.reshape(a.shape[:-1])


def _locus_sectors():
    """The locus hull as fans around an inner point: (centre (2,), sorted
    vertex angles (n,), edge half-planes (n, 3) with edge k between the
    vertices at angles k - 1 and k, outward unit normals)."""
    global _LOCUS_SECTORS
    if _LOCUS_SECTORS is None:
        from scipy.spatial import ConvexHull

        cmfs = _colour().MSDS_CMFS["CIE 1931 2 Degree Standard Observer"].values
        pts = cmfs[:, :2] / cmfs.sum(axis=1, keepdims=True)
        v = pts[ConvexHull(pts).vertices]  # counter-clockwise
        centre = v.mean(axis=0)
        ang = np.arctan2(v[:, 1] - centre[1], v[:, 0] - centre[0])
        order = np.argsort(ang)
        v, ang = v[order], ang[order]
        a, b = np.roll(v, 1, axis=0), v  # edge k: vertex k - 1 -> vertex k (counter-clockwise)
        normal = np.stack([b[:, 1] - a[:, 1], a[:, 0] - b[:, 0]], axis=1)  # outward for a counter-clockwise polygon
        normal /= np.linalg.norm(normal, axis=1, keepdims=True)
        _LOCUS_SECTORS = (centre, ang, np.column_stack([normal, -np.sum(normal * a, axis=1)]))
    return _LOCUS_SECTORS


_LOCUS_SECTORS = None


def _inside_locus(xy: np.ndarray, tolerance: float) -> np.ndarray:
    """(n,) whether each chromaticity (n, 2) meets every half-plane of the
    locus hull within ``tolerance`` (:func:`_locus_half_planes`).

    The same answer as testing all ~60 half-planes, from one: a point lies
    in the fan triangle (centre, vertex k - 1, vertex k) its angle falls in,
    so the edge of that triangle decides it, clearly inside (below
    -1e-9) or clearly outside (past ``tolerance``, which fails the full test
    too); the few points in between get the full test."""
    centre, ang, edges = _locus_sectors()
    k = np.searchsorted(ang, np.arctan2(xy[:, 1] - centre[1], xy[:, 0] - centre[0])) % ang.size
    e = edges[k]
    v = e[:, 0] * xy[:, 0] + e[:, 1] * xy[:, 1] + e[:, 2]
    out = v <= -1e-9
    unsure = np.flatnonzero((v > -1e-9) & (v <= tolerance))
    if unsure.size:
        outer = _locus_half_planes()
        out[unsure] = np.all(xy[unsure] @ outer[:, :2].T + outer[:, 2] <= tolerance, axis=-1)
    return out
