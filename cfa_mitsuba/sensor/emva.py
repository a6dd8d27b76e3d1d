"""The EMVA 1288 measurement, simulated on our sensor model.

EMVA 1288 (release 4.0, "Standard for characterization of image sensors
and cameras", s. 6-8) characterises a camera from image pairs: for each
point of a ramp of exposures under uniform, monochromatic light, two
bright images and two dark ones (the photon transfer method: mean and
temporal variance from the pair), and at one exposure (near 50 % of
saturation) a stack of L bright and L dark images for the spatial
non-uniformities.  This module takes those images with the real capture
chain (:func:`~.capture.capture`: optics, pixel integration, PRNU, dark
current, Poisson charge, well, DSNU, read noise, gain, black level, ADC)
and writes them as the ``emva1288`` package reads them: per channel a
folder with ``EMVA1288descriptor.txt`` (``v``, ``n bits width height``,
``b exposure_ns photons`` / ``d exposure_ns``, each followed by ``i
image`` lines) and 16-bit PNG images, the layout of the package's own
``camera.dataset_generator``.

The light.  A uniform field whose radiance is non-zero in one band of the
spectral grid: the band of the channel's peak QE (or a given wavelength),
10 nm wide, as the standard's narrow-band source (FWHM <= 50 nm) and
through the lens with relative illumination and diffraction off, so the
field stays uniform.  Its level makes the channel saturate at
``saturation_exposure_s``; the photons per pixel written in the
descriptor are the photometer's count over the whole pixel area,
u_p = E A t lambda dlambda / (h c) (the standard's eq. 2), with E the
sensor-plane band irradiance.

The pixels.  Each channel is measured on its own pixels.  Without
crosstalk a pixel's response depends only on its own filter, so the
channel's pixels are taken with every pixel of the array carrying that
channel (the same chain, 1 / density of the work); with crosstalk the
native mosaic is captured and the channel's pixels at its first tile
position are kept, so that the neighbours' charge is the real one.

The gain.  As the standard asks (and ``emva1288``'s dataset generator
does, ``_get_emva_gain``: temporal dark noise above 0.5 DN), the analog
gain is raised by the smallest step of :data:`GAIN_STEPS` that brings the
temporal dark noise to 0.5 DN: below it the ADC's quantisation, not the
pixel, sets the dark noise (``emva1288`` floors sigma_y.dark^2 at
0.24 DN^2).  The expected values follow that operating point.

The model's values that the standard's parameters estimate
(:func:`expected_parameters`): K = DN per electron at the operating gain;
QE = the channel's band QE at the light's band x fill factor (the standard
refers QE to the pixel area); temporal dark noise = read noise; saturation
capacity = the signal at the maximum of the photon transfer curve, where
the standard locates it, which the model's noise puts about 1.5 noise
sigmas below the clip (the well, or the ADC's top code in electrons when
the gain brings that first; :func:`photon_transfer_peak`); DSNU (e-) and
PRNU (%) as the sensor's fixed-pattern maps realise them on the measured
pixels (the set rms times the maps' sample deviation: the physical
sensor's values; the nominal ones are kept beside them); dark current
(e-/s) as set.
"""

from __future__ import annotations

__all__ = ["EmvaSettings", "ChannelSeries", "simulate_emva", "expected_parameters", "measurement_gain",
           "clip_electrons", "photon_transfer_peak", "DESCRIPTOR", "GAIN_STEPS"]

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import spectra as _spectra
from ..errors import require
from ..io import atomic_output
from ..io.limits import estimate_capture_bytes, require_memory
from .capture import capture
from .catalogue import get_cfa
from .cfa import make_cfa
from .params import SensorParams
from .physics import with_ir_cut

DESCRIPTOR = "EMVA1288descriptor.txt"
#: Analog gain factors tried, smallest first, to reach 0.5 DN of dark noise.
GAIN_STEPS = (1.0, 1.5, 2.0, 3.0, 4.0, 6.0, 8.0, 12.0, 16.0, 24.0, 32.0)
_MIN_DARK_NOISE_DN = 0.5


@dataclass(frozen=True)
class EmvaSettings:
    """How the measurement is taken.

    Attributes
    ----------
    size : the measured image of each channel is size x size pixels.
    steps : exposures of the ramp, equally spaced from ``0.9 / steps`` to
        0.9 of ``saturation_exposure_s`` (the standard asks for at least 50
        points in all).
    fine_steps : further exposures equally spaced above 0.9 of it up to
        ``overexposure`` times it, where the photon transfer curve peaks,
        so that its maximum is located to better than 1 %.
    overexposure : the ramp's top as a multiple of the saturation exposure
        (the standard's ramp goes past saturation).
    spatial_frames : L, images of each spatial stack (bright and dark).
    saturation_exposure_s : exposure (s) at which the light saturates the channel.
    wavelength_nm : the light's band centre for every channel; None: each
        channel's peak QE band.
    analog_gain : the operating point's analog gain, or None: the sensor's
        own, raised by :data:`GAIN_STEPS` to 0.5 DN of dark noise.
    seed : temporal noise seed of the first image (each image takes the next).
    """

    size: int = 128
    steps: int = 50
    fine_steps: int = 20
    overexposure: float = 1.05
    spatial_frames: int = 16
    saturation_exposure_s: float = 1.0
    wavelength_nm: float | None = None
    analog_gain: float | None = None
    seed: int = 0

    def __post_init__(self):
        for name, lo in (("size", 8), ("steps", 10), ("fine_steps", 1), ("spatial_frames", 3)):
            v = getattr(self, name)
            require(isinstance(v, int) and not isinstance(v, bool) and v >= lo,
                    f"emva {name} must be a whole number of at least {lo}, got {v!r}")
        require(self.size <= 4096, f"emva size {self.size} is above 4096 pixels")
        require(isinstance(self.overexposure, (int, float)) and 1.0 <= self.overexposure <= 2.0,
                f"emva overexposure must lie in [1, 2], got {self.overexposure!r}")

    def ramp(self) -> np.ndarray:
        """The exposures as fractions of the saturation exposure, ascending."""
        coarse = np.linspace(0.9 / self.steps, 0.9, self.steps)
        fine = np.linspace(0.9, self.overexposure, self.fine_steps + 1)[1:]
        return np.concatenate([coarse, fine])
        require(isinstance(self.saturation_exposure_s, (int, float)) and self.saturation_exposure_s > 0
                and math.isfinite(self.saturation_exposure_s),
                f"emva saturation exposure must be a positive number of seconds, got {self.saturation_exposure_s!r}")


@dataclass
class ChannelSeries:
    """One channel's measurement: where its images are and what was set."""

    channel: str
    folder: Path
    wavelength_nm: float
    band_index: int
    exposures_s: np.ndarray
    photons_per_pixel: np.ndarray
    expected: dict = field(default_factory=dict)


def measurement_gain(sensor: SensorParams, channel_gain: float = 1.0) -> float:
    """The analog gain of the operating point: the sensor's, times the
    smallest factor of :data:`GAIN_STEPS` whose temporal dark noise
    (read noise x DN per electron) reaches 0.5 DN (the largest if none does)."""
    for f in GAIN_STEPS:
        if sensor.read_noise_e * sensor.dn_per_electron * channel_gain * f >= _MIN_DARK_NOISE_DN:
            return sensor.analog_gain * f
    return sensor.analog_gain * GAIN_STEPS[-1]


def clip_electrons(sensor: SensorParams, channel: str) -> float:
    """Where a channel's signal clips (electrons): its full well, or the
    ADC's top code when the gain brings that first."""
    k = sensor.dn_per_electron * sensor.channel_value("channel_gain", channel)
    return min(sensor.channel_value("channel_well_e", channel), (sensor.max_dn - sensor.black_level_dn) / k)


def photon_transfer_peak(mean_e: np.ndarray, clip_e: float, prnu_percent: float, dark_e: np.ndarray,
                         read_noise_e: float) -> int:
    """Index of the ramp point where the model's temporal variance peaks:
    the standard's saturation point (EMVA 1288 release 4.0, s. 6.5: the
    maximum of the photon transfer curve), which lies below the clip by
    about 1.5 x the noise of a full pixel.

    Each pixel's signal is taken as normal with variance = its mean + the
    read noise^2 (shot and read noise; Poisson is normal to 0.1 % at these
    counts), PRNU spreading the means over 64 quantiles of a normal, and
    clipped at ``clip_e``; the variance of a clipped normal
    Y = min(X, c), X ~ N(m, s^2), with a = (c - m)/s:
    E[Y] = m Phi(a) - s phi(a) + c (1 - Phi(a)),
    E[Y^2] = (m^2 + s^2) Phi(a) - s (m + c) phi(a) + c^2 (1 - Phi(a))
    (the censored normal; Greene, Econometric Analysis, 7th ed., s. 19.3).
    DSNU and quantisation, small against the shot noise there, are left out.
    """
    from scipy import stats

    z = stats.norm.ppf((np.arange(64) + 0.5) / 64.0)
    m = np.asarray(mean_e, float)[:, None] * (1.0 + prnu_percent / 100.0 * z[None, :]) \
        + np.asarray(dark_e, float)[:, None]
    s = np.sqrt(np.maximum(m, 0.0) + read_noise_e**2)
    a = (clip_e - m) / s
    cdf, pdf = stats.norm.cdf(a), stats.norm.pdf(a)
    ey = m * cdf - s * pdf + clip_e * (1.0 - cdf)
    ey2 = (m * m + s * s) * cdf - s * (m + clip_e) * pdf + clip_e**2 * (1.0 - cdf)
    return int(np.argmax(np.mean(ey2 - ey * ey, axis=1)))


def expected_parameters(sensor: SensorParams, qe_band: float, channel: str) -> dict:
    """The model's values of the EMVA 1288 parameters of one channel
    (module doc), keyed as ``emva1288``'s ``Results1288`` attributes; the
    saturation capacity (``u_e_sat``) is filled in by :func:`simulate_emva`,
    which knows the ramp."""
    return {
        "K": sensor.dn_per_electron * sensor.channel_value("channel_gain", channel),
        "QE": 100.0 * qe_band * sensor.fill_factor,
        "sigma_d": sensor.read_noise_e,
        "DSNU1288": sensor.dsnu_e,
        "PRNU1288": sensor.prnu_percent,
        "u_I_mean": sensor.dark_current_e_s,
        "u_I_var": sensor.dark_current_e_s,
        "clip_e": clip_electrons(sensor, channel),
        "analog_gain": sensor.analog_gain,
    }


def _realised_non_uniformity(sensor: SensorParams, cam) -> dict:
    """DSNU (e-) and PRNU (%) of the measured pixels as the sensor's fixed
    pattern maps realise them (:func:`~.noise.fixed_pattern`): the set rms
    times the maps' sample standard deviation over those pixels, the
    physical sensor's values that the standard measures (the nominal values
    stay in ``dsnu_nominal_e`` and ``prnu_nominal_percent``)."""
    from .noise import fixed_pattern

    prnu_z, dsnu_z = fixed_pattern(cam.shape, sensor.sensor_seed)
    return {"DSNU1288": sensor.dsnu_e * float(np.std(dsnu_z[cam.pick], ddof=1)),
            "PRNU1288": sensor.prnu_percent * float(np.std(prnu_z[cam.pick], ddof=1)),
            "dsnu_nominal_e": sensor.dsnu_e, "prnu_nominal_percent": sensor.prnu_percent}


def _uniform_field(wl: np.ndarray, band: int, radiance: float, shape, sensor: SensorParams):
    """The sensor-plane image of a uniform field of ``radiance`` W/(m^2 sr nm)
    in one band (the lens without falloff or diffraction)."""
    from ..optics import OpticsParams, compute_optics
    from ..values import SpectralImage

    cube = np.zeros((shape[0], shape[1], wl.size))
    cube[..., band] = radiance
    return compute_optics(SpectralImage(cube, wl.copy(), {}),
                          OpticsParams(relative_illumination=False, diffraction=False),
                          pixel_pitch_um=sensor.pixel_pitch_um, oversample=1, fill_factor=sensor.fill_factor)


def _write_png(path: Path, image: np.ndarray, bits: int) -> None:
    from PIL import Image

    dtype = np.uint8 if bits <= 8 else np.uint16
    Image.fromarray(np.ascontiguousarray(image.astype(dtype))).save(path, compress_level=1)  # 2.5x faster than 6


class _Camera:
    """Takes one channel's images through :func:`capture` and writes them."""

    def __init__(self, sensor, cfa, channel, settings: EmvaSettings, folder: Path, seed: int):
        self.sensor, self.channel, self.settings, self.folder = sensor, channel, settings, folder
        n = settings.size
        if sensor.crosstalk or sensor.crosstalk_700nm:
            self.cfa = cfa
            pos = np.argwhere(cfa.pattern == channel)[0]
            th, tw = cfa.tile_shape
            self.shape = (n * th, n * tw)
            self.pick = (slice(int(pos[0]), None, th), slice(int(pos[1]), None, tw))
        else:  # every pixel carries the channel: the same pixel chain, no pixel wasted
            self.cfa = make_cfa(f"{cfa.name}-{channel}", [[channel]], {channel: cfa.curves[channel]},
                                where=f"channel {channel!r} of {cfa.name!r}")
            self.shape = (n, n)
            self.pick = (slice(None), slice(None))
        self.seed = seed
        self.count = 0
        self.lines: list[str] = []

    def series(self, oi, exposure_s: float, frames: int, header: str) -> None:
        self.lines.append(header)
        for _ in range(frames):
            raw = capture(oi, self.cfa, exposure_s=exposure_s, noise="all", seed=self.seed, sensor=self.sensor)
            self.seed += 1
            name = f"image{self.count:05d}.png"
            _write_png(self.folder / "images" / name, raw.raw[self.pick], self.sensor.adc_bits)
            self.lines.append(f"i images/{name}")
            self.count += 1


def measured_sensor(sensor):
    """The sensor as measured: EMVA 1288 images are at most 16 bits, so a
    wider (or, as ISETCam's, unquantised: ``isetcam-default``'s 32 bits)
    ADC is measured through a 16-bit one, with a black level of at least six
    dark-noise sigmas so that the dark images' noise is not cut at code 0.
    K, QE and the electron-domain parameters do not depend on it."""
    if sensor.adc_bits <= 16:
        return sensor
    sixteen = sensor.with_(adc_bits=16, black_level_dn=0.0)
    pedestal = float(np.ceil(6.0 * np.hypot(sensor.read_noise_e, sensor.dsnu_e) * sixteen.dn_per_electron))
    return sixteen.with_(black_level_dn=max(float(sensor.black_level_dn), pedestal))


def simulate_emva(sensor: SensorParams, cfa, out_dir, settings: EmvaSettings | None = None,
                  progress=None) -> list[ChannelSeries]:
    """Take and write the EMVA 1288 image series of every channel.

    Parameters
    ----------
    sensor : the pixel and read-out chain (``readout`` 'full').
    cfa : a :class:`~.cfa.CFA` or a name / TOML path (:func:`get_cfa`).
    out_dir : folder; each channel's series goes to ``out_dir/<channel>/``.
    settings : :class:`EmvaSettings`.
    progress : optional callable(channel, done, total) after each exposure.

    Returns
    -------
    One :class:`ChannelSeries` per channel, in ``cfa.channels`` order.
    """
    settings = settings or EmvaSettings()
    require(sensor.readout == "full", f"sensor emva measures the native pixel: readout must be 'full', "
                                      f"got {sensor.readout!r}")
    sensor = measured_sensor(sensor)
    cfa = with_ir_cut(get_cfa(cfa), sensor.ir_cut)
    wl = np.asarray(_spectra.DEFAULT_WAVELENGTHS, dtype=np.float64)
    qe = cfa.sensitivities(wl)
    out = Path(out_dir)
    photons_per_w = _spectra.photons_per_joule(wl) * _spectra.band_widths(wl) * sensor.pixel_area_m2
    results = []
    for ci, channel in enumerate(cfa.channels):
        cgain = sensor.channel_value("channel_gain", channel)
        gain = settings.analog_gain or measurement_gain(sensor, cgain)
        op = sensor.with_(analog_gain=gain)
        if settings.wavelength_nm is None:
            band = int(np.argmax(qe[ci]))
        else:
            band = int(np.argmin(np.abs(wl - settings.wavelength_nm)))
            require(abs(wl[band] - settings.wavelength_nm) <= 5.0,
                    f"emva wavelength {settings.wavelength_nm:g} nm lies outside the grid {wl[0]:g}..{wl[-1]:g} nm")
        require(qe[ci, band] > 0, f"channel {channel!r} has no QE at {wl[band]:g} nm: choose another wavelength")
        expected = expected_parameters(op, float(qe[ci, band]), channel)
        folder = out / channel
        cam = _Camera(op, cfa, channel, settings, folder, settings.seed + 1_000_000 * ci)
        h, w = cam.shape  # two uniform fields (irradiance and pixel irradiance each) and the captures
        require_memory(2 * 2 * h * w * wl.size * 8 + estimate_capture_bytes(h, w, wl.size),
                       f"sensor emva on {w} x {h} pixels x {wl.size} bands", "give a smaller --size")
        (folder / "images").mkdir(parents=True, exist_ok=True)
        probe = _uniform_field(wl, band, 1.0, cam.shape, op)
        rate = float(capture(probe, cam.cfa, exposure_s=1.0, noise="off", sensor=op)
                     .electrons_per_radiance[0 if cam.cfa.channels == (channel,) else ci, band])
        del probe  # (memory: the fields are (H, W, B) float64)
        radiance = expected["clip_e"] / (rate * settings.saturation_exposure_s)
        bright = _uniform_field(wl, band, radiance, cam.shape, op)
        dark = _uniform_field(wl, band, 0.0, cam.shape, op)
        irradiance = float(np.mean(bright.pixel_irradiance_w_m2_nm[..., band]))
        t_sat = settings.saturation_exposure_s
        exposures = settings.ramp() * t_sat
        photons = irradiance * photons_per_w[band] * exposures
        mean_e = photons * expected["QE"] / 100.0
        peak = photon_transfer_peak(mean_e, expected["clip_e"], op.prnu_percent, op.dark_current_e_s * exposures,
                                    op.read_noise_e)
        expected["u_e_sat"] = float(mean_e[peak])
        expected.update(_realised_non_uniformity(op, cam))
        cam.lines += ["v 4.0", f"n {op.adc_bits} {settings.size} {settings.size}"]  # bits, width, height
        for i, (t, up) in enumerate(zip(exposures, photons)):
            cam.series(bright, t, 2, f"b {t * 1e9:.6f} {up:.6f}")
            cam.series(dark, t, 2, f"d {t * 1e9:.6f}")
            if progress:
                progress(channel, i + 1, len(exposures))
        mid = int(np.argmin(np.abs(exposures - 0.5 * t_sat)))
        cam.series(bright, exposures[mid], settings.spatial_frames, f"b {exposures[mid] * 1e9:.6f} {photons[mid]:.6f}")
        cam.series(dark, exposures[mid], settings.spatial_frames, f"d {exposures[mid] * 1e9:.6f}")
        with atomic_output(folder / DESCRIPTOR) as tmp:  # written last: a descriptor lists finished images
            tmp.write_text("\n".join(cam.lines) + "\n")
        results.append(ChannelSeries(channel, folder, float(wl[band]), band, exposures, photons, expected))
    return results
