"""A synthetic raw capture of a known radiance (the ISP tests' input): every
pixel's electrons from the CFA's sensitivities, no optics, no noise."""

from __future__ import annotations

import cfa_mitsuba as cm
from cfa_mitsuba import spectra
from cfa_mitsuba.isp.colour_matrix import electrons_per_radiance_of
from cfa_mitsuba.values import RawImage

WL = spectra.DEFAULT_WAVELENGTHS
D65 = spectra.illuminant("D65", WL)
WHITE = D65 * (100.0 / spectra.luminance_cd_m2(D65, WL))  # a 100 cd/m^2 white


def synthetic_raw(radiance, cfa, *, white=WHITE, peak_e=5000.0, dn_per_e=0.6, black=64.0) -> RawImage:
    """A noise-free capture computed here, independently of sensor/:
    electrons = sum_b L_b epr[c, b] at each pixel's channel, DN = e g + black."""
    cfa = cm.sensor.get_cfa(cfa)
    qe = cfa.sensitivities(WL)
    epr = electrons_per_radiance_of(qe, WL)
    epr *= peak_e / (epr @ white).max()
    electrons = cm.isp.mosaic_image(radiance @ epr.T, cfa)
    return RawImage(raw=electrons * dn_per_e + black, pattern=cfa.pattern.copy(), channels=cfa.channels,
                    spectra=qe, wavelengths=WL.copy(), electrons_per_radiance=epr, white_radiance=white,
                    exposure_s=0.01, dn_per_electron=dn_per_e, black_level_dn=black, seed=0,
                    settings={"cfa": {"name": cfa.name}, "sensor": {"adc_bits": 12}}, meta={"scene": "test"})
