"""Parsing shared by the commands: units and ranges, walker and model options, actuation
options, output directories and resumable stores. It builds inputs; it computes nothing."""

from __future__ import annotations

import argparse
import contextlib
import math
import os
import re
import sys
import warnings
from collections.abc import Callable, Iterator, Sequence
from typing import Any, NoReturn


class CliError(Exception):
    """A user-facing error: printed as one line, exit status 2."""


class Parser(argparse.ArgumentParser):
    def __init__(self, *args: Any, **kwargs: Any) -> None:
        # an option is given by its whole name: an abbreviation is an error, not a guess
        # (``bifurcation --slope 3deg`` was read as ``--slope-range``: issue 32)
        kwargs.setdefault("allow_abbrev", False)
        super().__init__(*args, **kwargs)
        # A negative value with a unit or a range (``--angle -20deg``, ``--slope -3deg``,
        # ``--radius -0.1:0.3:3``) is a value, not an option: argparse's own pattern only
        # knows bare numbers and would answer "expected one argument" instead of saying what
        # is wrong with the value. No heelstrike option starts with "-" and a digit.
        self._negative_number_matcher = re.compile(r"^-\.?\d")

    def error(self, message: str) -> NoReturn:
        # "argument --slope: must be ..." reads "--slope must be ..."
        m = re.fullmatch(r"argument (--[\w-]+): (must .*)", message, flags=re.DOTALL)
        if m:
            raise CliError(f"{m[1]} {m[2]}")
        # a missing subcommand: name the choices, not the parser's internal destination
        for action in self._actions:
            if (isinstance(action, argparse._SubParsersAction)
                    and message == f"the following arguments are required: {action.dest}"):
                raise CliError(f"{self.prog} needs a command: {', '.join(action.choices)} "
                               f"(see '{self.prog} --help')")
        raise CliError(message)


def parse_angle(text: str) -> float:
    """Parse ``'20deg'``, ``'0.3rad'`` or ``'0.3'`` (radians) into radians."""
    t = str(text).strip().lower()
    factor = 1.0
    if t.endswith("deg"):
        t, factor = t[:-3], math.pi / 180.0
    elif t.endswith("rad"):
        t = t[:-3]
    try:
        value = float(t) * factor
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"invalid angle {text!r}: use e.g. 20deg, 0.35rad or 0.35 (radians)"
        ) from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"invalid angle {text!r}: must be finite")
    return value


def parse_slope(text: str) -> float:
    """Parse a ground slope like :func:`parse_angle`, refusing one of 90 deg or more (no
    walkable incline): the usual cause is a bare number read as radians (``3`` is 172 deg),
    and the message says so."""
    value = parse_angle(text)
    if abs(value) >= math.pi / 2:
        bare = not str(text).strip().lower().endswith(("deg", "rad"))
        hint = (f": a bare number is radians; for degrees write {str(text).strip()}deg"
                if bare else "")
        raise argparse.ArgumentTypeError(
            f"must be below 90deg in magnitude (a walkable incline), got {str(text).strip()!r} = "
            f"{math.degrees(value):.6g} deg{hint}")
    return value


def parse_range(
    text: str, convert: Callable[[str], float] = float
) -> tuple[float, float, int | None]:
    """Parse ``'start:stop'`` or ``'start:stop:count'`` (count points, inclusive), or one
    value ``'v'``: the one point ``v:v:1``."""
    parts = str(text).split(":")
    if len(parts) == 1:
        try:
            value = convert(parts[0])
        except (ValueError, argparse.ArgumentTypeError) as exc:
            raise argparse.ArgumentTypeError(f"invalid range {text!r}: {exc}") from None
        return value, value, 1
    if len(parts) not in (2, 3):
        raise argparse.ArgumentTypeError(
            f"invalid range {text!r}: use VALUE, START:STOP or START:STOP:COUNT"
        )
    try:
        start, stop = convert(parts[0]), convert(parts[1])
        count = int(parts[2]) if len(parts) == 3 else None
    except (ValueError, argparse.ArgumentTypeError) as exc:
        raise argparse.ArgumentTypeError(f"invalid range {text!r}: {exc}") from None
    if count is not None and count < 1:
        raise argparse.ArgumentTypeError(f"invalid range {text!r}: COUNT must be >= 1")
    if count == 1 and start != stop:  # one point: STOP would be ignored
        raise argparse.ArgumentTypeError(
            f"invalid range {text!r}: COUNT 1 is one point, START, so STOP must equal START")
    if count != 1 and start == stop:  # the one value repeated (a sweep refuses repeats)
        raise argparse.ArgumentTypeError(
            f"invalid range {text!r}: START = STOP is one value; write START:START:1 for one "
            "point, or give STOP != START")
    return start, stop, count


def _int_at_least(text: str, lowest: int, what: str) -> int:
    """``int(text)`` if it is at least ``lowest``, else an argparse error naming ``what``."""
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected {what}, got {text!r}") from None
    if v < lowest:
        raise argparse.ArgumentTypeError(f"expected {what}, got {text!r}")
    return v


def positive_int(text: str) -> int:
    return _int_at_least(text, 1, "a positive integer")


def nonnegative_int(text: str) -> int:
    return _int_at_least(text, 0, "an integer >= 0")


class Explicit(argparse.Action):
    """Store the value and record the option's ``dest`` in ``namespace.explicit``: options given
    on the command line are told from defaults, so that none is silently ignored."""

    def __call__(
        self, parser: argparse.ArgumentParser, namespace: argparse.Namespace,
        values: Any, option_string: str | None = None,
    ) -> None:
        setattr(namespace, self.dest, values)
        namespace.explicit = {*vars(namespace).get("explicit", ()), self.dest}


def explicit_options(args: argparse.Namespace) -> set[str]:
    """``dest`` names of the :class:`Explicit` options given on the command line."""
    return set(vars(args).get("explicit", ()))


#: Compass-gait options: ``dest``, the :class:`~heelstrike.models.compass.CompassGait` field it
#: sets, and its help text. The defaults are the model's own (read from the dataclass).
_COMPASS_OPTIONS = (
    ("radius", "foot_radius", "foot radius R (m), 0 <= R <= l"),
    ("hip_mass", "hip_mass", "hip mass mH (kg)"),
    ("leg_mass", "leg_mass", "mass of each leg m (kg)"),
    ("leg_length", "leg_length", "leg length l (m)"),
    ("com_from_hip", "leg_com_from_hip", "hip to leg centre of mass b (m)"),
    ("leg_inertia", "leg_inertia", "leg inertia about its COM (kg m^2)"),
    ("gravity", "gravity", "gravity g (m/s^2)"),
)


def compass_params() -> dict[str, str]:
    """Compass-gait options (``dest``) and the description parameter each one sets with
    ``--model`` (:data:`~heelstrike.models.compass.DESCRIBED_PARAMETERS`: the names of the
    shipped compass and torso walkers)."""
    from heelstrike.models.compass import DESCRIBED_PARAMETERS

    return {dest: DESCRIBED_PARAMETERS[field] for dest, field, _ in _COMPASS_OPTIONS}


def add_walker_options(p: argparse.ArgumentParser) -> None:
    """Options for every parameter of the paper's compass gait (SI units, the model's defaults)."""
    from dataclasses import fields

    from heelstrike.models.compass import CompassGait

    defaults = {f.name: f.default for f in fields(CompassGait)}
    g = p.add_argument_group(
        "walker parameters (paper defaults; with --model they set the model's R, mH, m, l, b, "
        "I, g)"
    )
    for dest, field, text in _COMPASS_OPTIONS:
        g.add_argument("--" + dest.replace("_", "-"), type=float, default=defaults[field],
                       action=Explicit, help=f"{text}; default {defaults[field]:g}")


def walker_from_args(args: argparse.Namespace) -> Any:
    from heelstrike.models.compass import CompassGait, WalkerParameterError

    if vars(args).get("param"):
        raise CliError("--param needs --model (the compass gait takes --radius, --hip-mass, ...)")
    try:
        return CompassGait(**{field: getattr(args, dest) for dest, field, _ in _COMPASS_OPTIONS})
    except WalkerParameterError as exc:
        # the model names its fields; say which options set the ones the failed rule names
        rule = str(exc).split("; got", 1)[0]
        named = [f"--{dest.replace('_', '-')} sets {field}" for dest, field, _ in _COMPASS_OPTIONS
                 if re.search(rf"\b{field}\b", rule)]
        raise CliError(f"{exc} ({', '.join(named)})" if named else str(exc)) from None


def add_model_options(p: argparse.ArgumentParser, *, required: bool = False) -> None:
    """``--model`` (a TOML description or shipped name; ``required`` for a command without
    compass shorthand) and repeatable ``--param NAME=VALUE``."""
    g = p.add_argument_group("described walker" if required
                             else "described walker (overrides the compass-gait options)")
    g.add_argument("--model", default=None, metavar="FILE_OR_NAME", required=required,
                   help="walker description: a .toml file or a shipped name "
                   "(compass, kneed, torso, wheel)")
    g.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                   help="set a description parameter (SI units), repeatable, e.g. R=0.2")


def add_backend_option(
    p: argparse.ArgumentParser, help: str, default: str | None = None
) -> None:
    """``--backend compiled|scipy`` with the command's help (what runs on each backend)."""
    from heelstrike.models.base import BACKEND_NAMES

    p.add_argument("--backend", choices=sorted(BACKEND_NAMES), default=default, help=help,
                   action=Explicit)


def default_backend_for(args: argparse.Namespace, walker: Any) -> None:
    """A command's default ``--backend`` that ``walker`` does not run on becomes the one it runs
    on (:attr:`~heelstrike.models.base.PlanarWalker.backends`: a walker without a compiled
    kernel, e.g. one declaring its own step schedule, runs on the scipy reference; every walker
    file, its legs alike or not, runs on both); a ``--backend`` given on the command line is
    kept (and refused later if unsupported, with the reason)."""
    backend = vars(args).get("backend")
    if backend is None or "backend" in explicit_options(args) or walker.supports(backend):
        return
    args.backend = walker.backends[0]


def _note_borrowed_name(model: str, description: Any) -> None:
    """Warn (:class:`ShippedNameWarning`, a note of the command) when a walker file carries a
    shipped walker's ``name`` but describes a different walker (a copy with changed values):
    outputs and figures are labelled by that name, so they would read as the shipped walker's
    (QA sweep 11)."""
    from heelstrike.models.builder import shipped_walkers, walker_description

    if model in shipped_walkers() or description.name not in shipped_walkers():
        return
    if description != walker_description(description.name):
        warnings.warn(ShippedNameWarning(
            f"{model} is named {description.name!r} like the shipped walker but differs from "
            f"it; outputs are labelled {description.name!r}: give the file its own "
            'name = "..." to tell them apart'), stacklevel=2)


def model_from_args(args: argparse.Namespace) -> Any:
    from heelstrike.dynamics.phased import PhasedWalker
    from heelstrike.models.builder import walker_description

    params: dict[str, float] = {}
    for item in args.param:
        name, sep, value = item.partition("=")
        if not sep or not name.strip():
            raise CliError(f"invalid --param {item!r}: use NAME=VALUE, e.g. R=0.2")
        if name.strip() in params:
            raise CliError(f"--param {name.strip()} is given twice: give it once")
        try:
            params[name.strip()] = float(value)
        except ValueError:
            raise CliError(f"invalid --param {item!r}: {value.strip()!r} is not a number "
                           "(NAME=VALUE in SI units, e.g. R=0.2)") from None
    model = str(args.model)
    from heelstrike.models.builder import shipped_walkers

    if model in shipped_walkers():  # the shipped walker, whatever the working directory holds
        if os.path.isfile(model):
            warnings.warn(ShippedNameWarning(
                f"--model {model} is the shipped walker; the file {model!r} in the working "
                f"directory is not read (give it as ./{model} to use it)"), stacklevel=2)
    from heelstrike.models.description import ModelDescriptionError

    try:
        description = walker_description(model)
    except OSError as exc:
        raise CliError(f"cannot read model {model!r}: {exc.strerror or exc}") from exc
    except ModelDescriptionError as exc:  # the field's path: say in which file
        name = os.path.basename(model)
        text = str(exc)
        raise CliError(text if text.startswith((name, model)) else f"{model}: {text}") from exc
    _note_borrowed_name(model, description)
    if description.unused_params:
        idle = ", ".join(sorted(description.unused_params))
        warnings.warn(UnusedParameterWarning(
            f"model {description.name!r} declares parameter(s) {idle} that no field uses: "
            "their values change nothing"), stacklevel=2)
    names = sorted(name for name, _ in description.params)
    unknown = sorted(set(params) - set(names))
    if unknown:  # before the derivation, which takes seconds on a cold cache (QA sweep 9)
        raise CliError(f"--param {unknown[0]}: model {description.name!r} has no parameter "
                       f"{unknown[0]!r} (its parameters: {', '.join(names)})")
    walker = PhasedWalker(description)
    default_backend_for(args, walker)
    known = walker.parameters
    by_option = compass_params()
    for dest in sorted(explicit_options(args) & set(by_option)):
        name, option = by_option[dest], "--" + dest.replace("_", "-")
        if name not in known:
            raise CliError(
                f"{option} sets the compass parameter {name!r}, which model "
                f"{walker.description.name!r} does not have (its parameters: "
                f"{', '.join(sorted(known))}); use --param NAME=VALUE"
            )
        if name in params:
            raise CliError(f"{option} and --param {name}=... both set {name!r}: give it once")
        params[name] = float(getattr(args, dest))
    if not params:
        return walker
    from heelstrike.models.description import ModelDescriptionError, parameter_units

    try:
        return walker.replace(**params)
    except ModelDescriptionError as exc:  # said in the file's terms: say which values (QA 11)
        units = parameter_units(walker.description)
        given = ", ".join(f"{k}={v:g}" + (f" {units[k]}" if units.get(k, "1") != "1" else "")
                          for k, v in params.items())
        raise CliError(f"model {walker.description.name!r} with {given}: {exc}") from exc


def parse_floats(text: str, option: str, n: int | None = None) -> list[float]:
    try:
        vals = [float(v) for v in text.split(",")]
    except ValueError:
        raise CliError(f"invalid {option} {text!r}: use comma-separated numbers") from None
    if not all(math.isfinite(v) for v in vals):
        raise CliError(f"invalid {option} {text!r}: the numbers must be finite")
    if n is not None and len(vals) != n:
        raise CliError(f"invalid {option} {text!r}: expected {n} comma-separated numbers")
    return vals


#: Output folders claimed by this process (their real path -> the claim), released by
#: :func:`release_claims` when the command ends.
_CLAIMS: dict[str, Any] = {}


def writable_dir(path: str | os.PathLike[str], option: str = "--out") -> Any:
    """Create the directory ``path`` if needed, check that a file can be written in it and
    claim it for this run (:func:`heelstrike.io.claim_directory`: a second run on the same
    folder is refused), before any computing; returns it as a :class:`~pathlib.Path`."""
    import tempfile
    from pathlib import Path

    from heelstrike.io import DirectoryInUseError, claim_directory

    if not str(path).strip():
        raise CliError(f"{option} is empty: give a directory, e.g. {option} results")
    out = Path(path)
    if out.exists() and not out.is_dir():  # mkdir's own answer would be "File exists"
        raise CliError(f"cannot write to {option} {str(path)!r}: it exists and is not a "
                       "directory")
    try:
        out.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=out):
            pass
        real = os.path.realpath(out)
        if real not in _CLAIMS:
            _CLAIMS[real] = claim_directory(real)
    except DirectoryInUseError as exc:
        raise CliError(f"{option}: {exc.strerror}") from None
    except OSError as exc:
        raise CliError(f"cannot write to {option} {str(path)!r}: {exc.strerror or exc}") from None
    return out


def release_claims() -> None:
    """Release the output folders this process claimed (:func:`writable_dir`)."""
    while _CLAIMS:
        _, claim = _CLAIMS.popitem()
        claim.release()


def parse_guess(text: str | None) -> list[float] | None:
    if text is None:
        return None
    try:
        vals = [float(v) for v in text.split(",")]
    except ValueError:
        raise CliError(f"invalid --guess {text!r}: use Q3,Q3DOT,Q4DOT (rad, rad/s)") from None
    if len(vals) != 3:
        raise CliError(f"invalid --guess {text!r}: expected 3 comma-separated numbers")
    return vals


def nonempty_path(text: str) -> str:
    """A path option's value, refused when empty (``--store ''``: no folder named)."""
    if not str(text).strip():
        raise argparse.ArgumentTypeError("must name a directory, got an empty string")
    return str(text)


def add_store_option(p: argparse.ArgumentParser) -> None:
    p.add_argument("--store", metavar="DIR", default=None, type=nonempty_path,
                   help="keep every finished chunk in this Zarr directory as it is computed; "
                   "after an interruption (Ctrl-C) the same command resumes from it. The "
                   "finished figure and data are still written to --out (as without --store)")


@contextlib.contextmanager
def warnings_as_notes(*categories: type[Warning]) -> Iterator[None]:
    """Within the block, warnings of ``categories`` become ``heelstrike: note: ...`` lines on
    stderr (news for the user, not a Python warning with a source line); others as before.

    The notes are printed when the block ends normally: a command that fails prints its one
    error line only. Each command says its notes again (``main`` called twice in one process,
    as tests and scripts do: Python's default filter would show a repeated warning once)."""
    show = warnings.showwarning
    notes: dict[str, int] = {}  # each note once, with its count

    def note(message: Any, category: Any, filename: Any = "", *args: Any, **kwargs: Any) -> None:
        if isinstance(category, type) and issubclass(category, categories):
            text = str(message).removeprefix("heelstrike: ")
            if issubclass(category, RuntimeWarning):  # numpy's, from generated or own code
                text = f"numerical warning in {_warning_place(str(filename))}: {text}"
            line = f"heelstrike: note: {text}"
            notes[line] = notes.get(line, 0) + 1
        else:
            show(message, category, filename, *args, **kwargs)

    with warnings.catch_warnings():
        for category in categories:
            warnings.simplefilter("always", category)
        warnings.showwarning = note
        try:
            yield
        finally:
            warnings.showwarning = show
    for line, count in notes.items():  # reached only when the block ended normally
        print(line + (f" ({count} times)" if count > 1 else ""), file=sys.stderr)


def _warning_place(filename: str) -> str:
    """Where a warning arose, said in one phrase: generated model code (the cache), a
    heelstrike module, or the file's name."""
    from pathlib import Path

    from heelstrike.models._generated import cache_dir

    path = Path(filename)
    try:
        path.resolve().relative_to(cache_dir().resolve())
        return "the walker's generated model code"
    except (ValueError, OSError):
        pass
    if "heelstrike" in path.parts:
        return f"heelstrike ({path.name})"
    return path.name or "an unknown place"


class ShippedNameWarning(UserWarning):
    """A walker file carries a shipped walker's ``name`` but describes another walker."""


class UnusedParameterWarning(UserWarning):
    """A walker file declares parameters that no field uses (their values change nothing)."""


class DeprecatedOptionWarning(UserWarning):
    """An option was given by an old name that still works (:class:`DeprecatedAlias`)."""


class DeprecatedAlias(argparse.Action):
    """An old option name kept working: it stores its value where the new option does
    (``dest``) and records a one-line note naming the new option (``new``), which ``main``
    says as a :class:`DeprecatedOptionWarning` when the command succeeds."""

    def __init__(self, option_strings: Sequence[str], dest: str, *, new: str,
                 **kwargs: Any) -> None:
        self.new = new
        super().__init__(option_strings, dest, **kwargs)

    def __call__(
        self, parser: argparse.ArgumentParser, namespace: argparse.Namespace,
        values: Any, option_string: str | None = None,
    ) -> None:
        setattr(namespace, self.dest, values)
        namespace.deprecated = [*vars(namespace).get("deprecated", ()),
                                f"{option_string} is deprecated: it is now {self.new} "
                                "(the same values)"]


def run_with_store(store: str | None, compute: Callable[[], Any], out: str | None = None) -> Any:
    """Run ``compute()``; with a store, report its progress on stderr and map store errors.
    ``out``: the command's ``--out`` directory, which the store must not be."""
    if store is None:
        return compute()
    from pathlib import Path


    if out is not None and Path(store).resolve() == Path(out).resolve():
        raise CliError(f"--store and --out are both {store!r}: the store keeps the sweep's "
                       "chunks and --out its figures and data; give the store a directory of "
                       "its own")
    import logging

    from heelstrike.analysis.sweep import (
        SweepError,
        SweepStoreLockedError,
        SweepStoreMismatchError,
        SweepStoreRepairWarning,
    )

    logger = logging.getLogger("heelstrike.analysis.sweep")
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(logging.Formatter("heelstrike: %(message)s"))
    level = logger.level
    logger.addHandler(handler)
    logger.setLevel(logging.INFO)
    with warnings_as_notes(SweepStoreRepairWarning):  # a repaired store is news
        try:
            return compute()
        except SweepStoreMismatchError as exc:
            # the sweep's internal names, said in the command's terms
            def plain(key: str) -> str:
                if key == "function.bound":
                    return "the command's options (walker, slope, steps, tol, ...)"
                head = key.split(".", 1)[0]
                return {"function": "the code that computes it",
                        "grid": "the grid (--grid, ranges)",
                        "chunks": "the chunking"}.get(head, key)

            what = sorted({plain(d) for d in exc.differs})
            raise CliError(
                f"--store {store!r} holds results of a different computation (differs in: "
                f"{'; '.join(what)}; internally {', '.join(exc.differs)}); remove it or choose "
                "another directory"
            ) from exc
        except SweepStoreLockedError as exc:
            raise CliError(
                f"--store {store!r} is in use by another heelstrike run; wait for it to finish "
                "or choose another directory"
            ) from exc
        except SweepError as exc:
            raise CliError(str(exc)) from exc
        except KeyboardInterrupt:
            print(f"heelstrike: finished chunks are kept in {store!r}; run the same command "
                  "again to resume", file=sys.stderr)
            raise
        finally:
            logger.removeHandler(handler)
            logger.setLevel(level)


# -- basin of attraction and stable-gait map (issue 6) ------------------------------------------
def parse_grid(text: str) -> tuple[int, int]:
    parts = str(text).lower().split("x")
    try:
        if len(parts) != 2:
            raise ValueError
        n1, n2 = int(parts[0]), int(parts[1])
    except ValueError:
        raise argparse.ArgumentTypeError(f"invalid grid {text!r}: use e.g. 400x400") from None
    if n1 < 1 or n2 < 1:
        raise argparse.ArgumentTypeError(f"invalid grid {text!r}: sizes must be >= 1")
    return n1, n2


def parse_sweep(text: str) -> tuple[str, float, float, int]:
    name, sep, rest = text.partition(":")
    if not sep or not name:
        raise argparse.ArgumentTypeError(
            f"invalid sweep {text!r}: use NAME:START:STOP:COUNT (NAME a parameter or 'angle')"
        )
    conv = parse_angle if name == "angle" else float
    start, stop, count = parse_range(rest, conv)
    if count is None:
        raise argparse.ArgumentTypeError(f"invalid sweep {text!r}: COUNT is required")
    return name, start, stop, count


ACTUATIONS = ("pushoff", "hip-energy", "hip-pd")


def add_actuation_options(p: argparse.ArgumentParser) -> None:
    # defaults (None) come from heelstrike.dynamics.actuation.default_gains, which scales the
    # DEFAULT_* constants (they explain them) to the walker
    g = p.add_argument_group(
        "actuation (defaults for the paper's walker, m_total g l = 196.2 N m with m_total = "
        "mH + 2 m = 20 kg, sqrt(l/g) = 0.319 s; another walker's are the same dimensionless "
        "gains: torques scaled by its m_total g l, "
        "times by its sqrt(l/g); heelstrike.dynamics.actuation.default_gains)")
    g.add_argument("--gain", type=float, default=None,
                   help="energy-tracking gain k of hip-energy (s/rad, default 3)")
    g.add_argument("--kp", type=float, default=None,
                   help="hip-pd stiffness (N m/rad, default 50)")
    g.add_argument("--kd", type=float, default=None,
                   help="hip-pd damping (N m s/rad, default 5)")
    g.add_argument("--max-torque", type=float, default=None,
                   help="hip torque limit (N m, default 50)")


def actuation_options(args: argparse.Namespace) -> dict[str, float]:
    """The actuation options given on the command line (the library supplies the rest)."""
    opts = {k: float(getattr(args, k)) for k in ("gain", "kp", "kd", "max_torque")
            if getattr(args, k) is not None}
    if "max_torque" in opts and not opts["max_torque"] > 0:
        raise CliError("--max-torque must be > 0 (N m)")
    if "gain" in opts and not opts["gain"] > 0:
        raise CliError("--gain must be > 0 (s/rad)")
    for k in ("kp", "kd"):
        if k in opts and not (math.isfinite(opts[k]) and opts[k] >= 0):
            raise CliError(f"--{k} must be finite and >= 0, got {opts[k]:g}")
    return opts


#: The hip laws' options each actuation uses (the others would be silently ignored).
_GAINS_USED = {"pushoff": (), "hip-energy": ("gain", "max_torque"),
               "hip-pd": ("kp", "kd", "max_torque")}


def refuse_unused_gains(args: argparse.Namespace, actuations: Sequence[str]) -> None:
    """A one-line error for a gain option none of the actuations uses (e.g. ``--kp`` with
    ``--actuation hip-energy``, or any gain with the push-off alone)."""
    used = {k for a in actuations for k in _GAINS_USED.get(a, ())}
    unused = [f"--{k.replace('_', '-')}" for k in ("gain", "kp", "kd", "max_torque")
              if getattr(args, k, None) is not None and k not in used]
    if unused:
        raise CliError(
            f"{', '.join(unused)} not used by --actuation {', '.join(actuations)} (--gain "
            "sets hip-energy, --kp and --kd set hip-pd, --max-torque both; the push-off has "
            "no gains, and a walker file's posture law declares its own)")


def family_from_args(args: argparse.Namespace) -> Any:
    from heelstrike.analysis.powered import actuation_family

    return actuation_family(args.actuation, **actuation_options(args))


def linspace_grid(r: tuple[float, float, int | None], default_count: int) -> list[float]:
    import numpy as np

    start, stop, count = r
    return [float(v) for v in np.linspace(start, stop, count or default_count)]
