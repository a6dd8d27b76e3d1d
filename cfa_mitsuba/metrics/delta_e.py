"""Colour accuracy on the Macbeth chart: CIE 1976 dE*ab and CIEDE2000 per patch
(Bae 2020 s. 2.2.1, Table 1, Figs 8-9; ISETCam ``macbethColorError``)."""

from __future__ import annotations

__all__ = ["RECORDS", "delta_e"]

import numpy as np

from ..errors import require
from ._common import as_pair, as_white
from ._result import MetricResult, summarise_array
from .colourspace import delta_e_1976, delta_e_2000, xyz_to_lab, xyz_to_xy
from .record import MetricRecord

_VERSIONS = ("2000", "1976")
#: Grey patches of the 24-patch ColorChecker in reading order (last row).
GREY_PATCHES = tuple(range(18, 24))
#: The white patch of the 24-patch ColorChecker in reading order.
WHITE_PATCH = 18


def _stats(values: np.ndarray) -> dict:
    s = summarise_array(values)
    return {"mean": s["mean"], "median": s["median"], "p95": s["p95"], "max": s["max"], "n": int(values.size)}


def delta_e(reference_xyz, test_xyz, white_xyz, *, patches=None, grey_patches=None,
            version: str = "2000", lab_constants: str = "cie", white: str = "scene",
            white_patch: int = WHITE_PATCH) -> MetricResult:
    """Colour difference between an ideal and a camera XYZ image.

    Parameters
    ----------
    reference_xyz, test_xyz : (H, W, 3) CIE 1931 XYZ, any common absolute
        scale (ours: Y in cd/m^2); reference = the ideal sensor.
    white_xyz : (3,) the scene white on the same scale (CIELAB's white).
    patches : sequence of rectangles ``(y0, x0, y1, x1)``, half-open pixel
        bounds of each patch *interior* (the sidecar's ``interior_rect``,
        divided by the oversampling factor).  Each patch's mean XYZ is taken
        and compared in CIELAB.  ``None``: compare pixel by pixel.
    grey_patches : indices into ``patches`` of the achromatic patches for
        the mean |dL*|; default the last row (18..23) when 24 patches are
        given, none otherwise.
    version : ``'2000'`` (CIEDE2000, ISETCam's default and our headline) or
        ``'1976'`` (the paper's Euclidean dE*ab).  Both are always reported.
    lab_constants : ``'cie'`` (exact CIE constants, default) or ``'isetcam'``
        (ISETCam's rounded ones), see :func:`~cfa_mitsuba.metrics.colourspace.xyz_to_lab`.
    white : CIELAB's white: ``'scene'`` (``white_xyz``, default) or
        ``'white-patch'`` (ISETCam's ``macbethColorError``: the reference's
        white patch is the white and the test is scaled so that its white
        patch has the reference's Y; needs ``patches``).
    white_patch : index of the white patch in ``patches`` (18, the
        ColorChecker's in reading order).

    Returns
    -------
    MetricResult
        Headline: the mean over patches (or pixels) of dE in ``version``;
        unit ``'dE00'`` or ``'dE76'``.  Details with patches: ``de2000`` and
        ``de1976`` per patch (24,), their means ``mean_de2000`` /
        ``mean_de1976``, ``mean_dl_grey`` (mean |dL*| over the grey patches),
        ``lab_reference`` / ``lab_test`` (N, 3) and ``xy_reference`` /
        ``xy_test`` (N, 2).  Without patches: ``de2000`` / ``de1976`` maps and
        their ``mean, median, p95, max, n`` statistics (``stats2000``,
        ``stats1976``).

    References
    ----------
    Bae 2020, s. 2.2.1; CIE 015:2018 (CIELAB, eq. 8.x); Sharma, Wu & Dalal,
    Color Res. Appl. 30 (2005) 21-30 (CIEDE2000).

    Examples
    --------
    >>> img = np.full((4, 4, 3), [40.0, 42.0, 45.0])
    >>> float(delta_e(img, img, [95.05, 100.0, 108.9]))
    0.0
    >>> r = delta_e(img, img * [1.02, 1.0, 1.0], [95.05, 100.0, 108.9], patches=[(0, 0, 4, 4)])
    >>> round(r.details["mean_de1976"], 3), r.unit
    (2.481, 'dE00')
    """
    require(version in _VERSIONS, f"unknown dE version {version!r} (expected '2000' or '1976')")
    require(white in ("scene", "white-patch"), f"unknown white {white!r} (expected 'scene' or 'white-patch')")
    require(white == "scene" or patches is not None, "white 'white-patch' needs the chart's patches")
    ref, test = as_pair(reference_xyz, test_xyz)
    lab_white = as_white(white_xyz)
    unit = "dE00" if version == "2000" else "dE76"
    key = "de2000" if version == "2000" else "de1976"

    if patches is None:
        lab_r, lab_t = (xyz_to_lab(ref, lab_white, constants=lab_constants),
                        xyz_to_lab(test, lab_white, constants=lab_constants))
        d00, d76 = delta_e_2000(lab_r, lab_t), delta_e_1976(lab_r, lab_t)
        details = {"de2000": d00, "de1976": d76, "stats2000": _stats(d00), "stats1976": _stats(d76),
                   "mode": "per-pixel"}
        return MetricResult(details[f"stats{version}"]["mean"], name="delta-e", unit=unit, details=details)

    rects = [tuple(int(v) for v in p) for p in patches]
    require(len(rects) > 0, "patches is empty")
    h, w = ref.shape[:2]
    mean_r, mean_t = [], []
    for i, (y0, x0, y1, x1) in enumerate(rects):
        require(0 <= y0 < y1 <= h and 0 <= x0 < x1 <= w,
                f"patch {i} rectangle {[y0, x0, y1, x1]} is empty or outside the {h} x {w} image")
        mean_r.append(ref[y0:y1, x0:x1].reshape(-1, 3).mean(axis=0))
        mean_t.append(test[y0:y1, x0:x1].reshape(-1, 3).mean(axis=0))
    xyz_r, xyz_t = np.array(mean_r), np.array(mean_t)
    if white == "white-patch":
        require(0 <= int(white_patch) < len(rects), f"white patch {white_patch} outside 0..{len(rects) - 1}")
        lab_white = xyz_r[int(white_patch)]
        require(lab_white[1] > 0 and xyz_t[int(white_patch), 1] > 0, "the white patch is black")
        xyz_t = xyz_t * (lab_white[1] / xyz_t[int(white_patch), 1])
    lab_r, lab_t = (xyz_to_lab(xyz_r, lab_white, constants=lab_constants),
                    xyz_to_lab(xyz_t, lab_white, constants=lab_constants))
    d00, d76 = delta_e_2000(lab_r, lab_t), delta_e_1976(lab_r, lab_t)
    if grey_patches is None:
        grey_patches = GREY_PATCHES if len(rects) == 24 else ()
    grey = [int(i) for i in grey_patches]
    require(all(0 <= i < len(rects) for i in grey), f"grey patch indices {grey} outside 0..{len(rects) - 1}")
    dl = np.abs(lab_t[grey, 0] - lab_r[grey, 0]) if grey else np.zeros(0)
    details = {
        "mode": "patches",
        "de2000": d00, "de1976": d76,
        "mean_de2000": float(d00.mean()), "mean_de1976": float(d76.mean()),
        "mean_dl_grey": float(dl.mean()) if grey else None,
        "dl_grey": dl, "grey_patches": grey,
        "lab_reference": lab_r, "lab_test": lab_t,
        "xy_reference": xyz_to_xy(xyz_r), "xy_test": xyz_to_xy(xyz_t),
        "xyz_reference": xyz_r, "xyz_test": xyz_t,
    }
    return MetricResult(details[f"mean_{key}"], name="delta-e", unit=unit, details=details)


#: The smallest colour difference that matters (the ΔE records' ``practical_source``).
PRACTICAL_DE = ("0.8 dE00: the 50:50 % perceptibility threshold of CIEDE2000 (Paravina et al. 2015, "
                "J. Esthet. Restor. Dent. 27 S1:S1-S9, adopted by ISO/TR 28642:2016); 2.3 dEab (dE76): the "
                "just noticeable difference of CIELAB (Mahy, Van Eycken & Oosterlinck 1994, Color Res. Appl. "
                "19:105-121; colour-science's JND_CIE1976)")

def _reads(geometry: dict, shape, options: dict, reference_xyz=None, white_xyz=None) -> list | None:
    """The patch interiors; None (the whole image) without patches."""
    patches = options.get("patches", geometry.get("patches"))
    return None if patches is None else [tuple(p) for p in patches]


#: This module's metric records (collected by :mod:`.registry`).
_DELTA_E = MetricRecord(
    name="delta-e", function=delta_e, scenes=("macbeth",), inputs="xyz", unit="dE00", higher_is_better=False,
    reads=_reads,
    identical_value=0.0,
    scored=True, label="ΔE00", order=1, decimals=2, paper="ΔE (s. 2.2.1, Fig 8)", score_range=(6.0, 2.2),
    range_units=("dE00", "dE76"), description="colour error, mean CIEDE2000 over the 24 ColorChecker patches",
    practical_difference=(("dE00", 0.8), ("dE76", 2.3), ("dEab", 2.3)),
    practical_source=PRACTICAL_DE)
RECORDS = (
    _DELTA_E,
    # values read from delta-e's details: reported, not scored
    _DELTA_E.detail("mean_de1976", name="delta-e76", unit="dEab", label="ΔE*ab", order=101, decimals=2,
                    description="colour error, mean CIE 1976 ΔE*ab over the 24 patches"),
    _DELTA_E.detail("mean_dl_grey", name="delta-l", unit="L*", label="ΔL grey", order=102, decimals=2,
                    paper="Table 1",
                    description="mean |ΔL*| over the six grey patches (the paper's Table 1 'Mean ΔL')"),
)
