"""Argument checks shared by the sub-commands: argparse ``type=``
converters (a bad value becomes argparse's one-line usage error, exit 2,
naming the option) and the output-directory probe."""

from __future__ import annotations

import argparse

__all__ = ["positive_int", "non_negative_int", "positive_float", "non_negative_float", "check_out_dir",
           "write_scene_files"]


def _int_at_least(text: str, minimum: int) -> int:
    try:
        n = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a whole number, got {text!r}") from None
    if n < minimum:
        raise argparse.ArgumentTypeError(f"must be at least {minimum}, got {n}")
    return n


def positive_int(text: str) -> int:
    """A whole number >= 1 (sizes, counts, worker processes)."""
    return _int_at_least(text, 1)


def non_negative_int(text: str) -> int:
    """A whole number >= 0 (seeds, optional counts)."""
    return _int_at_least(text, 0)


def _finite_float(text: str, ok, what: str) -> float:
    import math

    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not (math.isfinite(v) and ok(v)):
        raise argparse.ArgumentTypeError(f"must be a {what} number, got {text!r}")
    return v


def positive_float(text: str) -> float:
    """A finite number > 0 (luminances, lengths, f-numbers, gains)."""
    return _finite_float(text, lambda v: v > 0, "positive")


def non_negative_float(text: str) -> float:
    """A finite number >= 0 (noise levels, offsets)."""
    return _finite_float(text, lambda v: v >= 0, "non-negative")


def check_out_dir(out) -> None:
    """Refuse an output directory that cannot be created or written, before
    rendering, by really trying (permission bits say little to root);
    nothing is left behind."""
    import tempfile

    from ..errors import CfaMitsubaError

    if out.exists() and not out.is_dir():
        raise CfaMitsubaError(f"output directory {str(out)!r} is a file")
    probe_in = out if out.exists() else out.absolute().parent
    while not probe_in.exists():
        probe_in = probe_in.parent
    if not probe_in.is_dir():
        raise CfaMitsubaError(f"cannot create output directory {str(out)!r}: {str(probe_in)!r} is a file")
    try:
        tempfile.TemporaryDirectory(dir=probe_in, prefix=".cfa-mitsuba-probe-").cleanup()
    except OSError as exc:
        what = "write to" if out.exists() else "create"
        raise CfaMitsubaError(f"cannot {what} output directory {str(out)!r}: {exc.strerror}") from None


def write_scene_files(exr, image, *, preview: bool) -> list:
    """Write a scene's spectral EXR, its sidecar and (``preview``) an sRGB
    PNG beside them; on any failure remove what was written, so no half
    set is left.  Returns the paths written, for the command to print."""
    from ..io.exr import write_spectral_exr
    from ..io.sidecar import write_sidecar

    side = exr.with_suffix(".json")
    write_spectral_exr(exr, image)
    written = [exr, side]
    try:
        write_sidecar(side, image.meta)
        if preview:
            from ..render.preview import write_preview

            written.append(write_preview(exr.with_suffix(".png"), image))
    except BaseException:
        exr.unlink(missing_ok=True)
        side.unlink(missing_ok=True)
        raise
    return written
