"""Physical ranges of a study's values, checked with the config (before
``config.json`` or anything else is written), so a value no camera meets
is refused by its key instead of aborting the study at evaluation.

Luminance (cd/m^2): positive and at most :data:`MAX_LUMINANCE_CD_M2`, above
the sun's disc (about 1.6e9 cd/m^2, the brightest natural source) and far
below where the capture's electron count overflows (1e308 gives an infinite
count: the study ran its renders, then every task failed).

Noise realisations (``seeds``): at least 2 when the capture is noisy.  Every
value a study reports is the mean of its realisations with a 95 % t interval,
and ranks tie where intervals overlap (DESIGN.md); one realisation has no
spread to measure, so it would report zero-width intervals and strict ranks
that the noise does not support.  With ``[sensor] noise = "off"`` every
realisation is the same and one is exact.
"""

from __future__ import annotations

__all__ = ["MAX_LUMINANCE_CD_M2", "check_physical", "check_realisations"]

#: The brightest scene luminance a study accepts, cd/m^2.
MAX_LUMINANCE_CD_M2 = 1e10


def check_physical(fail, luminances, sweeps, program) -> None:
    """Refuse (through ``fail(key, reason)``, the config checker's) a
    luminance beyond :data:`MAX_LUMINANCE_CD_M2` in ``luminances``, a
    sweep's luminance axis or the exposure program's
    (``sensor.reference_luminance_cd_m2``); a sweep's 'auto' exposure under
    the 'fixed' policy, which chooses none."""
    why = f"must be at most {MAX_LUMINANCE_CD_M2:g} cd/m^2 (the sun's disc is about 1.6e9)"
    for i, lum in enumerate(luminances):
        if lum > MAX_LUMINANCE_CD_M2:
            fail(f"luminances[{i}]", f"{why}, got {lum:g}")
    for i, sw in enumerate(sweeps):
        for j, lum in enumerate(sw.values.get("luminance", ())):
            if lum > MAX_LUMINANCE_CD_M2:
                fail(f"sweep[{i}].luminance[{j}]", f"{why}, got {lum:g}")
        if program.policy == "fixed" and "auto" in sw.values.get("exposure", ()):
            fail(f"sweep[{i}].exposure", "'auto' needs an exposure policy that chooses the exposure; "
                                         "exposure_policy \"fixed\" takes times in seconds")
    ref = program.reference_luminance_cd_m2
    if ref > MAX_LUMINANCE_CD_M2:
        fail("sensor.reference_luminance_cd_m2", f"{why}, got {ref:g}")


def check_realisations(fail, seeds: int, noise: str) -> None:
    """Refuse one noise realisation of a noisy capture (module docstring)."""
    if seeds < 2 and noise != "off":
        fail("seeds", f"at least 2 noise realisations are needed for the 95 % intervals and the ties in the "
                      f"ranks (got {seeds}); one is exact only with [sensor] noise = \"off\"")
