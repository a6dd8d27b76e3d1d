"""Bilinear Bayer demosaicing's in-band (phase-averaged) response through
the colour matrix to Y, computed from the demosaic itself: a neutral complex
grating (a neutral's white-balanced channels are equal) demosaiced, weighted
by the matrix's Y column, projected on the grating's own frequency.  The
reference of tests/metrics/test_texture.py for the Bayer chain's edge and
texture MTF, and of benchmarks/texture_vs_edge.py's table."""

from __future__ import annotations

import numpy as np

import cfa_mitsuba as cm


def y_of_channels(image) -> np.ndarray:
    """The share of Y each Bayer channel gives a neutral, from the colour
    matrix the chain fits for ``image`` (XYZ = channels @ matrix)."""
    raw = cm.sensor.capture(image, "bayer", luminance_cd_m2=100.0, noise="off")
    matrix = np.asarray(cm.isp.process(raw, "bilinear").meta["isp"]["colour_matrix"])
    return matrix[:, 1] / matrix[:, 1].sum()


def in_band(weights: np.ndarray, fx: float, fy: float, n: int = 128, border: int = 8) -> float:
    """The response at (``fx``, ``fy``) cy/px, unitless (1 at DC)."""
    bayer = cm.sensor.get_cfa("bayer")
    y, x = np.mgrid[0:n, 0:n].astype(float)
    wave = np.exp(2j * np.pi * (fx * x + fy * y))
    out = sum(w * cm.isp.demosaic(g, bayer, "bilinear") @ weights
              for g, w in ((wave.real, 1.0), (wave.imag, 1j)))  # a complex grating, through a real system
    inner = (slice(border, n - border),) * 2
    return float(abs(np.mean(out[inner] * np.conj(wave[inner]))))


def ring_mean(weights: np.ndarray, f: float, angles: int = 7) -> float:
    """:func:`in_band` at radius ``f`` cy/px, averaged over ``angles``
    directions from 0 to 90 degrees (the texture MTF's ring)."""
    return float(np.mean([in_band(weights, f * np.cos(t), f * np.sin(t))
                          for t in np.linspace(0.0, np.pi / 2, angles)]))
