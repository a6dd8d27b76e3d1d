"""``cfa-mitsuba process``: placeholder until its issue lands (see DESIGN.md)."""

from __future__ import annotations

from ..errors import CfaMitsubaError

HELP = "process (not implemented yet)"


def add_arguments(parser) -> None:
    parser.add_argument("rest", nargs="*")


def run(args) -> int:
    raise CfaMitsubaError("'process' is not implemented yet")
