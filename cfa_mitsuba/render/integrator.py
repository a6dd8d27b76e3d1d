"""The spectral-quadrature integrator: every band along every path.

Hand-written because no library offers it: Mitsuba 3's integrators carry 4
wavelengths per path, drawn from the film's sensitivity, so with 31 narrow
bands a band only gets a sample when one of the 4 lands in it (32 % per-band
noise at 64 spp, research/mitsuba-spectral.md s. 1-2).  This integrator traces
each path once and evaluates emitters and BSDFs at one wavelength *per band*,
in groups of 4 through ``si.wavelengths`` (the slot Mitsuba's plugins read
their spectra from), and returns the bands as AOVs of an ``hdrfilm``.  Each
band's wavelength is jittered uniformly inside its box by one number per
sample (from the sampler, hence stratified across a pixel's samples), so a
pixel's value is an unbiased estimate of the band's box mean: the project's
definition of a band value (DESIGN.md, Conventions).

Path construction is Mitsuba's own unidirectional path tracer (the structure
of ``mitsuba/python/ad/integrators/prb.py``: emitter sampling and BSDF
sampling combined with the power heuristic, no Russian roulette, a fixed
``max_depth``), with the one change that every spectral quantity is evaluated
once per band group.  Directions, emitter choices and positions are drawn
once and shared by all groups; that is exact for BSDFs whose sampling does not
depend on wavelength (diffuse, plastic, conductor, dielectric with a scalar
index), which :mod:`.userxml` enforces for users' scenes.

Properties: ``band_edges`` (comma-separated box edges in nm, B + 1 values for
B contiguous bands), ``band_inset`` (fraction of each box left unsampled at
both ends, default 0; 0.5 evaluates every band at its box centre, for
band-constant scenes; see :mod:`.light`), ``max_depth`` (1: emitters seen directly, the flat
charts; 2: direct lighting; larger: multi-bounce).  Only for the JIT variants
(llvm/cuda): Python integrators are impractically slow in ``scalar_*``.
"""

from __future__ import annotations

__all__ = ["PLUGIN_NAME", "register", "aov_band_names"]

#: Name under which the integrator is registered with Mitsuba.
PLUGIN_NAME = "cfa_spectral"

_registered: set[str] = set()


def aov_band_names(n_bands: int) -> list[str]:
    """AOV channel names for ``n_bands`` bands; zero-padded so that any
    alphabetical channel sort keeps band order."""
    return [f"band{i:03d}" for i in range(n_bands)]


def register(mi) -> None:
    """Register :data:`PLUGIN_NAME` for the current (JIT) variant; no-op in
    ``scalar_*`` variants and when already registered."""
    variant = mi.variant()
    if variant in _registered or variant.startswith("scalar"):
        return
    mi.register_integrator(PLUGIN_NAME, lambda props: _make_class(mi)(props))
    _registered.add(variant)


_classes: dict[str, type] = {}


def _make_class(mi):
    variant = mi.variant()
    if variant in _classes:
        return _classes[variant]
    import drjit as dr

    def mis_weight(pdf_a, pdf_b):
        # Power heuristic (Veach 1997, eq. 9.13), as Mitsuba's own integrators.
        a2 = dr.square(pdf_a)
        w = a2 / (a2 + dr.square(pdf_b))
        return dr.select(dr.isfinite(w), w, 0.0)

    class SpectralQuadrature(mi.SamplingIntegrator):
        def __init__(self, props):
            super().__init__(props)
            edges = [float(v) for v in str(props.get("band_edges", "395,705")).split(",")]
            if len(edges) < 2 or any(b <= a for a, b in zip(edges, edges[1:])):
                raise ValueError("band_edges must be at least two ascending wavelengths (nm)")
            inset = float(props.get("band_inset", 0.0))
            if not 0.0 <= inset <= 0.5:
                raise ValueError("band_inset must be in [0, 0.5] (0.5: each band at its box centre)")
            # Sample each band uniformly on [lo + inset w, hi - inset w].
            self.lo = [a + inset * (b - a) for a, b in zip(edges, edges[1:])]
            self.width = [(b - a) * (1.0 - 2.0 * inset) for a, b in zip(edges, edges[1:])]
            self.max_depth = int(props.get("max_depth", 1))
            if self.max_depth < 1:
                raise ValueError("max_depth must be >= 1")
            n = len(self.lo)
            self.groups = [list(range(g, min(g + 4, n))) for g in range(0, n, 4)]

        def aov_names(self):
            return aov_band_names(len(self.lo))

        def _wavelengths(self, u):
            """One Spectrum of 4 wavelengths per band group, each band's
            wavelength at fraction ``u`` of its box (padding lanes repeat the
            group's last band and are discarded)."""
            out = []
            for grp in self.groups:
                lam = [self.lo[i] + u * self.width[i] for i in grp]
                lam += [lam[-1]] * (4 - len(lam))
                out.append(mi.Spectrum(*lam))
            return out

        def _aovs(self, values):
            return [values[g][k] for g, grp in enumerate(self.groups) for k in range(len(grp))]

        def sample(self, scene, sampler, ray, medium=None, active=True):
            active = mi.Bool(active)
            wls = self._wavelengths(sampler.next_1d(active))
            if self.max_depth == 1:
                return self._emission(scene, ray, active, wls)
            return self._path(scene, sampler, ray, active, wls)

        def _emission(self, scene, ray, active, wls):
            # Flat charts: the camera sees emitters directly; nothing to light.
            si = scene.ray_intersect(ray, active)
            emitter = si.emitter(scene, active)
            values = []
            for wl in wls:
                si.wavelengths = wl
                values.append(emitter.eval(si, active))
            return mi.Spectrum(0.0), si.is_valid(), self._aovs(values)

        def _path(self, scene, sampler, ray, active, wls):
            ctx = mi.BSDFContext()
            n_groups = len(wls)
            has_delta = any(mi.has_flag(e.flags(), mi.EmitterFlags.Delta) for e in scene.emitters())
            max_depth = self.max_depth

            def cond(sampler, ray, depth, active, thr, rad, si_prev, pdf_prev, delta_prev, valid):
                return active

            def body(sampler, ray, depth, active, thr, rad, si_prev, pdf_prev, delta_prev, valid):
                si = scene.ray_intersect(ray, ray_flags=mi.RayFlags.All, coherent=depth == 0, active=active)
                valid = dr.select(depth == 0, si.is_valid(), valid)
                rad = list(rad)

                # Emission at the hit (or from the environment if the ray
                # escaped), MIS-weighted against emitter sampling at the
                # previous vertex.  At depth 0, pdf_prev = 1 and delta_prev =
                # True give weight 1.
                ds = mi.DirectionSample3f(scene, si=si, ref=si_prev)
                em_pdf = scene.pdf_emitter_direction(si_prev, ds, ~delta_prev)
                mis_hit = mis_weight(pdf_prev, em_pdf)
                hit_em = active & (ds.emitter != None)  # noqa: E711 (a pointer array compared with null)
                for g in range(n_groups):
                    si.wavelengths = wls[g]
                    rad[g] = rad[g] + thr[g] * mis_hit * ds.emitter.eval(si, hit_em)

                active_next = active & (depth + 1 < max_depth) & si.is_valid()
                bsdf = si.bsdf(ray)

                # Emitter sampling: one emitter position and one BSDF
                # direction for all bands; emitter and BSDF evaluated per band
                # group (one eval_pdf_sample call gives the BSDF's value
                # towards the emitter, its pdf, and the sampled continuation).
                active_em = active_next & mi.has_flag(bsdf.flags(), mi.BSDFFlags.Smooth)
                s_em = sampler.next_2d(active_next)
                ds_em, _ = scene.sample_emitter_direction(si, s_em, False, active_em)
                active_em &= ds_em.pdf != 0.0
                active_em &= ~scene.ray_test(si.spawn_ray_to(ds_em.p), active_em)
                wo_em = si.to_local(ds_em.d)
                inv_pdf_em = dr.select(ds_em.pdf > 0.0, dr.rcp(ds_em.pdf), 0.0)
                s1 = sampler.next_1d(active_next)
                s2 = sampler.next_2d(active_next)
                thr = list(thr)
                bs0 = mis_em = None
                for g in range(n_groups):
                    si.wavelengths = wls[g]
                    if has_delta:  # point/spot lights have no eval_direction: resample (same numbers, same point)
                        _, em_weight = scene.sample_emitter_direction(si, s_em, False, active_em)
                    else:
                        em_weight = scene.eval_emitter_direction(si, ds_em, active_em) * inv_pdf_em
                    bsdf_val, bsdf_pdf, bs, weight = bsdf.eval_pdf_sample(ctx, si, wo_em, s1, s2, active_next)
                    if bs0 is None:
                        bs0 = bs
                        mis_em = dr.select(ds_em.delta, 1.0, mis_weight(ds_em.pdf, bsdf_pdf))
                    rad[g] = rad[g] + dr.select(active_em, thr[g] * mis_em * bsdf_val * em_weight, 0.0)
                    thr[g] = dr.select(active_next, thr[g] * weight, 0.0)
                nonzero = mi.Bool(False)
                for g in range(n_groups):
                    nonzero |= dr.max(thr[g]) > 0.0
                active_next &= nonzero

                ray = si.spawn_ray(si.to_world(bs0.wo))
                delta = mi.has_flag(bs0.sampled_type, mi.BSDFFlags.Delta)
                return (sampler, ray, depth + 1, active_next, tuple(thr), tuple(rad),
                        si, bs0.pdf, delta, valid)

            state = (
                sampler,
                mi.Ray3f(ray),
                mi.UInt32(0),
                active,
                tuple(mi.Spectrum(1.0) for _ in range(n_groups)),
                tuple(mi.Spectrum(0.0) for _ in range(n_groups)),
                dr.zeros(mi.SurfaceInteraction3f),
                mi.Float(1.0),
                mi.Bool(True),
                mi.Bool(False),
            )
            state = dr.while_loop(state, cond, body, label="cfa_spectral path")
            rad, valid = state[5], state[9]
            return mi.Spectrum(0.0), valid, self._aovs(rad)

        def to_string(self):
            return f"SpectralQuadrature[bands={len(self.lo)}, max_depth={self.max_depth}]"

    _classes[variant] = SpectralQuadrature
    return SpectralQuadrature
