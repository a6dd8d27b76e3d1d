"""The lines of a CFA TOML that the design writes (candidates in
design/fullchain.py, transposed tiles in design/orientation.py): one
letter's QE curve, and the file written at once."""

from __future__ import annotations

__all__ = ["curve_line", "write_lines"]

from pathlib import Path

from ..io import atomic_output


def curve_line(letter: str, wavelengths, qe, digits: int = 6) -> str:
    """One letter's QE curve as a CFA TOML ``[spectra]`` line."""
    return (f"{letter} = {{ wavelengths = [{', '.join(f'{x:g}' for x in wavelengths)}], "
            f"values = [{', '.join(f'{v:.{digits}g}' for v in qe)}] }}")


def write_lines(path, lines) -> Path:
    """Write a TOML's lines at once (no half-written file)."""
    p = Path(path)
    with atomic_output(p) as tmp:
        tmp.write_text("\n".join(lines) + "\n")
    return p
