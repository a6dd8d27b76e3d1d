"""Spectral textures: per-texel reflectance as a mix of measured spectra.

A :class:`SpectralTexture` is a small palette of measured reflectances (by
name, from colour-science's 'ColorChecker N Ohta' set) and, per texel, the
weights with which they mix (non-negative, summing to 1): a texel of weight
1 on 'red' *is* the measured red, a texel half 'red' half 'dark skin' is the
area mix of two inks.  The reflectance of texel (r, c) in band b is
``sum_k weights[r, c, k] * palette_k[b]``: spectral, never an RGB colour
upsampled (Mitsuba's ``bitmap`` texture evaluates 3-channel data as RGB,
turned into a smooth Jakob-Hanika spectrum; research/mitsuba-spectral.md
s. 4).

How Mitsuba evaluates it, exactly, at whatever wavelengths
``si.wavelengths`` holds (the project's integrator, :mod:`.integrator`,
evaluates every BSDF band group by band group through that slot):

- JIT variants: a Lambertian BSDF whose reflectance is a small Python
  ``mi.Texture`` (:func:`mix_texture_class`): the nearest texel's K weights
  (one gather each) times each palette spectrum's value in the band of each
  of the 4 wavelengths (one gather each from a (K, B) table).  The kernel
  compiles in 1.5-4 s for the puppy and a lookup costs a few gathers.
- ``scalar_spectral`` (stock C++ plugins only; a Python texture there runs
  Python per lookup, about 80 us): a chain of ``blendbsdf`` nodes
  (stick-breaking: node k mixes the Lambertian BSDF of palette spectrum k
  with the rest of the chain, with the 1-channel weight map ``1 - w_k /
  (w_k + ... + w_K-1)``, a ``bitmap`` with ``raw`` values and ``nearest``
  lookup).  ``blendbsdf`` evaluates ``(1 - t) f_0 + t f_1``, so the
  chain's value is ``sum_k w_k rho_k / pi``.  Sampling picks one node by
  its weight: unbiased, a little extra noise in indirect light only.  The
  same chain in the JIT variants compiled for 26-38 s (each distinct BSDF
  is traced into each of the integrator's 8 band-group BSDF calls), and
  a Python texture calling K ``regular`` spectrum plugins for 10-12 s.

A 3-channel bitmap per band group would not do: a spectral variant reads 3
channels as sRGB and upsamples them.  Measurements: docs/scenes.md,
"Textures".

Texel orientation: ``weights[r, c]`` sits at uv ((c + 0.5) / W, (r + 0.5) /
H), i.e. row r at v = (r + 0.5) / H (Mitsuba's bitmap convention, checked in
tests/render/test_texture.py).
"""

from __future__ import annotations

__all__ = ["SpectralTexture", "chain_weights", "palette_reflectance", "mix_texture_class"]

from dataclasses import dataclass

import numpy as np

from .. import spectra
from .light import band_spectrum


def palette_reflectance(palette, wavelengths) -> np.ndarray:
    """(K, B) band-mean reflectances of the named 'ColorChecker N Ohta'
    patches on the band grid ``wavelengths`` (nm)."""
    names, refl = spectra.colorchecker(wavelengths)
    unknown = [p for p in palette if p not in names]
    if unknown:
        raise ValueError(f"unknown ColorChecker N Ohta patch(es) {unknown}; known: {', '.join(names)}")
    return np.stack([refl[names.index(p)] for p in palette])


def chain_weights(weights: np.ndarray) -> list[np.ndarray]:
    """Stick-breaking blend maps of a (H, W, K) weight stack: K - 1 maps
    t_k (H, W) in [0, 1], t_k = 1 - w_k / (w_k + ... + w_{K-1}) (0 where
    the rest is empty), so that the chain blend(t_0, rho_0, blend(t_1,
    rho_1, ... rho_{K-1})) is sum_k w_k rho_k."""
    w = np.asarray(weights, dtype=np.float64)
    rest = np.cumsum(w[..., ::-1], axis=-1)[..., ::-1]  # w_k + ... + w_{K-1}
    out = []
    for k in range(w.shape[-1] - 1):
        with np.errstate(invalid="ignore", divide="ignore"):
            t = np.where(rest[..., k] > 0, 1.0 - w[..., k] / rest[..., k], 0.0)
        out.append(np.clip(t, 0.0, 1.0).astype(np.float32))
    return out


@dataclass(frozen=True)
class SpectralTexture:
    """A texture of mixed measured reflectances (module docstring).

    Attributes
    ----------
    name : what it shows (for the sidecar and the docs).
    palette : 'ColorChecker N Ohta' patch names, K of them.
    weights : (H, W, K) float32, each texel's mixing weights (>= 0, sum 1).
    texel_m : the texel's size on the object (m), nominal (a shape's uv
        mapping may stretch it).
    """

    name: str
    palette: tuple[str, ...]
    weights: np.ndarray
    texel_m: float

    def __post_init__(self):
        w = self.weights
        if w.ndim != 3 or w.shape[-1] != len(self.palette) or len(self.palette) < 1:
            raise ValueError(f"weights must be (H, W, {len(self.palette)}), got {w.shape}")
        if not (np.all(w >= 0) and np.allclose(w.sum(-1), 1.0, atol=1e-4)):
            raise ValueError("texture weights must be non-negative and sum to 1 per texel")

    @property
    def shape(self) -> tuple[int, int]:
        return self.weights.shape[:2]

    def reflectance(self, wavelengths) -> np.ndarray:
        """(H, W, B) band-mean reflectance of every texel."""
        return np.einsum("hwk,kb->hwb", self.weights, palette_reflectance(self.palette, wavelengths))

    def record(self) -> dict:
        """The sidecar's description."""
        return {"name": self.name, "palette": list(self.palette), "texels": list(self.shape),
                "texel_mm": round(self.texel_m * 1e3, 4), "reflectance_set": "ColorChecker N Ohta"}

    def bsdf(self, mi, config, *, uv_scale=(1.0, 1.0), wrap: str = "repeat") -> dict:
        """The Mitsuba BSDF dict for ``config``'s band grid and variant: a
        Lambertian BSDF whose reflectance is the texture (module docstring;
        JIT variants: a :func:`mix_texture_class` texture, scalar_spectral:
        a ``blendbsdf`` chain).  ``uv_scale`` (su, sv) repeats the texture
        su x sv times over the shape's uv square (``wrap`` 'repeat') or
        clamps to its border texels (``wrap`` 'clamp')."""
        if wrap not in ("repeat", "clamp"):
            raise ValueError(f"wrap must be 'repeat' or 'clamp', got {wrap!r}")
        rho = palette_reflectance(self.palette, config.wl)
        if not config.variant.startswith("scalar"):
            tex = mix_texture_class(mi)().setup(self.weights, rho, spectra.band_edges(config.wl), uv_scale,
                                                wrap == "repeat")
            return {"type": "diffuse", "reflectance": tex}
        node = {"type": "diffuse", "reflectance": band_spectrum(config, rho[-1])}
        to_uv = mi.ScalarTransform4f().scale([float(uv_scale[0]), float(uv_scale[1]), 1.0])
        for k, t in reversed(list(enumerate(chain_weights(self.weights)))):
            weight = {"type": "bitmap", "bitmap": mi.Bitmap(t[..., None]), "raw": True, "filter_type": "nearest",
                      "wrap_mode": wrap, "to_uv": to_uv}
            node = {"type": "blendbsdf", "weight": weight,
                    "bsdf_0": {"type": "diffuse", "reflectance": band_spectrum(config, rho[k])}, "bsdf_1": node}
        return node


_mix_classes: dict[str, type] = {}


def mix_texture_class(mi) -> type:
    """The ``mi.Texture`` subclass of the JIT variants (one per variant):
    the nearest texel's K weights (one gather each) times the K palette
    spectra evaluated at ``si.wavelengths``.  Build one with
    ``cls().setup(weights, spectra, uv_scale, repeat)``."""
    variant = mi.variant()
    if variant in _mix_classes:
        return _mix_classes[variant]
    import drjit as dr

    class MixTexture(mi.Texture):
        def __init__(self, props=None):
            super().__init__(mi.Properties() if props is None else props)

        def setup(self, weights, rho, edges, uv_scale, repeat: bool):
            h, w, k = weights.shape
            self.h, self.w, self.k = int(h), int(w), int(k)
            self.data = mi.Float(np.ascontiguousarray(weights, dtype=np.float32).ravel())
            self.n_bands = int(rho.shape[1])
            self.palette = mi.Float(np.ascontiguousarray(rho, dtype=np.float32).ravel())
            self.edges = mi.Float(np.asarray(edges, dtype=np.float32))
            step = np.diff(edges)
            self.uniform = (float(edges[0]), float(step[0])) if np.allclose(step, step[0], rtol=0, atol=1e-9) else None
            self.su, self.sv = float(uv_scale[0]), float(uv_scale[1])
            self.repeat = bool(repeat)
            self.mean_value = float(np.mean(np.asarray(weights, dtype=np.float64).mean(axis=(0, 1)) @ rho))
            return self

        def _band(self, lam, active):
            """The band index of wavelength ``lam`` (nm)."""
            if self.uniform is not None:
                b = mi.Int32(dr.floor((lam - self.uniform[0]) / self.uniform[1]))
            else:  # the last edge <= lam
                b = mi.Int32(dr.binary_search(0, self.n_bands, lambda i: dr.gather(mi.Float, self.edges, i) <= lam)) - 1
            return mi.UInt32(dr.clip(b, 0, self.n_bands - 1))

        def _texel(self, si, active):
            u, v = si.uv.x * self.su, si.uv.y * self.sv
            if self.repeat:
                u, v = u - dr.floor(u), v - dr.floor(v)
            c = mi.UInt32(dr.clip(mi.Int32(dr.floor(u * self.w)), 0, self.w - 1))
            r = mi.UInt32(dr.clip(mi.Int32(dr.floor(v * self.h)), 0, self.h - 1))
            return (r * self.w + c) * self.k

        def eval(self, si, active=True):
            base = self._texel(si, active)
            bands = [self._band(si.wavelengths[i], active) for i in range(4)]
            lanes = [mi.Float(0.0) for _ in range(4)]
            for j in range(self.k):
                wj = dr.gather(mi.Float, self.data, base + j, active)
                for i in range(4):
                    lanes[i] += wj * dr.gather(mi.Float, self.palette, j * self.n_bands + bands[i], active)
            return mi.UnpolarizedSpectrum(*lanes)

        def eval_1(self, si, active=True):
            return dr.mean(self.eval(si, active))

        def mean(self):
            return self.mean_value

        def is_spatially_varying(self):
            return True

        def to_string(self):
            return f"MixTexture[{self.h} x {self.w} texels, {self.k} spectra]"

    _mix_classes[variant] = MixTexture
    return MixTexture
