"""Filter spectra of a design: the letters' curves from a spectra set, or
parametric ones.

Families (``[spectra] family``):

* ``bandpass``: a smooth band-pass dye, a 4th-order super-Gaussian
  transmittance  T(l) = peak exp(-ln 2 |2 (l - centre) / width|^4)  (flat
  top, width the full width at half maximum, no ripple), placed on the
  sensor's common silicon QE and IR-cut filter as the spectra sets place a
  'dye' curve (:mod:`cfa_mitsuba.sensor.spectra_sets`): QE = T x IR x Si;
* ``mixture``: a non-negative mixture  sum_j a_j Q_j  of the single-letter
  curves of one spectra set or several (a dye library; whole-pixel QE
  already), scaled down if it would peak above 1;
* ``spline``: a free-form dye transmittance  T(l) = sum_k c_k B_k(l),  cubic
  B-splines (de Boor) on a clamped, uniform knot vector over the study's
  bands (395-705 nm: the 10-nm boxes of 400..700; held at its end values
  beyond, where no band sees it, so no coefficient is left free of the
  objective) with ``knots`` functions, on the common silicon and IR cut:
  QE = T x IR x Si.  B-splines are non-negative and sum to 1, so coefficients in [0, 1]
  bound T in [0, 1] (what :mod:`.gradient_search` searches).

Curves are tabulated on a 2-nm grid, 380..720 nm (what the emitted CFA
TOML holds), and band-averaged to the render's bands where used, as any
CFA's curves are.
"""

from __future__ import annotations

__all__ = ["GRID_NM", "bandpass_qe", "mixture_qe", "spline_basis", "spline_qe", "library", "basis_matrices",
           "fit_to_basis", "common_qe", "n_params", "decode_params", "letter_curves"]

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


def library(basis) -> list[tuple[str, str]]:
    """The (set, letter) curves a ``mixture`` mixes: every single-letter
    curve of the spectra set ``basis`` (a name, or a list of names: a dye
    library), in the sets' order."""
    names = [basis] if isinstance(basis, str) else list(basis)
    return [(n, c) for n in names for c in get_spectra_set(n).letters if len(c) == 1]


def mixture_qe(basis, weights) -> np.ndarray:
    """QE on :data:`GRID_NM` of sum_j weights_j x the j-th curve of
    :func:`library` ``(basis)``, at most 1 anywhere."""
    q = sum(float(a) * _on_grid(get_spectra_set(n).curves[c]) for a, (n, c) in zip(weights, library(basis)))
    q = np.asarray(q, dtype=np.float64)
    top = float(q.max())
    return q / top if top > 1.0 else q


def common_qe() -> np.ndarray:
    """The common IR cut x silicon QE on :data:`GRID_NM` (a clear pixel)."""
    return _on_grid(ir_cut()) * _on_grid(silicon_qe())


def spline_basis(n: int, x=None) -> np.ndarray:
    """(len(x), n) cubic B-spline basis on a clamped uniform knot vector over
    the study's bands, 395-705 nm (module doc), evaluated at ``x`` (default
    :data:`GRID_NM`; held at the ends' values outside).

    >>> bool(np.allclose(spline_basis(12).sum(axis=1), 1.0))
    True
    """
    from scipy.interpolate import BSpline

    if n < 4:
        raise ValueError("a cubic B-spline basis needs at least 4 functions")
    x = GRID_NM if x is None else np.asarray(x, dtype=np.float64)
    from .. import spectra as _sp

    edges = _sp.band_edges(_sp.DEFAULT_WAVELENGTHS)
    lo, hi = float(edges[0]), float(edges[-1])
    knots = np.concatenate([[lo] * 3, np.linspace(lo, hi, n - 2), [hi] * 3])
    return BSpline.design_matrix(np.clip(x, lo, hi), knots, 3).toarray()


def spline_qe(coefficients) -> np.ndarray:
    """QE on :data:`GRID_NM` of a spline dye (module doc) on the common IR cut and silicon."""
    c = np.asarray(coefficients, dtype=np.float64)
    return (spline_basis(c.size) @ c) * common_qe()


def basis_matrices(spec) -> tuple[np.ndarray, np.ndarray]:
    """((G, K) QE on :data:`GRID_NM`, (B, K) band QE on the study's grid) of
    each parameter of a ``spline`` or ``mixture`` spec: a letter's QE is
    linear in its parameters, and its band values are those of its emitted
    curve (the same band averaging as any CFA's curve)."""
    from .. import spectra as _sp

    if spec.family == "spline":
        grid = spline_basis(spec.knots) * common_qe()[:, None]
    else:
        grid = np.stack([_on_grid(get_spectra_set(n).curves[c]) for n, c in library(spec.basis)], axis=1)
    return grid, _sp.band_average(GRID_NM, grid, _sp.DEFAULT_WAVELENGTHS)


def fit_to_basis(spec, target_qe, grid: np.ndarray) -> np.ndarray:
    """Parameters within the spec's bounds whose QE on :data:`GRID_NM` best
    fits ``target_qe`` (bounded least squares, scipy ``lsq_linear``)."""
    from scipy.optimize import lsq_linear

    lo, hi = (1e-4, 1.0) if spec.family == "spline" else spec.weight
    return lsq_linear(grid, np.asarray(target_qe, dtype=np.float64), bounds=(lo, hi)).x


def n_params(spec) -> int:
    """Free parameters per letter of a spectra spec (None: 0)."""
    if spec is None:
        return 0
    if spec.family == "spline":
        return int(spec.knots)
    return 3 if spec.family == "bandpass" else len(library(spec.basis))


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
        elif spec.family == "spline":
            out.append({"coefficients": np.maximum(u, 1e-4).tolist()})
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
                 else spline_qe(p["coefficients"]) if spec.family == "spline"
                 else mixture_qe(spec.basis, p["weights"]))
            out[a] = (GRID_NM, q)
        else:
            out[a] = sset.curve(a)
    return out
