"""What a metric is, as the study, the command line and the report see it.

Each metric module defines its pure function and, beside it, its
:class:`MetricRecord` (``RECORDS``); :mod:`.registry` collects them.  The
pattern is colour-science's ``DELTA_E_METHODS`` + ``filter_kwargs``: a
record names the function, one generic adapter
(:func:`.registry.evaluate`) fills its arguments by name.
"""

from __future__ import annotations

__all__ = ["MetricRecord", "NATURAL", "INPUT_KINDS"]

from dataclasses import dataclass
from typing import Any, Callable

from ..values import NATURAL  # the kind of a natural scene (puppy, user XML, measured image)

#: What a metric function takes positionally, by the record's ``inputs``:
#: 'xyz' (reference XYZ, test XYZ, white XYZ), 'srgb8' (reference and test
#: 8-bit sRGB code values), 'linear' (the test image in linear sRGB with the
#: white at 1; a ``reference`` keyword, when the function has one, gets the
#: ideal's).
INPUT_KINDS = ("xyz", "srgb8", "linear")


@dataclass(frozen=True, kw_only=True)
class MetricRecord:
    """A metric, as the study, the command line and the report see it.

    Attributes
    ----------
    name : the command-line name (``'delta-e'``).
    function : the pure metric function (``metrics.delta_e``), or None for a
        value read from another metric's details (``parent``, ``detail_key``).
    scenes : the scene kinds that feed it (:attr:`cfa_mitsuba.render.Scene.kind`):
        a chart's kind (``'macbeth'``, ``'slanted-edge'``, ...) or
        :data:`NATURAL` for any natural scene.  This is the one place that
        says which scenes feed which metric.
    inputs : one of :data:`INPUT_KINDS`.
    unit : unit of the headline value ('' for unitless indices).
    higher_is_better : direction of "better".
    identical_value : the value when the camera image is the reference
        itself (its best: 0 for an error, 1 for a similarity); None for a
        metric that measures the camera image alone (sharpness, moire,
        noise, texture against the chart's exact pattern).  The generic
        metric tests hold every metric to it.
    scored : whether it enters the normalised scores (the paper's eight).
    label, description, decimals, paper : how tables and plots show it.
    order : position in tables (the paper's section order; secondary values
        after the scored ones).
    score_range : eq. 8's default (worst, best), the paper's printed range;
        None for unscored metrics.
    range_units : the units the range applies to (default: ``unit``).
    range_scaling : how the default range follows the study's geometry:
        None (as printed); ``'pixel_pitch'`` (printed at 2.2 um, moved so the
        same cycles per pixel score the same); ``'chirp_cy_px'`` (the range
        is in cycles per camera pixel, times the chirp's samples per degree).
    parent, detail_key : for a secondary value (``delta-l``): the metric
        whose details hold it and the key.
    censored_key : the details key (a bool) that says the headline is a
        bound, not a measurement; None for metrics always measured.
    ideal_details : whether the study keeps this metric's curves of the
        ideal sensor too (the MTF: the report draws camera against ideal).
    reference_cache : optional ``(keyword, function)``: ``function(reference,
        white, **options)`` (``function(reference, **options)`` for metrics of
        two display images) computes what depends on the reference image alone
        (S-CIELAB's filtered reference, ``('reference_lab',
        scielab_reference)``; SSIM's window means; MDSI's and HaarPSI's
        reference maps); the adapter calls it once per ideal image
        and option set (the options it takes) and passes the result to the
        metric as ``keyword``.
    study_options : ``((keyword, value), ...)``: options a study passes to
        ``function`` unless its ``[metrics.<name>]`` table sets them (S-CIELAB's
        ``fft_precision = 'single'``: the same numbers to 1e-5 dE00 in about half
        the filtering time); a direct call gets the function's own defaults.
    practical_difference : ``((unit, amount), ...)``: the smallest difference
        of the headline value that matters to a user, per unit the value
        may be in (``'%'``: a share of the value itself); a decision names a
        best CFA only when its lead is at least this large
        (study/decisions.py).  ``practical_source`` says where each amount
        comes from (a published threshold, or our choice and why).
    reads : ``reads(geometry, shape, options, reference_xyz, white_xyz) ->
        [(y0, x0, y1, x1), ...]``: the rectangles of the camera image
        (half-open pixel bounds) its values read, given the scene geometry,
        the image's (H, W), the metric's options and the ideal image and
        white (a region chosen on the ideal: the gray bar's mid-grey); None (the default, or returned): the whole image.
        A study demosaics and measures only these regions and each method's
        support around them (study/roi.py); the metric then gets an image
        whose other pixels hold the ideal's.
    decibels : the value is an amplitude ratio (an SNR): tables give
        ``20 log10`` of it in dB beside the ratio (metrics.csv's
        ``value_db``, ``ci_low_db``, ``ci_high_db``).
    summary_options : ``((keyword, value), ...)``: options that leave out of
        the details what only the details files read, passed by a study for
        every camera output whose details it does not keep (the realisations
        after the first), unless its ``[metrics.<name>]`` table sets them
        (S-CIELAB's ``order_statistics = False``: the map's median and 95th
        percentile, a partial sort of the whole map).  They never change a
        row of metrics.csv.
    """

    name: str
    function: Callable | None
    scenes: tuple[str, ...]
    inputs: str
    unit: str
    higher_is_better: bool
    scored: bool
    identical_value: float | None = None
    label: str
    description: str
    order: int = 1000
    decimals: int = 3
    paper: str = "—"
    score_range: tuple[float, float] | None = None
    range_scaling: str | None = None
    range_units: tuple[str, ...] | None = None
    parent: str | None = None
    detail_key: str | None = None
    censored_key: str | None = None
    ideal_details: bool = False
    reference_cache: tuple[str, Callable[..., Any]] | None = None
    study_options: tuple[tuple[str, Any], ...] = ()
    summary_options: tuple[tuple[str, Any], ...] = ()
    practical_difference: tuple[tuple[str, float], ...] = ()
    practical_source: str = ""
    decibels: bool = False
    reads: Callable[..., Any] | None = None

    def __post_init__(self):
        if self.inputs not in INPUT_KINDS:
            raise ValueError(f"metric {self.name!r}: inputs must be one of {INPUT_KINDS}, got {self.inputs!r}")
        if (self.function is None) == (self.parent is None):
            raise ValueError(f"metric {self.name!r}: give a function, or a parent and detail_key (not both)")

    def practical(self, unit: str, typical: float | None = None) -> float | None:
        """The practical difference in ``unit`` (None when the record gives
        none for it); a relative one (``'%'``) is taken of ``typical`` (the
        value it applies to; None: not known, None returned).

        >>> MetricRecord(name="t", function=abs, scenes=("x",), inputs="xyz", unit="cy/mm", higher_is_better=True,
        ...              scored=True, label="t", description="", practical_difference=(("%", 5.0),)).practical("cy/mm", 80.0)
        4.0
        """
        table = dict(self.practical_difference)
        if unit in table:
            return float(table[unit])
        if "%" in table and typical is not None and typical == typical:
            return abs(float(typical)) * float(table["%"]) / 100.0
        return None

    @property
    def secondary(self) -> bool:
        return self.parent is not None

    def detail(self, detail_key: str, **fields) -> "MetricRecord":
        """A value read from this metric's details (``detail_key``), reported
        but not scored: a record with this one's scenes and inputs, the
        ``fields`` given (name, unit, label, description, ...)."""
        base = {"function": None, "scenes": self.scenes, "inputs": self.inputs, "scored": False,
                "higher_is_better": False, "parent": self.name, "detail_key": detail_key}
        return MetricRecord(**{**base, **fields})
