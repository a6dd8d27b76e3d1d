"""S-CIELAB (Zhang & Wandell 1996): CIELAB after filtering opponent channels
with the eye's spatial sensitivity (Bae 2020 s. 2.2.2, Fig 4, Fig 10).

Written here because no maintained Python library implements it with
ISETCam's parameters.  The steps and numbers are those ISETCam's
``scielab.m`` uses with its 'distribution' filters (the reference values in
tests/data/reference/ come from it), except the boundary: we extend the image symmetrically (MATLAB's and
numpy's 'symmetric', Zhang's original code) and return a map of the input's
size, registered to it, where ISETCam crops a row/column and convolves
circularly.  Away from the border (one degree in) both agree to 1e-13.
"""

from __future__ import annotations

__all__ = ["RECORDS", "scielab", "scielab_filters", "scielab_reference", "scielab_reference_lab", "FilteredReference",
           "OPPONENT_MATRICES", "FILTER_PARAMETERS", "FFT_PRECISIONS"]

import functools
from dataclasses import dataclass

import numpy as np

from ..errors import require
from ._common import as_image, as_pair, as_white
from ._result import MetricResult, summarise_array
from .colourspace import delta_e_1976, delta_e_2000, xyz_to_lab
from .delta_e import PRACTICAL_DE  # one source for the ΔE threshold
from .record import NATURAL, MetricRecord

#: XYZ -> opponent (luminance, red-green, blue-yellow), rows = output channels
#: (ISETCam ``colorTransformMatrix('xyz2opp', 2 | 10)``).  'xyz2' matches CIE
#: 1931 2-degree XYZ, which is what our images hold.
OPPONENT_MATRICES = {
    "xyz2": np.array([
        [0.2787336, 0.7218031, -0.1065520],
        [-0.4487736, 0.2898056, 0.0771569],
        [0.0859513, -0.5899859, 0.5011089],
    ]),
    "xyz10": np.array([
        [0.2885613, 0.6597617, -0.1305654],
        [-0.4648864, 0.3262702, 0.0624200],
        [0.0798787, -0.5547976, 0.4814746],
    ]),
}

#: Sum-of-Gaussians parameters per opponent channel: (half-width at half
#: maximum in degrees, weight).  'distribution' = Zhang's released code
#: (ISETCam ``scGaussianParameters`` default).
FILTER_PARAMETERS = {
    "distribution": (
        ((0.05, 1.00327), (0.225, 0.114416), (7.0, -0.117686)),
        ((0.0685, 0.616725), (0.826, 0.383275)),
        ((0.0920, 0.567885), (0.6451, 0.432115)),
    ),
}


def _support_px(samples_per_degree: float) -> int:
    """One degree of support, made odd (41 -> 41, 72 -> 71)."""
    n = int(np.floor(samples_per_degree + 0.5))
    return n if n % 2 == 1 else n - 1


def scielab_filters(samples_per_degree: float, *, parameters: str = "distribution") -> list[np.ndarray]:
    """The three (N, N) S-CIELAB kernels (luminance, red-green, blue-yellow).

    N = one degree in pixels, made odd; each Gaussian has standard deviation
    ``hwhm * spd / sqrt(2 ln 2)`` px, is sampled on the N x N grid centred on
    0 and normalised to sum 1; the weighted sum is normalised to sum 1.

    Examples
    --------
    >>> k = scielab_filters(41)
    >>> [f.shape for f in k], round(float(k[0].sum()), 12)
    ([(41, 41), (41, 41), (41, 41)], 1.0)
    """
    require(np.isfinite(samples_per_degree) and samples_per_degree >= 2,
            f"samples per degree must be at least 2, got {samples_per_degree}")
    require(parameters in FILTER_PARAMETERS, f"unknown S-CIELAB filter set {parameters!r}")
    n = _support_px(samples_per_degree)
    x = np.arange(n) - (n - 1) / 2.0
    kernels = []
    for channel in FILTER_PARAMETERS[parameters]:
        k = np.zeros((n, n))
        for hwhm_deg, weight in channel:
            sd = hwhm_deg * samples_per_degree / np.sqrt(2.0 * np.log(2.0))
            g = np.exp(-(x[:, None] ** 2 + x[None, :] ** 2) / (2.0 * sd * sd))
            k += weight * g / g.sum()
        kernels.append(k / k.sum())
    return kernels


#: ``fft_precision`` -> the real dtype the filtering's transforms use
FFT_PRECISIONS = {"double": np.float64, "single": np.float32}


def _circular(plane: np.ndarray, k: np.ndarray, dtype=np.float64) -> np.ndarray:
    """Circular convolution with a centred kernel (ISETCam's FFT filtering),
    in ``dtype`` (float64: numpy's transforms, as before single precision
    was offered; float32: scipy's, which keep it)."""
    h, w = plane.shape
    half = k.shape[0] // 2
    rows = (np.arange(k.shape[0]) - half) % h
    cols = (np.arange(k.shape[1]) - half) % w
    kp = np.zeros((h, w))
    np.add.at(kp, (rows[:, None], cols[None, :]), k)
    if dtype == np.float64:
        return np.fft.irfft2(np.fft.rfft2(plane) * np.fft.rfft2(kp), s=(h, w))
    from scipy import fft

    return fft.irfft2(fft.rfft2(plane.astype(dtype)) * fft.rfft2(kp.astype(dtype)), s=(h, w))


@functools.lru_cache(maxsize=8)
def _kernel_spectra(samples_per_degree: float, parameters: str, fshape: tuple, dtype=np.float64) -> np.ndarray:
    """(3, fh, fw // 2 + 1) the kernels' real FFTs at the padded size ``fshape``
    (one per image size, viewing geometry and precision, reused for every image)."""
    from scipy import fft

    kernels = np.stack(scielab_filters(samples_per_degree, parameters=parameters)).astype(dtype)
    spectra = fft.rfft2(kernels, s=fshape)
    spectra.flags.writeable = False
    return spectra


def _symmetric_filter(opp: np.ndarray, samples_per_degree: float, parameters: str, n: int,
                      dtype=np.float64) -> np.ndarray:
    """Each opponent plane of ``opp`` (H, W, 3) convolved with its kernel after
    symmetric extension by n // 2, the map of the input's size: what
    ``scipy.signal.fftconvolve(padded, kernel, mode='valid')`` computes per
    plane, returned as (3, H, W) planes (a view).

    The three planes go through one transform, the kernels' transforms are
    kept (:func:`_kernel_spectra`), and the transform is only as long as the
    extended image (next fast length), not the extended image plus the
    kernel: a circular convolution at that length wraps only into outputs
    nearer than n - 1 to the start, and the valid outputs start at n - 1, so
    they equal the linear convolution's (to rounding: 1e-13, checked in
    tests/test_fast_paths.py), with 17 % fewer points on the paper's puppy.
    The transforms run in ``dtype`` (float32: single precision, the planes
    returned in float32)."""
    half = n // 2
    planes = np.pad(np.moveaxis(opp, -1, 0).astype(dtype, copy=False), ((0, 0), (half, half), (half, half)),
                    mode="symmetric")
    return _convolve_extended(planes, opp.shape[:2], samples_per_degree, parameters, n, dtype)


def _transform_shape(h: int, w: int, n: int) -> tuple[int, int]:
    """The transform's size for an (h, w) image extended by n // 2 each side: the next fast lengths."""
    from scipy import fft

    return tuple(fft.next_fast_len(d + 2 * (n // 2), True) for d in (h, w))


def _convolve_extended(planes: np.ndarray, size: tuple[int, int], samples_per_degree: float, parameters: str, n: int,
                       dtype) -> np.ndarray:
    """The (3, H, W) map of ``size`` = (H, W) from the planes of the image
    extended by n // 2 each side (zero-padded up to :func:`_transform_shape`
    or not), each convolved with its kernel at that transform size
    (:func:`_symmetric_filter`'s argument for the length)."""
    from scipy import fft

    h, w = size
    fshape = _transform_shape(h, w, n)
    spectra = _kernel_spectra(samples_per_degree, parameters, fshape, dtype)
    spectrum = fft.rfft2(planes, s=fshape)
    spectrum *= spectra  # in place, and the inverse may overwrite it: no copies of the spectrum
    full = fft.irfft2(spectrum, s=fshape, overwrite_x=True)
    return full[:, n - 1:n - 1 + h, n - 1:n - 1 + w]


def _filtered_difference(test: np.ndarray, ref: np.ndarray, matrix: np.ndarray, samples_per_degree: float,
                         parameters: str, n: int) -> np.ndarray:
    """:func:`_filtered_planes` of ``test - ref`` with symmetric extension and
    float32 transforms, its input made in one compiled pass straight into
    the transform's buffer (:mod:`._scielab_kernel`): (3, H, W) float32."""
    from ._scielab_kernel import opponent_difference_padded

    h, w = test.shape[:2]
    buf = opponent_difference_padded(test, ref, matrix, n // 2, _transform_shape(h, w, n))
    return _convolve_extended(buf, (h, w), samples_per_degree, parameters, n, np.float32)


def _filtered_planes(xyz: np.ndarray, matrix: np.ndarray, kernels, boundary: str, samples_per_degree: float,
                     parameters: str, dtype=np.float64) -> np.ndarray:
    """XYZ (H, W, 3) -> opponent, each channel filtered (transforms in
    ``dtype``): the filtered opponent planes (3, H, W) in ``dtype``."""
    opp = xyz @ matrix.T
    if boundary == "symmetric":
        return _symmetric_filter(opp, samples_per_degree, parameters, kernels[0].shape[0], dtype)
    # ISETCam: wrap-around, and the map shifted by one pixel
    return np.stack([np.roll(_circular(opp[..., c], k, dtype), (-1, -1), axis=(0, 1)) for c, k in enumerate(kernels)])


def _planes_lab(planes: np.ndarray, matrix: np.ndarray, white: np.ndarray, lab_constants: str,
                base: np.ndarray | None = None) -> np.ndarray:
    """CIELAB (H, W, 3) float64 of filtered opponent planes (of ``base +
    planes`` when a float64 ``base`` is given); with CIE constants the sum,
    the return to XYZ and CIELAB in one compiled pass
    (:func:`~cfa_mitsuba.colour_kernels.opponent_lab`)."""
    if lab_constants == "cie":
        from ..colour_kernels import opponent_lab

        return opponent_lab(planes, np.linalg.inv(matrix), white, base=base)
    if base is not None:
        planes = base + planes
    return xyz_to_lab(np.moveaxis(planes, 0, -1) @ np.linalg.inv(matrix).T, white, constants=lab_constants)


@dataclass(frozen=True)
class FilteredReference:
    """What :func:`scielab` keeps of a reference image: its filtered
    opponent planes (3, H, W) and their CIELAB (H, W, 3), both float64
    (:func:`scielab_reference`)."""

    planes: np.ndarray
    lab: np.ndarray


def _crop_isetcam(img: np.ndarray, n: int) -> np.ndarray:
    """ISETCam's crop: the last row/column dropped where (size - n) is odd."""
    h, w = img.shape[:2]
    return img[:h - (h - n) % 2, :w - (w - n) % 2]


def scielab_reference(reference_xyz, white_xyz, *, samples_per_degree: float, matrix: str = "xyz2",
                      parameters: str = "distribution", lab_constants: str = "cie",
                      boundary: str = "symmetric") -> FilteredReference:
    """The half of :func:`scielab` that depends on the reference alone, in
    double precision: pass it as ``reference_lab`` when one reference is
    compared with many test images (same arguments; any ``fft_precision``)."""
    ref = as_image(reference_xyz, "reference image")
    kernels = scielab_filters(samples_per_degree, parameters=parameters)
    if boundary == "isetcam":
        ref = _crop_isetcam(ref, kernels[0].shape[0])
    m = OPPONENT_MATRICES[matrix]
    planes = _filtered_planes(ref, m, kernels, boundary, samples_per_degree, parameters)
    return FilteredReference(planes, _planes_lab(planes, m, as_white(white_xyz), lab_constants))


def scielab_reference_lab(reference_xyz, white_xyz, **options) -> np.ndarray:
    """The spatially filtered reference in CIELAB (:func:`scielab_reference`'s
    ``lab``; the same keywords)."""
    return scielab_reference(reference_xyz, white_xyz, **options).lab


def _fft_dtype(fft_precision: str):
    require(fft_precision in FFT_PRECISIONS,
            f"unknown fft_precision {fft_precision!r} (expected {' or '.join(map(repr, FFT_PRECISIONS))})")
    return FFT_PRECISIONS[fft_precision]


def scielab(reference_xyz, test_xyz, white_xyz, *, samples_per_degree: float, matrix: str = "xyz2",
            version: str = "2000", parameters: str = "distribution", lab_constants: str = "cie",
            boundary: str = "symmetric", fft_precision: str = "double", reference_lab=None,
            order_statistics: bool = True) -> MetricResult:
    """S-CIELAB colour difference map and its mean.

    Parameters
    ----------
    reference_xyz, test_xyz : (H, W, 3) CIE 1931 XYZ on a common scale
        (reference = the ideal image).
    white_xyz : (3,) white point on the same scale.
    samples_per_degree : pixels per degree of visual angle; for our scenes
        image width in pixels / horizontal field of view in degrees (the
        paper's PUPPY: 720 px / 10 deg = 72).
    matrix : ``'xyz2'`` (default: our XYZ is CIE 1931 2-degree) or
        ``'xyz10'`` (ISETCam's default).
    version : ``'2000'`` (CIEDE2000, default, as ISETCam) or ``'1976'``.
    parameters : the filter set; only ``'distribution'``.
    lab_constants : ``'cie'`` (exact CIE constants, default) or ``'isetcam'``
        (ISETCam's rounded ones), see :func:`~cfa_mitsuba.metrics.colourspace.xyz_to_lab`.
    boundary : ``'symmetric'`` (default: symmetric extension, a map of the
        input's size registered to it) or ``'isetcam'`` (ISETCam's
        ``scielab.m`` exactly: the last row/column dropped when (size - N) is
        odd, circular convolution, the map shifted by one pixel; only to
        reproduce ISETCam's whole-map numbers).  ``mean_interior`` is the same
        for both.
    fft_precision : ``'double'`` (default: ISETCam's numbers to 1e-12) or
        ``'single'``: the test image is filtered as the reference's filtered
        planes (double) plus the filtered difference (test - reference),
        whose transforms run in float32.  Filtering is linear, so only the
        rounding differs, and it scales with the difference, not the image:
        about twice as fast per test image, the dE map moves by less than
        1e-5 dE00 (tests/metrics/test_scielab.py).  A study uses ``'single'`` unless
        its ``[metrics.scielab]`` says otherwise (the record's
        ``study_options``; docs/study.md).
    reference_lab : optional, :func:`scielab_reference` (or its CIELAB,
        :func:`scielab_reference_lab`) of this reference with the same
        arguments: a speed-up only, the result is identical.
    order_statistics : whether the details hold the map's ``median`` and
        ``p95`` (default); False leaves them None and saves a partial sort of
        the whole map (8 ms on the paper's puppy), which a study does for
        the camera outputs whose details it does not keep (the record's
        ``summary_options``).  The headline and ``mean_interior`` are the same.

    Returns
    -------
    MetricResult
        Headline: the mean of the whole dE map (unit ``'dE00'``/``'dE76'``).
        Details: ``map`` (H, W), ``mean_interior`` (over the pixels at least
        one degree, ``b = round(spd)`` px, from every border; ``None`` when the
        image is smaller than 2b + 1), ``interior_rect``, ``median``, ``p95``,
        ``max``, ``samples_per_degree``, ``support_px``, ``matrix``,
        ``version``.

    References
    ----------
    X. Zhang, B. A. Wandell, "A spatial extension of CIELAB for digital
    color image reproduction", SID Digest 27 (1996) 731-734; Bae 2020 s. 2.2.2.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> img = 20 + 60 * rng.random((48, 48, 3))
    >>> float(scielab(img, img, [95.05, 100, 108.9], samples_per_degree=20))
    0.0
    """
    require(matrix in OPPONENT_MATRICES, f"unknown opponent matrix {matrix!r} (expected 'xyz2' or 'xyz10')")
    require(version in ("2000", "1976"), f"unknown dE version {version!r} (expected '2000' or '1976')")
    require(boundary in ("symmetric", "isetcam"), f"unknown boundary {boundary!r} (expected 'symmetric' or 'isetcam')")
    dtype = _fft_dtype(fft_precision)
    ref, test = as_pair(reference_xyz, test_xyz)
    white = as_white(white_xyz)
    kernels = scielab_filters(samples_per_degree, parameters=parameters)
    m = OPPONENT_MATRICES[matrix]
    h_in, w_in = ref.shape[:2]
    if boundary == "isetcam":
        ref, test = _crop_isetcam(ref, kernels[0].shape[0]), _crop_isetcam(test, kernels[0].shape[0])
    fref = reference_lab
    if fref is None or (dtype != np.float64 and not isinstance(fref, FilteredReference)):
        fref = scielab_reference(ref, white, samples_per_degree=samples_per_degree, matrix=matrix,
                                 parameters=parameters, lab_constants=lab_constants, boundary=boundary)
    lab_r = fref.lab if isinstance(fref, FilteredReference) else np.asarray(fref, dtype=np.float64)
    require(lab_r.shape == ref.shape, f"reference_lab has shape {lab_r.shape}, the reference {ref.shape}")
    if dtype == np.float64:
        lab_t = _planes_lab(_filtered_planes(test, m, kernels, boundary, samples_per_degree, parameters), m, white,
                            lab_constants)
    else:  # the reference's planes (double) + the filtered difference (single): the rounding scales with it
        if boundary == "symmetric":
            diff = _filtered_difference(test, ref, m, samples_per_degree, parameters, kernels[0].shape[0])
        else:
            diff = _filtered_planes(test - ref, m, kernels, boundary, samples_per_degree, parameters, dtype)
        lab_t = _planes_lab(diff, m, white, lab_constants, base=fref.planes)
    de_map = delta_e_2000(lab_r, lab_t) if version == "2000" else delta_e_1976(lab_r, lab_t)

    b = int(np.floor(samples_per_degree + 0.5))
    # interior: input rows/cols b .. size-b-1; ISETCam's map index = input index - 1
    o = 1 if boundary == "isetcam" else 0
    interior = de_map[max(b - o, 0):h_in - b - o, max(b - o, 0):w_in - b - o] if min(h_in, w_in) > 2 * b else de_map[:0]
    require(isinstance(order_statistics, (bool, np.bool_)),
            f"order_statistics must be true or false, got {order_statistics!r}")
    stats = summarise_array(de_map, order_statistics=bool(order_statistics))
    details = {
        "map": de_map,
        "mean_interior": float(interior.mean()) if interior.size else None,
        "interior_rect": [b, b, h_in - b, w_in - b] if interior.size else None,
        "median": stats["median"], "p95": stats["p95"], "max": stats["max"],
        "samples_per_degree": float(samples_per_degree),
        "support_px": kernels[0].shape[0],
        "matrix": matrix, "version": version, "boundary": boundary, "fft_precision": fft_precision,
    }
    return MetricResult(stats["mean"], name="scielab", unit="dE00" if version == "2000" else "dE76",
                        details=details)


#: This module's metric records (collected by :mod:`.registry`).
_SCIELAB = MetricRecord(
    name="scielab", function=scielab, scenes=(NATURAL,), inputs="xyz", unit="dE00", higher_is_better=False,
    identical_value=0.0,
    scored=True, label="S-CIELAB", order=2, decimals=2, paper="ΔEs (s. 2.2.2, Fig 10)", score_range=(9.5, 2.5),
    range_units=("dE00", "dE76"), reference_cache=("reference_lab", scielab_reference),
    study_options=(("fft_precision", "single"),), summary_options=(("order_statistics", False),),
    description="colour reproduction error, mean S-CIELAB ΔE00 over the image (Zhang-Wandell)",
    practical_difference=(("dE00", 0.8), ("dE76", 2.3)),
    practical_source=PRACTICAL_DE + " (S-CIELAB is CIELAB on uniform areas: Zhang & Wandell 1997)")
RECORDS = (
    _SCIELAB,
    _SCIELAB.detail("mean_interior", name="scielab-interior", unit="dE00", label="S-CIELAB interior", order=105,
                    decimals=2, description="S-CIELAB mean ΔE00 away from the image border"),
)
