"""What a study records about each of its CFAs, so that the report draws
them from files alone (``cfas.json`` beside metrics.csv).

Per CFA label: its tile (``pattern``), ``channels``, the ``spectra`` set the
captures used, the side of its same-colour blocks (``block``) and the tile
binning gives (``binned_pattern``), and ``mcc_fit_de76``: the colour fit
alone, without optics, mosaic or noise (the 24 ColorChecker patches under
D65 seen by the CFA's channels, a least-squares matrix fitted on the same
24 patches, mean CIE 1976 dE*ab against the chart).  That last number is
the one ISETCam's own check of the filter files reports
(research/isetcam-paper-check.md: 'the fit alone'), so a reader can tell a
filter set's colour limit from what the rest of the chain adds.
"""

from __future__ import annotations

__all__ = ["cfa_facts", "mcc_fit_de76", "write_cfa_facts", "CFA_FACTS_FILE"]

import json
from pathlib import Path

import numpy as np

CFA_FACTS_FILE = "cfas.json"


def mcc_fit_de76(cfa) -> float:
    """Mean CIE 1976 dE*ab of the MCC-fitted colour matrix on the MCC itself
    under D65 (no optics, mosaic or noise), for a :class:`~cfa_mitsuba.sensor.CFA`.

    The responses are each patch's band radiance (reflectance x D65) times
    the channel's electrons per unit radiance, normalised by the white's; the
    matrix is the plain least-squares fit (not white preserving) on the same
    24 patches (:func:`cfa_mitsuba.isp.colour_matrix.fit_colour_matrix`).
    """
    from .. import spectra
    from ..colorimetry import xyz_to_lab
    from ..isp.colour_matrix import colour_fit_reflectances, electrons_per_radiance_of, fit_colour_matrix

    wl = spectra.DEFAULT_WAVELENGTHS
    d65 = spectra.illuminant("D65", wl)
    refl = colour_fit_reflectances("mcc", wl)
    white = spectra.xyz_from_radiance(d65, wl)
    epr = electrons_per_radiance_of(cfa.sensitivities(wl), wl)
    fit = fit_colour_matrix(epr, d65, wl, white_preserving=False, reflectances=refl)
    cam = (refl * d65) @ epr.T / (epr @ d65)
    ref = spectra.xyz_from_radiance(refl * d65, wl)
    return float(np.linalg.norm(xyz_to_lab(fit.apply(cam), white) - xyz_to_lab(ref, white), axis=1).mean())


def cfa_facts(cfa, spectra: str | None = None) -> dict:
    """The record of one CFA (a name, TOML path or CFA) with the spectra set
    its captures use (None: its own)."""
    from ..sensor import get_cfa
    from ..sensor.readout import binned_pattern, block_size

    obj = get_cfa(cfa, spectra=spectra) if spectra else get_cfa(cfa)
    pattern = np.asarray(obj.pattern)
    n = block_size(pattern)
    return {
        "name": obj.name, "pattern": pattern.tolist(), "channels": list(obj.channels),
        "spectra": str(obj.spectra or ""), "block": int(n),
        "binned_pattern": binned_pattern(pattern).tolist() if n > 1 else None,
        "mcc_fit_de76": mcc_fit_de76(obj),
    }


def write_cfa_facts(out_dir, cfas, labels, settings, condition) -> Path:
    """Write ``cfas.json``: {label: :func:`cfa_facts`} for a study's CFAs,
    each with the spectra set ``settings`` (a ChainSettings) gives it under
    the study's base ``condition``."""
    from ..io import atomic_output
    from ..io.sidecar import json_default

    facts = {label: cfa_facts(c, settings.spectra_for(c, condition)) for c, label in zip(cfas, labels)}
    path = Path(out_dir) / CFA_FACTS_FILE
    with atomic_output(path) as tmp:
        tmp.write_text(json.dumps(facts, indent=1, default=json_default))
    return path
