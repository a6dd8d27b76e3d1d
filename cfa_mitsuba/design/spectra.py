"""Filter spectra of a design: the letters' curves from a spectra set, or
parametric ones.

Families (``[spectra] family``):

* ``bandpass``: a smooth band-pass dye, a 4th-order super-Gaussian
  transmittance  T(l) = peak exp(-ln 2 |2 (l - centre) / width|^4)  (flat
  top, width the full width at half maximum, no ripple), placed on the
  sensor's common silicon QE and IR-cut filter as the spectra sets place a
  'dye' curve (:mod:`cfa_mitsuba.sensor.spectra_sets`): QE = T x IR x Si;
* ``mixture``: a non-negative mixture  sum_j a_j Q_j  of a spectra set's
  curves (whole-pixel QE already), scaled down if it would peak above 1.

Curves are tabulated on a 2-nm grid, 380..720 nm (what the emitted CFA
TOML holds), and band-averaged to the render's bands where used, as any
CFA's curves are.
"""

from __future__ import annotations

__all__ = ["GRID_NM", "bandpass_qe", "mixture_qe", "n_params", "decode_params", "letter_curves"]

import numpy as np

from ..sensor.spectra_sets import get_spectra_set, ir_cut, silicon_qe

#: The grid of emitted curves, nm.
GRID_NM = np.arange(380.0, 721.0, 2.0)


def _on_grid(curve) -> np.ndarray:
    wl, y = curve
    return np.interp(GRID_NM, wl, y)


def bandpass_qe(centre_nm: float, width_nm: float, peak: float) -> np.ndarray:
    """QE on :data:`GRID_NM` of a super-Gaussian band-pass dye on the common
    silicon and IR-cut filter (module doc).

    Examples
    --------
    >>> q = bandpass_qe(550, 100, 1.0)
    >>> bool(q.argmax() in range(int((500 - 380) / 2), int((600 - 380) / 2)))
    True
    """
    t = peak * np.exp(-np.log(2.0) * np.abs(2.0 * (GRID_NM - centre_nm) / width_nm) ** 4)
    return t * _on_grid(ir_cut()) * _on_grid(silicon_qe())


def mixture_qe(basis: str, weights) -> np.ndarray:
    """QE on :data:`GRID_NM` of sum_j weights_j x the j-th curve of spectra
    set ``basis`` (its letters in order), at most 1 anywhere."""
    sset = get_spectra_set(basis)
    q = sum(float(a) * _on_grid(sset.curves[c]) for a, c in zip(weights, sset.letters))
    q = np.asarray(q, dtype=np.float64)
    top = float(q.max())
    return q / top if top > 1.0 else q


def n_params(spec) -> int:
    """Free parameters per letter of a spectra spec (None: 0)."""
    if spec is None:
        return 0
    return 3 if spec.family == "bandpass" else len(get_spectra_set(spec.basis).letters)


def decode_params(spec, unit) -> list[dict]:
    """Per free letter, its parameters from ``unit`` (values in [0, 1], n_params
    per letter, letters in ``spec.letters`` order), scaled to the bounds."""
    unit = np.clip(np.asarray(unit, dtype=np.float64), 0.0, 1.0)
    k = n_params(spec)
    out = []
    for i, _ in enumerate(spec.letters):
        u = unit[i * k:(i + 1) * k]
        if spec.family == "bandpass":
            (c0, c1), (w0, w1), (p0, p1) = spec.centre_nm, spec.width_nm, spec.peak
            out.append({"centre_nm": c0 + u[0] * (c1 - c0), "width_nm": w0 + u[1] * (w1 - w0),
                        "peak": p0 + u[2] * (p1 - p0)})
        else:
            a0, a1 = spec.weight
            out.append({"weights": (a0 + u * (a1 - a0)).tolist()})
    return out


def letter_curves(alphabet, spectra_set: str, spec=None, params=None) -> dict:
    """``{letter: (wavelengths_nm, qe)}`` of every letter: the set's curve,
    or the parametric one for the letters ``spec`` frees (``params`` from
    :func:`decode_params`)."""
    sset = get_spectra_set(spectra_set)
    free = {} if spec is None else dict(zip(spec.letters, params))
    out = {}
    for a in alphabet:
        if a in free:
            p = free[a]
            q = (bandpass_qe(p["centre_nm"], p["width_nm"], p["peak"]) if spec.family == "bandpass"
                 else mixture_qe(spec.basis, p["weights"]))
            out[a] = (GRID_NM, q)
        else:
            out[a] = sset.curve(a)
    return out
