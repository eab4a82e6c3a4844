"""Rendering shared by the commands: one JSON object on stdout, one-line errors on stderr."""

from __future__ import annotations

import json
import math
import os
import sys
from collections.abc import Iterable
from typing import Any

from heelstrike.cli._common import CliError


def nonfinite_paths(obj: Any, path: str = "") -> list[str]:
    """Paths of the non-finite numbers in a JSON-ready object (``T_c``, ``qdot_plus[1]``)."""
    if isinstance(obj, float):
        return [] if math.isfinite(obj) else [path or "value"]
    if isinstance(obj, dict):
        return [p for k, v in obj.items() for p in nonfinite_paths(v, f"{path}.{k}" if path else k)]
    if isinstance(obj, list | tuple):
        return [p for i, v in enumerate(obj) for p in nonfinite_paths(v, f"{path}[{i}]")]
    return []


def require_finite(obj: Any) -> None:
    """Refuse a result holding inf or NaN (overflow or a degenerate input)."""
    bad = nonfinite_paths(obj)
    if bad:
        shown = ", ".join(bad[:4]) + (f" and {len(bad) - 4} more" if len(bad) > 4 else "")
        raise CliError(f"the result is not finite ({shown}): the input overflows or is "
                       "degenerate; use smaller velocities or other parameters")


def _plain_zeros(obj: Any) -> Any:
    """``obj`` with every ``-0.0`` written ``0.0`` (a signed zero says nothing physical)."""
    if isinstance(obj, float):
        return 0.0 if obj == 0.0 else obj
    if isinstance(obj, dict):
        return {k: _plain_zeros(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_plain_zeros(v) for v in obj]
    return obj


def json_text(obj: Any) -> str:
    """The JSON text of a result: finite (:func:`require_finite`), no ``-0.0``."""
    require_finite(obj)
    return json.dumps(_plain_zeros(obj), allow_nan=False)


def print_json(obj: Any, units: dict[str, Any] | None = None) -> None:
    """Print one whole JSON object on stdout, or nothing (the text is built before writing).

    A ``units`` map for the object's keys is added: ``units`` if given, else
    :func:`heelstrike._units.json_units`.
    """
    from heelstrike._units import json_units

    if isinstance(obj, dict) and "units" not in obj:
        obj = {**obj, "units": json_units(obj) if units is None else units}
    text = json_text(obj) + "\n"
    sys.stdout.write(text)
    sys.stdout.flush()


def print_paths(paths: Iterable[Any]) -> None:
    """Print the paths written, one per line."""
    for path in paths:
        print(path)


def fixed_point_text(fixed_point: dict[str, float]) -> str:
    """``'q3 = -0.2 rad, q3_dot = ... rad/s'``: a fixed point's section coordinates (angles,
    then rates) to six significant digits (a slow gait's ``q4_dot`` of 3e-6 rad/s read
    ``-0.000003``)."""
    from heelstrike.models.base import section_unit

    return ", ".join(f"{k} = {v:.6g} {section_unit(k)}" for k, v in fixed_point.items())


def multipliers_text(multipliers: Iterable[complex]) -> str:
    """The Floquet multipliers' moduli, ``'0.5200, 0.5200, 0.1800'``; one near 1 with the
    digits that tell it from 1 (``0.9999971``: 4 decimals read ``1.0000``, which says neither
    stable nor unstable)."""

    def text(m: complex) -> str:
        gap = abs(abs(m) - 1.0)
        digits = 4 if gap >= 5e-5 or gap == 0 else min(12, math.ceil(-math.log10(gap)) + 1)
        return f"{abs(m):.{digits}f}"

    return ", ".join(text(m) for m in multipliers)


def energy_text(value: float, width: int = 10) -> str:
    """An energy per step (or per metre) with 5 decimals, or in exponent form below 1e-3
    (QA sweep 13: on a slope of 1e-6 rad the loss and the energy released both printed as
    0.00000 J, so that the books could not be read)."""
    if value == 0.0 or 1e-3 <= abs(value) < 1e7:
        return f"{value:{width}.5f}"
    return f"{value:{width}.4e}"


def print_step_lines(gait: Any) -> None:
    """The period (s), step length (m) and speed (m/s) lines of a gait report."""
    print(f"  period          {gait.period:10.5f} s")
    print(f"  step length     {gait.step_length:10.5f} m")
    print(f"  speed           {gait.speed:10.5f} m/s")


def print_impact_angle_line(gait: Any) -> None:
    """The impact angle line of a gait report: the stance angle at heel strike (rad, deg)."""
    print(f"  impact angle    {gait.impact_angle:10.5f} rad "
          f"({math.degrees(gait.impact_angle):.3f} deg)")


def print_stability_lines(gait: Any) -> None:
    """The ``|multipliers|`` and ``stable`` lines of a gait report; a largest ``|m|`` within
    :data:`~heelstrike.analysis.limit_cycle.MULTIPLIER_ACCURACY` of 1 is called neutral."""
    from heelstrike.analysis.limit_cycle import MULTIPLIER_ACCURACY

    print(f"  |multipliers|   {multipliers_text(gait.multipliers)}")
    largest = max((abs(m) for m in gait.multipliers), default=0.0)
    accuracy = format(MULTIPLIER_ACCURACY, ".0e").replace("e-0", "e-")
    within = (f"the largest |multiplier| is within {accuracy} of 1, the multipliers' accuracy"
              if abs(largest - 1.0) < MULTIPLIER_ACCURACY else "")
    if gait.stability_undecided:  # McGeer's wheel: a neutral family of gaits at one target
        print("  stable          undecided" + (f": {within}" if within else "")
              + " (a neutral family of gaits)")
        return
    verdict = "yes" if gait.stable else "no"
    if within:
        verdict += f", barely: {within} (neutral to that accuracy)"
    print(f"  stable          {verdict}")


def one_line(exc: BaseException) -> str:
    text = " ".join(str(exc).split())
    return text or type(exc).__name__


def printable(text: str) -> str:
    """``text`` with every control character but newline and tab written as an escape
    (``\\x1b``): names from robot files and paths must not drive the terminal."""
    return "".join(ch if ch in "\n\t" or not (ord(ch) < 32 or 127 <= ord(ch) < 160)
                   else f"\\x{ord(ch):02x}" for ch in text)


def fail(message: str) -> int:
    """Print the one-line error (after the traceback when ``HEELSTRIKE_DEBUG=1``), control
    characters escaped (a path or a name in it must not drive the terminal); status 2."""
    if os.environ.get("HEELSTRIKE_DEBUG") == "1":
        import traceback

        traceback.print_exc()
    print(f"heelstrike: error: {printable(message)}", file=sys.stderr)
    return 2
