"""``cfa-mitsuba render``: placeholder until its issue lands (see DESIGN.md)."""

from __future__ import annotations

from ..errors import CfaMitsubaError

HELP = "render (not implemented yet)"


def add_arguments(parser) -> None:
    parser.add_argument("rest", nargs="*")


def run(args) -> int:
    raise CfaMitsubaError("'render' is not implemented yet")
