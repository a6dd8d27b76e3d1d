"""The puppy's spectral textures (:mod:`.texture`, drawn by :mod:`.patterns`).

Detail from low frequencies to well beyond the sensor's Nyquist, so that
demosaicking shows.  At the puppy's default 720 x 636 and 10 degrees, a
pixel is 0.29 mm on the dog (1.2 m) and the sensor's Nyquist period is two
pixels, 0.58 mm; at the quick study's 240 x 212 a pixel is 0.88 mm.

- ``fur`` (dog's body, head, legs, tail): a 1024-texel tile of 0.1 mm
  texels, 'orange' with hair strands four texels (0.4 mm, about 1.4 px at
  720 x 636) wide and 15-50 long running down the body, combed into lanes
  eight texels apart (dark strands on one half of a lane, light ones on the
  other: a fine stripe of period 0.8 mm, 2.8 px face-on and finer where the
  body turns away), dark ('black 2 (1.5 D)': in wavy tabby bands 6.4 mm
  apart, patches a few mm across and locks of about 1 mm, from smooth
  noise) and light ('neutral 8 (.23 D)', between the bands).  Strong
  luminance contrast at the pixel scale: with strands narrower than a pixel
  (0.2 mm) on a red base, the fur averaged to a low-contrast mottle with
  dark, noisy green pixels, where bilinear's smoothing won every image
  metric at the paper's size; with uncombed 0.4-mm strands it still won
  HaarPSI against laplacian (docs/scenes.md).
- ``fur_brown`` (ears, snout): the same construction on 'dark skin' with
  'black 2 (1.5 D)' and white strands.
- ``wallpaper`` (backdrop, 3 m): light discs 16 mm across with dark rings,
  dark lines 3 mm wide and pinstripes on 'neutral 6.5 (.44 D)' (0.25 mm
  texels), coarse enough to survive the thin lens's defocus.
- ``poster_*`` (the three coloured panels at 2.2-2.7 m): their colour with
  black stripes 2 mm wide and dots.  Out-of-focus flat fields are where a
  smoothing demosaic wins on noise alone; the backdrop and panels carry
  detail that survives the blur, as a photograph's background does.
- ``tablecloth``: a plain-weave gingham of 1-mm threads, 'light skin' and
  'purplish blue' in bands of 6 threads (a 12 mm tile), the grooves between
  threads mixed with 'neutral 5 (.70 D)'.  Seen at a grazing angle, its
  depth-wise period is compressed far below a pixel: moire.
- ``chart`` (a card standing behind the dog, right): black ink on white,
  0.075 mm texels: a title, text lines 7 x 5 font pixels of 0.6 to 0.075 mm
  (the smallest far below a pixel), USAF-1951-like bar groups of bar widths
  1.8 to 0.075 mm (periods 3.6 to 0.15 mm, in both orientations), four
  chirped gratings (vertical, horizontal, both diagonals) whose period runs
  from 0.9 to 0.45 mm (3 to 1.5 px) through the Nyquist period, and a
  36-spoke Siemens star 27 mm across.
- ``colour_print`` (a card behind the dog's head, left): six inks on white
  ('red', 'green', 'blue', 'yellow', 'magenta', 'cyan'): fine lines of each
  ink 0.6 to 0.075 mm wide, a magenta-on-green zone plate (0 to 6.7
  cycles/mm), a blue-on-yellow stripe chirp (periods 3 to 0.15 mm), red and
  green checks of 0.45 and 0.225 mm, coloured text.

- ``toy_block``: the blue block is a letter block, a yellow 'A' in a
  yellow frame on a blue face dotted with yellow (0.4 mm texels; defocused,
  0.88 m).

Textures are built once per process (they depend on nothing but the code).
"""

from __future__ import annotations

__all__ = ["FUR_TILE_M", "POSTER_TILE_M", "fur", "fur_brown", "tablecloth", "chart", "colour_print", "poster",
           "all_textures"]

import functools

import numpy as np

from . import patterns as P
from .texture import SpectralTexture

_FUR_SIZE, _FUR_TEXEL = 1024, 1e-4
_FUR_LANE = 8  # texels between combed lanes: 0.8 mm
#: Physical size (m) of one fur tile.
FUR_TILE_M = _FUR_SIZE * _FUR_TEXEL
_CARD_TEXEL = 7.5e-5
_WHITE, _BLACK, _LIGHT = "white 9.5 (.05 D)", "black 2 (1.5 D)", "neutral 8 (.23 D)"


def _fur_weights(seed: int) -> np.ndarray:
    """(size, size, 3) weights: base, dark strands, light strands."""
    n = _FUR_SIZE
    patches = P.smooth_noise((n, n), 40.0, seed)  # darker patches, ~4 mm
    locks = P.smooth_noise((n, n), 8.0, seed + 3)  # locks of hair, ~1 mm
    # Tabby stripes: wavy dark bands along the strands, 64 texels (6.4 mm) apart.
    warp = P.smooth_noise((n, n), 24.0, seed + 4)
    cols = np.arange(n)[None, :] / 64.0
    stripes = (0.5 + 0.5 * np.sin(2 * np.pi * (cols + 1.5 * warp))) ** 4
    # Combed: strands half a lane wide start on lanes _FUR_LANE texels apart
    # and stray by at most 3 degrees; the light strands fill the other half.
    half = _FUR_LANE // 2
    dark = P.fur_strands(n, 12000, (15.0, 50.0), 3.0, seed + 1,
                         density=0.01 + (0.3 * patches ** 3 + stripes) * (0.2 + locks ** 2), width=half, lane=_FUR_LANE)
    light = np.roll(P.fur_strands(n, 6000, (15.0, 40.0), 3.0, seed + 2, density=0.05 + (1.0 - stripes) * locks ** 2,
                                  width=half, lane=_FUR_LANE), half, axis=1)
    w_dark = np.minimum(0.95, 0.8 * dark)
    w_light = np.minimum(0.9, 0.7 * light) * (1.0 - w_dark)
    return np.stack([1.0 - w_dark - w_light, w_dark, w_light], axis=-1).astype(np.float32)


@functools.lru_cache(maxsize=1)
def fur() -> SpectralTexture:
    return SpectralTexture("fur: orange with black and light hair strands, tabby bands", ("orange", _BLACK, _LIGHT),
                           _fur_weights(11), _FUR_TEXEL)


@functools.lru_cache(maxsize=1)
def fur_brown() -> SpectralTexture:
    return SpectralTexture("brown fur: dark skin with black and light hair strands",
                           ("dark skin", _BLACK, _LIGHT), _fur_weights(23), _FUR_TEXEL)


@functools.lru_cache(maxsize=1)
def tablecloth() -> SpectralTexture:
    band = [0] * 6 + [1] * 6
    colour, groove = P.plain_weave(12, 8, band, band)
    w = np.zeros(colour.shape + (3,), dtype=np.float32)
    for k in (0, 1):
        w[..., k] = (colour == k) * (1.0 - 0.5 * groove)
    w[..., 2] = 0.5 * groove
    return SpectralTexture("tablecloth: gingham plain weave, 1 mm threads", ("light skin", "purplish blue",
                                                                             "neutral 5 (.70 D)"), w, 1.25e-4)


def _text(c: P.Canvas, text: str, scale: int, top: int, left: int, ink: int) -> int:
    """Paint a line of text; returns the row below it."""
    m = P.text_mask(text, scale)
    c.paint(m, ink, top, left)
    return top + m.shape[0]


@functools.lru_cache(maxsize=1)
def chart() -> SpectralTexture:
    """Black on white: title, text lines, bar groups, chirped gratings, Siemens star."""
    c = P.Canvas(1008, 1136, 2)
    row = _text(c, "CFA TEST 1951", 10, 24, 24, 1) + 20
    for scale, line in ((6, "THE QUICK BROWN FOX"), (4, "JUMPS OVER THE LAZY DOG"), (3, "SPHINX OF BLACK QUARTZ 0123456789"),
                        (2, "PACK MY BOX WITH FIVE DOZEN LIQUOR JUGS - 2.2 UM PIXELS AT 1.2 M"),
                        (1, "HOW VEXINGLY QUICK DAFT ZEBRAS JUMP / THE FIVE BOXING WIZARDS JUMP QUICKLY - " * 2)):
        row = _text(c, line, scale, row, 24, 1) + 2 * scale + 4
    top, left, tallest = row + 10, 24, 0
    for bar in (24, 16, 12, 8, 6, 4, 3, 2, 1):
        v, h = P.bar_group(bar, vertical=True), P.bar_group(bar, vertical=False)
        width = v.shape[1] + h.shape[1] + 2 * bar
        if left + width > 620:  # next row of groups, left of the star
            top, left, tallest = top + tallest + 16, 24, 0
        c.paint(v, 1, top, left)
        c.paint(h, 1, top, left + v.shape[1] + 2 * bar)
        left += width + 20
        tallest = max(tallest, v.shape[0])
    c.paint(P.siemens_star(440, 36), 1, 540, 660)
    row = max(row, top + tallest + 24)
    for line in ("GRATINGS BELOW: PERIODS 0.9 TO 0.45 MM,", "3 TO 1.5 SENSOR PIXELS AT 1.2 M, THE",
                 "NYQUIST PERIOD, 2 PX, HALF WAY ACROSS:", "VERTICAL, HORIZONTAL AND DIAGONAL."):
        row = _text(c, line, 2, row, 24, 1) + 8
    # Gratings through the sensor's Nyquist: periods 12 to 6 texels (0.9 to
    # 0.45 mm, 3 to 1.5 px at 720 x 636), vertical, horizontal, diagonal.
    for k, angle in enumerate((0.0, 90.0, 45.0, -45.0)):
        c.paint(P.chirp_grating(130, 296, 12.0, 6.0, angle), 1, 610 + 146 * (k // 2), 24 + 312 * (k % 2))
    for k, scale in enumerate((2, 1)):
        _text(c, "0123456789 ABCDEFGHIJKLMNOPQRSTUVWXYZ", scale, 900 + 24 * k, 24, 1)
    return SpectralTexture("test chart: text, bar groups, gratings, Siemens star", (_WHITE, _BLACK), c.weights,
                           _CARD_TEXEL)


@functools.lru_cache(maxsize=1)
def colour_print() -> SpectralTexture:
    """Six inks on white: fine lines, a zone plate, a chirp, checks, text."""
    inks = ("red", "green", "blue", "yellow", "magenta", "cyan")
    c = P.Canvas(672, 1072, 1 + len(inks))
    for k, name in enumerate(inks):  # a column of line groups per ink
        left = 16 + 88 * k
        top = _text(c, name.upper(), 2, 20, left, 1 + k) + 16
        for width in (8, 4, 2, 1):
            lines = P.bar_group(width, n_bars=max(3, 40 // (2 * width)), length_bars=max(1, 72 // width),
                                vertical=width % 2 == 0)
            c.paint(lines[:72, :72], 1 + k, top, left)
            top += 84
    ring = P.zone_rings(400, 0.25)
    c.paint(np.ones_like(ring), 2, 16, 560)  # green disc ...
    disc = P.zone_rings(400, 1e-9)  # the disc alone (no rings at ~zero frequency)
    c.paint(1.0 - disc, 0, 16, 560)  # ... trimmed to its circle
    c.paint(ring * disc, 5, 16, 560)  # magenta rings on it
    c.paint(np.ones((96, 520), np.float32), 4, 440, 536)  # yellow strip ...
    c.paint(P.chirp_stripes(96, 520, 40.0, 2.0), 3, 440, 536)  # ... with blue stripes
    for j, cell in enumerate((6, 3)):
        c.paint(np.ones((96, 96), np.float32), 2, 560, 16 + 112 * j)
        idx = np.arange(96) // cell
        c.paint(((idx[:, None] + idx[None, :]) % 2).astype(np.float32), 1, 560, 16 + 112 * j)  # red checks
    _text(c, "CYAN", 4, 560, 260, 6)
    _text(c, "MAGENTA", 4, 600, 260, 5)
    c.paint(np.ones((22, 200), np.float32), 3, 637, 256)
    _text(c, "YELLOW ON BLUE", 2, 640, 260, 4)
    return SpectralTexture("colour print: fine lines, zone plate, chirp, checks, text", (_WHITE,) + inks, c.weights,
                           _CARD_TEXEL)


@functools.lru_cache(maxsize=1)
def wallpaper() -> SpectralTexture:
    """Grey wallpaper: light discs 16 mm across on a 24 mm grid, offset
    every other row, each with a dark ring, and dark lines 3 mm wide between
    the rows, over a fine dark pinstripe (a 48 mm tile of 0.25 mm texels).
    The backdrop is 3 m away, out of focus (about 4.6 px of defocus at f/4):
    its pattern is kept coarse and contrasted enough to survive the blur, so
    it is detail, not a flat noisy field where smoothing wins."""
    n = 192
    y, x = np.mgrid[0:n, 0:n] + 0.5
    d = np.full((n, n), np.inf)
    for cy, cx in ((24, 24), (24, 120), (120, 72), (120, 168), (120, -24), (216, 24), (216, 120), (24, 216),
                   (216, 216)):
        d = np.minimum(d, np.hypot(y - cy, x - cx))
    c = P.Canvas(n, n, 3)
    c.paint(((np.arange(n)[None, :] % 16) < 4).astype(np.float32) * np.ones((n, 1), np.float32), 2)
    c.paint((d < 32).astype(np.float32), 1)
    c.paint(((d >= 20) & (d < 26)).astype(np.float32), 2)
    lines = np.zeros((n, n), np.float32)
    lines[66:78] = lines[162:174] = 1.0
    c.paint(lines, 2)
    return SpectralTexture("wallpaper: light discs with dark rings, dark lines and pinstripes on grey",
                           ("neutral 6.5 (.44 D)", "white 9.5 (.05 D)", "black 2 (1.5 D)"), c.weights, 2.5e-4)


#: The puppy's printed panels, by panel name.
_POSTERS = {"yellow": "yellow", "orange_yellow": "orange yellow", "blue_green": "bluish green"}
#: Side of one poster tile (m): see :func:`poster`.
POSTER_TILE_M = 0.024


@functools.lru_cache(maxsize=8)
def poster(colour: str) -> SpectralTexture:
    """A coloured panel printed with black diagonal stripes 2 mm wide,
    6 mm apart, and a black dot in every other gap (a 24 mm tile of
    0.25 mm texels).  The panels stand 2.2-2.7 m away, out of focus; as for
    the wallpaper, a coarse print keeps them detail rather than flat noisy
    fields."""
    n = 96
    y, x = np.mgrid[0:n, 0:n] + 0.5
    stripes = (((x + y) % 24) < 8).astype(np.float32)
    dots = (np.hypot((x % 24) - 18, (y % 48) - 30) < 3.5).astype(np.float32)
    c = P.Canvas(n, n, 2)
    c.paint(np.maximum(stripes, dots), 1)
    return SpectralTexture(f"{colour} poster: black stripes and dots", (colour, _BLACK), c.weights, 2.5e-4)


@functools.lru_cache(maxsize=1)
def toy_block() -> SpectralTexture:
    """A letter block's face: a yellow letter in a yellow frame on blue,
    the blue printed with a yellow grid of dots 1.6 mm apart (Mitsuba's cube
    repeats a face's uv square on every face)."""
    c = P.Canvas(128, 128, 2)
    y, x = np.mgrid[0:128, 0:128]
    c.paint((((y % 4) < 2) & ((x % 4) < 2)).astype(np.float32), 1)
    frame = np.ones((128, 128), np.float32)
    frame[10:-10, 10:-10] = 0.0
    c.paint(frame, 1)
    c.paint(np.pad(np.ones((56, 60), np.float32), ((16, 56), (30, 38))), 0)
    c.paint(P.text_mask("A", 12), 1, 22, 34)
    return SpectralTexture("toy block: a yellow letter and frame on blue dotted with yellow", ("blue", "yellow"),
                           c.weights, 4e-4)


@functools.lru_cache(maxsize=1)
def all_textures() -> dict[str, SpectralTexture]:
    """Every puppy texture by name."""
    return {"fur": fur(), "fur_brown": fur_brown(), "tablecloth": tablecloth(), "chart": chart(),
            "colour_print": colour_print(), "toy_block": toy_block(), "wallpaper": wallpaper(),
            **{f"poster_{k}": poster(v) for k, v in _POSTERS.items()}}
