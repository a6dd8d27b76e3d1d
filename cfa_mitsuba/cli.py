"""The ``cfa-mitsuba`` command line: parses arguments, calls the stages, prints.

Each sub-command lives in ``cfa_mitsuba/commands/<name>.py`` with
``HELP`` (one line), ``add_arguments(parser)`` and ``run(args) -> int``;
those modules import the heavy stages (Mitsuba, colour-science) only inside
``run``, so ``--help`` is instant.

Exit status: 0 on success; 2 with a single line ``cfa-mitsuba <cmd>: error:
...`` on stderr and no traceback for any bad input (a
:class:`~cfa_mitsuba.errors.CfaMitsubaError`, an unreadable or unwritable
path, a bad argument); 130 on Ctrl-C.
"""

from __future__ import annotations

import argparse
import importlib
import sys

from .errors import CfaMitsubaError, one_line

#: Sub-commands in the order ``--help`` lists them (module names under commands/).
COMMANDS = (
    "list",
    "render",
    "capture",
    "process",
    "metric",
    "evaluate",
    "study",
    "report",
    "convergence",
    "design",
    "league",
    "sensor",
    "parity",
)


class _Parser(argparse.ArgumentParser):
    """argparse with a one-line error (no usage dump) and exit status 2."""

    def error(self, message):  # noqa: D401 - argparse API
        sys.stderr.write(f"{self.prog}: error: {message} (see --help)\n")
        sys.exit(2)


def _command_module(name: str):
    return importlib.import_module(f".commands.{name.replace('-', '_')}", __package__)


def build_parser() -> argparse.ArgumentParser:
    from ._version import __version__

    parser = _Parser(
        prog="cfa-mitsuba",
        description="Physically based camera simulator and image-quality metrics for colour filter arrays.",
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True
    for name in COMMANDS:
        mod = _command_module(name)
        p = sub.add_parser(
            name,
            help=mod.HELP,
            description=getattr(mod, "DESCRIPTION", mod.HELP),
            formatter_class=argparse.RawDescriptionHelpFormatter,
        )
        mod.add_arguments(p)
        p.set_defaults(_run=mod.run, _prog=p.prog)
    return parser


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args._run(args) or 0)
    except CfaMitsubaError as exc:
        msg = one_line(exc)  # one line, whatever the message held
        sys.stderr.write(f"{args._prog}: error: {msg}\n")
        return 2
    except OSError as exc:  # unreadable input, unwritable output, full disk
        where = f" {exc.filename!r}" if getattr(exc, "filename", None) else ""
        sys.stderr.write(f"{args._prog}: error: {exc.strerror or exc}{where}\n")
        return 2
    except KeyboardInterrupt:
        sys.stderr.write(f"{args._prog}: interrupted\n")
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
