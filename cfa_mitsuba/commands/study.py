"""``cfa-mitsuba study``: placeholder until its issue lands (see DESIGN.md)."""

from __future__ import annotations

from ..errors import CfaMitsubaError

HELP = "study (not implemented yet)"


def add_arguments(parser) -> None:
    parser.add_argument("rest", nargs="*")


def run(args) -> int:
    raise CfaMitsubaError("'study' is not implemented yet")
