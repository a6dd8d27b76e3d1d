"""argparse ``type=`` converters shared by the sub-commands: a bad value
becomes argparse's one-line usage error (exit 2) naming the option."""

from __future__ import annotations

import argparse

__all__ = ["positive_int", "non_negative_int"]


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
