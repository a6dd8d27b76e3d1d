"""The ColorChecker patches of every camera against the ideal sensor, in
CIELAB a*b* (:func:`patch_ab`, the paper's Fig 8) and in CIE xy
(:func:`patch_xy`, Fig 9), drawn from the per-evaluation details."""

from __future__ import annotations

__all__ = ["patch_ab", "patch_xy"]

import numpy as np

from .figure import ReportFigure, grid_shape, no_details as _no_details, panel_grid
from .results import Results
from .style import cfa_styles, fmt_value


def _patch_colours(res: Results, scene: str, lum: float, det: dict) -> np.ndarray:
    """sRGB (0-1) of each patch as the ideal sensor sees it, for the markers."""
    from ..colorimetry import xyz_to_srgb8

    xyz = np.asarray(det.get("xyz_reference") or [], dtype=float)
    ideal = res.detail(scene, None, None, lum) or {}
    white = (ideal.get("extra") or {}).get("white_xyz")
    if xyz.ndim != 2 or xyz.shape[1] != 3:
        return np.full((len(det.get("lab_reference") or []), 3), 0.6)
    if white is None:  # the brightest patch stands in for the white
        white = xyz[np.argmax(xyz[:, 1])] / 0.9
    return np.clip(xyz_to_srgb8(xyz, white, quantize=False) / 255.0, 0, 1)


def _patch_figure(res: Results, kind: str):
    is_ab = kind == "ab"
    paper = "Fig 8" if is_ab else "Fig 9"
    title = (f"ColorChecker in a*b*: ideal vs camera (paper {paper})" if is_ab
             else f"ColorChecker chromaticity xy: ideal vs camera (paper {paper})")
    lum = res.primary_luminance
    scene, pairs = res.detail_pairs("delta-e", lum) if lum is not None else (None, [])
    key_ref, key_test = ("lab_reference", "lab_test") if is_ab else ("xy_reference", "xy_test")
    pairs = [p for p in pairs if p[2].get(key_ref) and p[2].get(key_test)]
    if not pairs:
        return [_no_details("colour", title, res, "delta-e", "ColorChecker patches")]

    def pts(det, key):
        a = np.asarray(det[key], dtype=float)
        return a[:, 1:3] if is_ab else a[:, :2]

    allp = np.concatenate([np.concatenate([pts(det, key_ref), pts(det, key_test)]) for _, _, det in pairs])
    lo, hi = np.nanmin(allp, axis=0), np.nanmax(allp, axis=0)
    half = 0.5 * (hi - lo).max() * 1.08
    mid = 0.5 * (lo + hi)
    lo, hi = mid - half, mid + half
    colours = _patch_colours(res, scene, lum, pairs[0][2])
    cst = cfa_styles(res.cfas)
    locus = _spectral_locus() if not is_ab else None
    white_xy = (0.3127, 0.3290) if not is_ab else None  # D65, the scenes' illuminant
    dems = [d for d in res.demosaics if any(p[1] == d for p in pairs)]
    return [_patch_panels(res, kind, title, scene, lum, d, [(c, det) for c, dd, det in pairs if dd == d],
                          (lo, hi), colours, cst, locus, white_xy, pts, key_ref, key_test) for d in dems]


def _patch_panels(res, kind, title, scene, lum, shown, sub, lims, colours, cst, locus, white_xy, pts, key_ref,
                  key_test):
    from matplotlib.collections import LineCollection

    is_ab = kind == "ab"
    lo, hi = lims
    rows, cols = grid_shape(len(sub), 4)
    fig, axes = panel_grid(rows, cols, 2.45, 2.45, left=0.6, right=0.15, top=0.3, bottom=0.5, wspace=0.15,
                           hspace=0.4, n=len(sub), sharex=True, sharey=True, width=6.0)
    for i, (ax, (c, det)) in enumerate(zip(axes, sub)):
        ref, test = pts(det, key_ref), pts(det, key_test)
        if locus is not None:
            ax.plot(locus[:, 0], locus[:, 1], color="#999999", linewidth=0.8)
        else:
            ax.axhline(0, color="#bbbbbb", linewidth=0.6)
            ax.axvline(0, color="#bbbbbb", linewidth=0.6)
        ax.add_collection(LineCollection(np.stack([ref, test], axis=1), colors="#222222", linewidths=0.9,
                                         zorder=3))
        ax.scatter(ref[:, 0], ref[:, 1], s=30, c=colours[:len(ref)], edgecolors="#222222", linewidths=0.5,
                   zorder=2, marker="o")
        ax.scatter(test[:, 0], test[:, 1], s=9, c="#000000", marker="o", edgecolors="white", linewidths=0.3,
                   zorder=4)
        if white_xy is not None:
            ax.plot(*white_xy, marker="+", color="#555555", markersize=7, zorder=1)
        st = cst[c]
        ax.plot([0.0], [1.06], transform=ax.transAxes, marker=st["marker"], color=st["color"], markersize=7,
                clip_on=False, linestyle="none")
        # the title gives Table 1's number (the mean over the noise realisations); the dots are the first one's
        mean = res.value(scene, c, shown, lum, "delta-e")
        ax.set_title(f"   {c}  (ΔE00 {fmt_value('delta-e', mean if mean is not None else det.get('value'))})",
                     loc="left", x=0.03)
        ax.set_xlim(lo[0], hi[0])
        ax.set_ylim(lo[1], hi[1])
        ax.set_aspect("equal", adjustable="box")
        last_row = i + cols >= len(sub)
        if last_row:
            ax.set_xlabel("a*" if is_ab else "x")
        else:
            ax.tick_params(labelbottom=False)
        if i % cols == 0:
            ax.set_ylabel("b*" if is_ab else "y")
        else:
            ax.tick_params(labelleft=False)
    what = "a*, b* (CIELAB, relative to the scene white)" if is_ab else "CIE 1931 chromaticity x, y"
    cap = (f"The 24 ColorChecker patches ({scene}, {lum:g} cd/m², demosaic {shown}) in {what}: large circles "
           f"filled with the patch's colour are the ideal sensor; the small black dot is the camera "
           f"(mean-matched to the ideal), joined to its ideal by a line whose length is the error (true scale). "
           f"All panels share one scale; the marker before each title is the CFA's in the other figures. "
           f"The dots are the first noise realisation; the ΔE00 in each title is the mean over the "
           f"realisations, as in Table 1.")
    if not is_ab:
        cap += " The grey curve is the spectral locus, + the D65 white."
    return ReportFigure(f"{kind}-{shown}", "colour", title, cap, fig, group=shown)


def _spectral_locus():
    try:
        from ..spectra import cmfs_xyz
    except ImportError:  # pragma: no cover
        return None
    c = np.asarray(cmfs_xyz(), dtype=float)
    s = c.sum(axis=1, keepdims=True)
    ok = s[:, 0] > 1e-9
    xy = c[ok, :2] / s[ok]
    return np.concatenate([xy, xy[:1]])


def patch_ab(res: Results):
    """The 24 patches in the a*b* plane, ideal vs camera, one figure per
    demosaic, one panel per CFA (the paper's Fig 8)."""
    return _patch_figure(res, "ab")


def patch_xy(res: Results):
    """The 24 patches in CIE xy, ideal vs camera, one figure per demosaic,
    one panel per CFA (the paper's Fig 9)."""
    return _patch_figure(res, "xy")


# -- S-CIELAB maps (Fig 10) -------------------------------------------------------------------------
