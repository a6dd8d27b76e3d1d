"""Read-out modes of the block layouts: full, remosaic and binning.

Quad Bayer (Sony IMX586, Samsung Tetracell), Nonacell (Samsung HM1) and
Tetra2pixel (Samsung HP1) are a Bayer tile with every pixel replaced by an
n x n block of one colour (n = 2, 3, 4).  Such a sensor is read in one of
three ways (research/cfa-design.md; :data:`.params.READOUT_MODES`):

* ``full``: every pixel, the native mosaic demosaiced as it is;
* ``remosaic``: every pixel, rearranged by the image processor into a
  full-resolution Bayer mosaic (:mod:`cfa_mitsuba.isp.remosaic`) that a
  standard demosaicker then reads;
* ``bin``: each same-colour block summed into one pixel, a Bayer mosaic
  at 1/n the resolution.  ``binning = "charge"``: the block's photodiodes
  share a sense node, so their charge is summed before the one read (read
  noise and DSNU added once per binned pixel; each photodiode still clips
  at its own well).  ``binning = "digital"``: every photodiode is read and
  quantised as usual and the codes are averaged (read noise once per
  sub-pixel, so its variance is n^2 times that of charge binning in the
  sum).  Either way the binned DN keep the scale of one pixel: DN per
  electron of the summed charge is that of one pixel / n^2, so a full
  block reaches the top code, and ``electrons_per_radiance`` of the binned
  pixel is n^2 times a pixel's.

Shot noise is the same in both (Poisson per photodiode, summed); against a
single pixel the binned pixel's shot-noise SNR is sqrt(n^2) = n times
higher, and with read noise sigma_r its SNR is
n^2 S / sqrt(n^2 S + sigma_r^2) (charge) or n^2 S / sqrt(n^2 (S + sigma_r^2))
(digital) for S electrons per photodiode.
"""

from __future__ import annotations

__all__ = ["block_size", "binned_pattern", "readout_applies", "require_block_layout", "block_sum", "block_mean"]

import numpy as np

from ..errors import CfaMitsubaError


def block_size(pattern) -> int:
    """The side n of the same-colour blocks of a tile: the largest n >= 2
    such that the tile is made of uniform n x n blocks whose reduced tile
    still has more than one filter; 1 when there is none (Bayer, X-Trans)."""
    p = np.asarray(pattern)
    th, tw = p.shape
    for n in range(min(th, tw), 1, -1):
        if th % n or tw % n:
            continue
        blocks = p.reshape(th // n, n, tw // n, n)
        if np.all(blocks == blocks[:, :1, :, :1]) and np.unique(blocks[:, 0, :, 0]).size > 1:
            return n
    return 1


def binned_pattern(pattern) -> np.ndarray:
    """The tile one pixel per block (quad-bayer's ``G R / B G``): the mosaic
    that binning gives and remosaic aims at."""
    p = np.asarray(pattern)
    n = block_size(p)
    return p[::n, ::n].copy()


def readout_applies(pattern, readout: str) -> bool:
    """Whether ``readout`` means anything on this tile: ``full`` always,
    ``remosaic`` and ``bin`` only on a block layout."""
    return readout == "full" or block_size(pattern) > 1


def require_block_layout(pattern, readout: str, name: str = "this CFA") -> int:
    """The block size, or a one-line error when ``readout`` needs blocks the tile lacks."""
    n = block_size(pattern)
    if readout != "full" and n == 1:
        raise CfaMitsubaError(f"readout {readout!r} needs a block layout (quad-bayer, nona, tetra2: Bayer with "
                              f"n x n same-colour blocks); {name} has none (use readout 'full')")
    return n


def block_sum(a: np.ndarray, n: int) -> np.ndarray:
    """(H // n, W // n): the sum of each aligned n x n block (a partial
    block at the bottom or right border is left out)."""
    h, w = (a.shape[0] // n) * n, (a.shape[1] // n) * n
    return a[:h, :w].reshape(h // n, n, w // n, n).sum(axis=(1, 3))


def block_mean(a: np.ndarray, n: int) -> np.ndarray:
    """(H // n, W // n): the mean of each aligned n x n block."""
    return block_sum(a, n) / float(n * n)


def read_binned(electrons: np.ndarray, n: int, *, sensor, noise: str, rng, gain=None) -> np.ndarray:
    """The binned raw (H // n, W // n) DN of the collected ``electrons``
    (module doc): ``sensor.binning`` 'charge' sums the charge and reads it
    once, 'digital' reads every photodiode and averages the codes.  Either
    way DN per electron of the summed charge is ``sensor.dn_per_electron /
    n^2``.  ``gain``: the relative per-channel gain of each photodiode
    ((H, W)) or None."""
    from .noise import read_out

    if sensor.binning == "charge":
        summed = block_sum(electrons, n)
        sense_node = sensor.with_(well_capacity_e=sensor.well_capacity_e * n * n)  # DN per e- / n^2
        g = None if gain is None else gain[: summed.shape[0] * n: n, : summed.shape[1] * n: n]
        return read_out(summed, sensor=sense_node, noise=noise, rng=rng, gain=g)
    return block_mean(read_out(electrons, sensor=sensor, noise=noise, rng=rng, gain=gain), n)
