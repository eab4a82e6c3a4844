"""Command-line interface: ``heelstrike <command> ...``. It parses, calls and renders, nothing more.

Conventions shared by every command:

- angles accept a ``deg`` or ``rad`` suffix (``20deg``, ``0.3rad``); bare numbers are radians;
- lengths are metres, masses kilograms, times seconds;
- ``--json`` prints exactly one JSON object on stdout, or nothing: a non-finite result is an
  error;
- with ``--model``, a compass-gait option sets the model's parameter of the same name (``--radius``
  sets ``R``) or is refused; no option is silently ignored;
- outputs, frame rates and memory are checked before computing;
- every failure (bad input, unwritable output, out of memory, an unexpected error) exits with
  status 2 and a one-line ``heelstrike: error: ...`` message on stderr; ``HEELSTRIKE_DEBUG=1``
  adds the traceback.
Layout: :mod:`heelstrike.cli._common` parses (units, walker and model options),
:mod:`heelstrike.cli._render` renders (JSON, one-line errors), and one module per command group
(:mod:`~heelstrike.cli.paper`, :mod:`~heelstrike.cli.gait`, :mod:`~heelstrike.cli.powered`,
:mod:`~heelstrike.cli.robot`) registers its subcommands with an ``add_<name>(subparsers)``
function that sets ``func`` to the command's ``_run_<name>(args) -> int``.
"""

from __future__ import annotations

import argparse
import os
import sys
import warnings
from collections.abc import Callable, Sequence
from typing import Any

from heelstrike._caching import CacheWarning
from heelstrike._optional import MissingExtraError
from heelstrike._version import __version__
from heelstrike.cli import design, gait, paper, powered, robot
from heelstrike.cli._common import (
    CliError,
    DeprecatedOptionWarning,
    Parser,
    ShippedNameWarning,
    UnusedParameterWarning,
    parse_angle,
    parse_range,
    release_claims,
    warnings_as_notes,
)
from heelstrike.cli._render import fail, one_line

__all__ = ["CliError", "build_parser", "main", "parse_angle", "parse_range"]

#: The subcommands in the order ``heelstrike --help`` lists them.
_COMMANDS: tuple[Callable[[Any], None], ...] = (
    paper.add_reproduce,
    paper.add_impact,
    gait.add_gait,
    gait.add_walk,
    gait.add_bifurcation,
    gait.add_basin,
    gait.add_map,
    paper.add_impact_map,
    powered.add_powered,
    powered.add_study,
    design.add_design,
    robot.add_robot_command,
)


def build_parser() -> argparse.ArgumentParser:
    """The ``heelstrike`` argument parser with every registered command."""
    parser = Parser(
        prog="heelstrike",
        description="Impulsive dynamics and energetics of walking machines.",
    )
    parser.add_argument("--version", action="version", version=f"heelstrike {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=Parser)
    for add in _COMMANDS:
        add(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``heelstrike`` command; returns the exit status.

    Every failure ends in one line ``heelstrike: error: ...`` on stderr and exit status 2;
    set ``HEELSTRIKE_DEBUG=1`` to see the traceback of unexpected errors.
    """
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
        from heelstrike.analysis.newton import SearchTimeLimitWarning

        # a cut search and a file named like a shipped walker are news, said as such
        # and so are cache fallbacks and numerical warnings: one line each, no source shown
        with warnings_as_notes(SearchTimeLimitWarning, ShippedNameWarning,
                               UnusedParameterWarning, CacheWarning, RuntimeWarning,
                               DeprecatedOptionWarning):
            for note in vars(args).get("deprecated", ()):  # old option names (DeprecatedAlias)
                warnings.warn(note, DeprecatedOptionWarning, stacklevel=1)
            status = int(args.func(args))
    except CliError as exc:
        return fail(one_line(exc))
    except (ValueError, ArithmeticError, NotImplementedError) as exc:  # said as they are
        return fail(one_line(exc))
    except MemoryError as exc:
        detail = one_line(exc) if str(exc) else "the computation needs more memory than is free"
        return fail(f"out of memory: {detail}")
    except KeyboardInterrupt:
        print("heelstrike: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # the reader of stdout went away (e.g. `| head`): nothing to say
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 2
    except OSError as exc:
        where = f" {exc.filename!r}" if exc.filename else ""
        return fail(f"{exc.strerror or one_line(exc)}{where}")
    except MissingExtraError as exc:  # e.g. a sweep store without heelstrike[scale]
        return fail(one_line(exc))
    except RecursionError:  # a structure nested past Python's recursion limit
        return fail("the input is nested too deeply to process (Python's recursion limit): "
                    "flatten the walker file's expressions or tables")
    except Exception as exc:  # the last resort: one line, never a traceback
        hint = "" if os.environ.get("HEELSTRIKE_DEBUG") == "1" else \
            " (set HEELSTRIKE_DEBUG=1 for the traceback)"
        return fail(f"unexpected {type(exc).__name__}: {one_line(exc)}{hint}")
    finally:
        release_claims()  # the --out folders this run claimed
    return status


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
