"""The study axes: one record per named value a study can sweep.

An :class:`Axis` says everything the program needs to know about one axis:
its name (the metrics.csv column and the ``[[sweep]]`` key), how a value is
checked, where it applies in the camera chain, its label and unit in tables
and figures, the short prefix it gets in file names, and where its default
comes from (the stage's own parameters: never a second copy of a default).

Where an axis applies (``applies_to``):

============  ================================================================
``optics``    a field of :class:`~cfa_mitsuba.optics.OpticsParams` (``field``)
``sensor``    a field of :class:`~cfa_mitsuba.sensor.params.SensorParams`
``isp``       a keyword of :func:`cfa_mitsuba.isp.process` (``field``)
``metric``    an option of one metric's function (``field`` = ``'metric.option'``)
``capture``   an argument of the capture itself: the scene luminance, the
              exposure, the noise seed, the CFA's spectra set (the chain
              passes each where it belongs)
============  ================================================================

An axis record also carries its behaviour, so that no code names an axis
to special-case it: whether its values are numbers (a line in the sweep
figure) or categories (ticks), whether they are a scale or realisations,
the value in effect when a condition leaves it to the scene (the f-number a
render's sidecar records), the render setting it also sets on a 3D scene
(thin-lens defocus), and which CFAs a value applies to (a block read-out).

Adding an axis is one record in :data:`AXES` (and its test); the config
check, the sweep, the chain, the tables and the report follow.  Sweeping a
sensor field, for instance::

    Axis(name="well_capacity_e", applies_to="sensor", field="well_capacity_e",
         label="well capacity", unit="e⁻", short="wc", check=positive)
"""

from __future__ import annotations

__all__ = ["Axis", "AXES", "axis_unit", "axis_label", "register_axis", "unregister_axis", "get_axis"]

import dataclasses
import inspect
from dataclasses import dataclass
from typing import Any, Callable

from ..errors import CfaMitsubaError

APPLIES_TO = ("optics", "sensor", "isp", "metric", "capture")


def positive(ck, v, key):
    return ck.number(v, key, positive=True)


def non_negative(ck, v, key):
    return ck.number(v, key, nonneg=True)


def _f_number(ck, v, key):
    from ..optics import OpticsParams

    x = ck.number(v, key, positive=True, maximum=1000.0)
    try:  # the lens's own physical bound (optics.lens.MIN_F_NUMBER), with its reason
        OpticsParams(f_number=x)
    except CfaMitsubaError as exc:
        ck.fail(key, str(exc))
    return x


def _pixel_pitch(ck, v, key):
    from ..sensor.params import SensorParams

    x = ck.number(v, key, positive=True)
    try:  # the pixel's own physical bound (sensor.params.MIN_PIXEL_PITCH_UM), with its reason
        SensorParams(pixel_pitch_um=x)
    except CfaMitsubaError as exc:
        ck.fail(key, str(exc))
    return x


def _exposure(ck, v, key):
    return v if v == "auto" else ck.number(v, key, positive=True)


def _seed(ck, v, key):
    return ck.integer(v, key, 0)


def _spectra(ck, v, key):
    from ..sensor import list_spectra_sets

    return ck.string(v, key, tuple(list_spectra_sets()))


def _readout(ck, v, key):
    from ..sensor.params import READOUT_MODES

    return ck.string(v, key, READOUT_MODES)


def _isp_setting(kind: str):
    """The check of a ``denoise`` or ``sharpen`` value: ``NAME`` or
    ``NAME:AMOUNT`` (:func:`cfa_mitsuba.isp.denoise.denoise_setting`,
    :func:`cfa_mitsuba.isp.sharpen.sharpen_setting`), returned in its one
    spelling (so a sweep cannot list one setting twice)."""

    def check(ck, v, key):
        from .. import isp

        spell = isp.denoise_setting_name if kind == "denoise" else isp.sharpen_setting_name
        known = isp.list_denoisers() if kind == "denoise" else isp.list_sharpeners()
        if not isinstance(v, str) or not v:
            ck.fail(key, f"must be a {kind} method's name or NAME:AMOUNT (known: {', '.join(n for n, _ in known)}), "
                         f"got {type(v).__name__} {v!r}")
        try:
            return spell(v)
        except CfaMitsubaError as exc:
            ck.fail(key, str(exc))

    check.__name__ = f"_{kind}_setting"
    return check


def _isp_keywords(kind: str):
    """A ``denoise`` or ``sharpen`` value as :func:`cfa_mitsuba.isp.process`'s
    keywords: the method and its options (``{'denoise': 'nl-means',
    'denoise_options': {'scale': 2.0}}``)."""

    def keywords(value) -> dict:
        from .. import isp

        name, options = (isp.denoise_setting if kind == "denoise" else isp.sharpen_setting)(value)
        return {kind: name, f"{kind}_options": options}

    keywords.__name__ = f"_{kind}_keywords"
    return keywords


def _readout_applies(pattern, mode) -> bool:
    """``full`` reads any CFA; ``remosaic`` and ``bin`` the block layouts only."""
    from ..sensor.readout import readout_applies

    return readout_applies(pattern, mode)


def _optics_f_number(meta: dict):
    """The f-number the optics used (the render's sidecar, else the optics default)."""
    return (meta.get("optics") or {}).get("f_number")


@dataclass(frozen=True, kw_only=True)
class Axis:
    """One study axis.

    Attributes
    ----------
    name : the metrics.csv column and the ``[[sweep]]`` key.
    applies_to : one of ``optics``, ``sensor``, ``isp``, ``metric``,
        ``capture`` (the module docstring says what each means).
    field : the parameter it sets: an OpticsParams or SensorParams field, an
        :func:`~cfa_mitsuba.isp.process` keyword, ``'metric.option'``; for a
        ``capture`` axis, the name the chain knows it by (its own name).
    label, unit : how tables and figures name it.
    short : its prefix in condition labels (file names: ``L100_f8``).
    check : ``check(checker, value, key) -> value``: one value of a
        ``[[sweep]]`` list checked (the config's one-line errors).
    default : the default for a ``capture`` axis (the others read theirs
        from the stage's parameters, :meth:`default_value`).
    numeric : whether the values are numbers on a scale (a line against
        them in the sweep figure) or categories (one tick each); a numeric
        axis may still hold a word ('auto' exposure), drawn as categories.
    realisations : whether each value is a realisation of the same camera
        (the noise seed), not a setting: points, not a line.
    note : a sentence the sweep figure's caption adds about this axis.
    scene_value : for an axis a condition may leave to the scene (None),
        ``scene_value(meta)`` reads the value in effect from the ideal
        image's meta (metrics.csv records that value).
    render_setting : the render setting the axis also sets on a
        path-traced (3D) scene, when a condition gives a value (the
        f-number: the thin lens's defocus); None: renders do not depend on it.
    cfa_applies : ``cfa_applies(pattern, value) -> bool``: whether a value
        applies to a CFA (its tile of filter names); a CFA a value does not
        apply to is left out of that condition.  None: every value, every CFA.
    isp_keywords : for an ``isp`` axis whose value is a setting rather than
        one keyword (``'nl-means:2'``), ``isp_keywords(value) -> {keyword:
        value}`` of :func:`~cfa_mitsuba.isp.process`; None: ``{field: value}``.
    """

    name: str
    applies_to: str
    label: str
    unit: str
    short: str
    check: Callable[[Any, Any, str], Any]
    field: str = ""
    default: Any = None
    numeric: bool = True
    realisations: bool = False
    note: str = ""
    scene_value: Callable[[dict], Any] | None = None
    render_setting: str | None = None
    cfa_applies: Callable[[Any, Any], bool] | None = None
    isp_keywords: Callable[[Any], dict] | None = None

    def __post_init__(self):
        if self.applies_to not in APPLIES_TO:
            raise ValueError(f"axis {self.name!r}: applies_to must be one of {APPLIES_TO}")
        if not self.field:
            object.__setattr__(self, "field", self.name)

    def default_value(self):
        """The value the stage uses when nothing sets the axis: the
        parameter's own default (OpticsParams, SensorParams, the ISP's or the
        metric function's keyword), or the record's ``default`` for a capture
        axis."""
        if self.applies_to == "optics":
            from ..optics import OpticsParams

            return _dataclass_default(OpticsParams, self.field)
        if self.applies_to == "sensor":
            from ..sensor.params import SensorParams

            return _dataclass_default(SensorParams, self.field)
        if self.applies_to == "isp":
            from ..isp import process

            return inspect.signature(process).parameters[self.field].default
        if self.applies_to == "metric":
            from ..metrics import metric_parameters

            metric, option = self.field.split(".", 1)
            return metric_parameters(metric)[option].default
        return self.default

    def value_in(self, settings) -> Any:
        """The axis's value in a study's :class:`~.chain.ChainSettings` (the
        config's base value: its ``[optics]``, ``[sensor]``, ``[isp]`` or
        ``[metrics.<name>]`` entry, else the stage default)."""
        if self.applies_to == "optics":
            return getattr(settings.optics, self.field)
        if self.applies_to == "sensor":
            return getattr(settings.sensor, self.field)
        if self.applies_to == "isp":
            return dict(settings.isp).get(self.field, self.default_value())
        if self.applies_to == "metric":
            metric, option = self.field.split(".", 1)
            return settings.options_of_metrics().get(metric, {}).get(option, self.default_value())
        return self.default

    def in_effect(self, value, meta: dict):
        """The value in effect: ``value``, or the scene's own when the
        condition left it to the scene (:attr:`scene_value`)."""
        if value is None and self.scene_value is not None:
            return self.scene_value(meta)
        return value

    def applies(self, pattern, value) -> bool:
        """Whether ``value`` applies to a CFA of tile ``pattern`` (:attr:`cfa_applies`)."""
        return self.cfa_applies is None or bool(self.cfa_applies(pattern, value))


def _dataclass_default(cls, name: str):
    for f in dataclasses.fields(cls):
        if f.name == name:
            if f.default is not dataclasses.MISSING:
                return f.default
            return f.default_factory()  # type: ignore[misc]
    raise CfaMitsubaError(f"{cls.__name__} has no field {name!r}")


#: The axes, in metrics.csv column order (luminance first: the paper's sweep).
AXES: dict[str, Axis] = {a.name: a for a in (
    Axis(name="luminance", applies_to="capture", label="luminance", unit="cd/m²", short="L", check=positive,
         default=100.0),
    Axis(name="f_number", applies_to="optics", label="f-number", unit="", short="f", check=_f_number,
         scene_value=_optics_f_number, render_setting="f_number",
         note="The f-number sets both the diffraction OTF and, for a 3D scene, the thin-lens defocus of its render."),
    Axis(name="pixel_pitch_um", applies_to="sensor", label="pixel pitch", unit="µm", short="p", check=_pixel_pitch),
    Axis(name="exposure", applies_to="capture", label="exposure time", unit="s", short="t", check=_exposure,
         default="auto"),
    Axis(name="read_noise_e", applies_to="sensor", label="read noise", unit="e⁻", short="rn", check=non_negative),
    Axis(name="seed", applies_to="capture", label="noise seed (realisation)", unit="", short="seed", check=_seed,
         default=0, realisations=True,
         note="Each point is one noise realisation of the same camera: their spread is the noise of the value."),
    Axis(name="spectra", applies_to="capture", label="spectra set", unit="", short="s-", check=_spectra,
         numeric=False),
    Axis(name="readout", applies_to="sensor", label="read-out mode", unit="", short="ro-", check=_readout,
         numeric=False, cfa_applies=_readout_applies),
    Axis(name="denoise", applies_to="isp", label="noise reduction", unit="", short="dn-",
         check=_isp_setting("denoise"), numeric=False, isp_keywords=_isp_keywords("denoise"),
         note="Noise reduction before demosaicing, its strength set by the capture's own noise "
              "(NAME:SCALE: the tuned strength times SCALE)."),
    Axis(name="sharpen", applies_to="isp", label="sharpening", unit="", short="sh-",
         check=_isp_setting("sharpen"), numeric=False, isp_keywords=_isp_keywords("sharpen"),
         note="Sharpening after the colour matrix (NAME:AMOUNT: the sharpener's amount)."),
)}


def register_axis(axis: Axis) -> Axis:
    """Add an axis (a plug-in's or a test's); it becomes a column of every
    later study's tables.  The name must be new."""
    if axis.name in AXES:
        raise CfaMitsubaError(f"an axis named {axis.name!r} is already registered")
    AXES[axis.name] = axis
    return axis


def unregister_axis(name: str) -> None:
    """Remove a registered axis (tests that register a toy one)."""
    AXES.pop(name, None)


def get_axis(name: str) -> Axis:
    try:
        return AXES[name]
    except KeyError:
        raise CfaMitsubaError(f"unknown axis {name!r} (known: {', '.join(AXES)})") from None


def axis_unit(name: str) -> str:
    """An axis's unit for labels ('' for unknown or unitless axes)."""
    a = AXES.get(name)
    return a.unit if a else ""


def axis_label(name: str) -> str:
    a = AXES.get(name)
    return a.label if a else name
