"""Commands as users run them: wall time of whole processes (issue 9's targets).

Each command runs as a new process (interpreter start, imports, disk caches warm: one untimed
run of every command first), ``repeats`` times, interleaved round by round so that load changes
hit every command alike; the table gives the median wall time and the ratio to the median of
``heelstrike impact --json`` measured in the same rounds. Besides the ``heelstrike`` commands
the rounds time the floors under them: an empty interpreter, ``import numba``, and a process
that calls one trivial ``@njit(cache=True)`` function from numba's warm disk cache (what any
compiled command pays at least). Targets (issue 9):

- ``gait --radius 0.3 --slope 3deg`` within 3x of ``impact --json``;
- ``gait --model kneed``: compiled backend >= 10x faster than ``--backend scipy``, same answer
  to 1e-8 (checked here on the JSON fixed points);
- ``powered`` for each actuation at R = 0 and 0.3, 0.5 m/s: under 10 s each (every actuation
  runs compiled by default, on the kernel generated from ``compass.toml``; the rows with
  ``--backend scipy`` are the reference).

Every child process runs as a default Python does: ``PYTHONDONTWRITEBYTECODE`` is removed from
its environment, so imports use the bytecode caches that an installed package has (this
project's machines set it, and then every process compiles every module it imports from
source: 0.05-0.15 s more per command, e.g. ``gait --model kneed`` 0.34 s instead of 0.28 s).

The compiled gait commands run the kernels' ahead-of-time modules (``heelstrike.dynamics._aot``:
no numba in the process); the rows marked "JIT" run the same commands with ``HEELSTRIKE_AOT=0``,
i.e. through numba's JIT and its disk cache, for comparison.

Separately (one run each, not in the medians): the compiled gait commands on a first run, with
``NUMBA_CACHE_DIR`` set to a new empty directory and ``HEELSTRIKE_CACHE_DIR`` to a new one
holding a copy of the generated walker code but no ahead-of-time modules (so the first run
builds them; the walker's generated source is not derived again, ``bench_model_gait.py`` times
that), and the same with ``HEELSTRIKE_AOT=0`` (numba compiling every kernel).

Run ``python benchmarks/bench_cli.py`` (``--quick``: 1 timed round, no cold runs;
``--json PATH``).
"""

from __future__ import annotations

import itertools
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from _common import machine, run_main

#: A trivial cached numba function: the per-process floor of any compiled command.
FLOOR_SOURCE = """\
from numba import njit


@njit(cache=True)
def plus_one(x):
    return x + 1.0


plus_one(1.0)
"""

IMPACT = ["impact", "--radius", "0.25", "--angle", "20deg", "--json"]
GAIT = ["gait", "--radius", "0.3", "--slope", "3deg", "--json"]
KNEED = ["gait", "--model", "kneed", "--slope", "0.0504rad", "--json"]
#: name -> (kind, argv): kind "heelstrike" runs the command ("heelstrike-jit" with
#: ``HEELSTRIKE_AOT=0``), "python" an interpreter.
COMMANDS: dict[str, tuple[str, list[str]]] = {
    "python -c pass": ("python", ["-c", "pass"]),
    "python -c 'import numba'": ("python", ["-c", "import numba"]),
    "trivial cached @njit function (numba floor)": ("floor", []),
    "impact --json": ("heelstrike", IMPACT),
    "gait --radius 0.3 --slope 3deg": ("heelstrike", GAIT),
    "gait --radius 0.3 --slope 3deg (JIT)": ("heelstrike-jit", GAIT),
    "gait --radius 0.3 --slope 3deg --backend scipy": (
        "heelstrike", [*GAIT, "--backend", "scipy"],
    ),
    "gait --model kneed (compiled)": ("heelstrike", KNEED),
    "gait --model kneed (compiled, JIT)": ("heelstrike-jit", KNEED),
    "gait --model kneed --backend scipy": ("heelstrike", [*KNEED, "--backend", "scipy"]),
    **{
        f"powered --radius {R} --speed 0.5 --actuation {act}": (
            "heelstrike",
            ["powered", "--radius", R, "--speed", "0.5", "--actuation", act, "--json"],
        )
        for act in ("pushoff", "hip-energy", "hip-pd")
        for R in ("0", "0.3")
    },
    **{
        f"powered --radius {R} --speed 0.5 --actuation {act} --backend scipy": (
            "heelstrike",
            ["powered", "--radius", R, "--speed", "0.5", "--actuation", act, "--json",
             "--backend", "scipy"],
        )
        for act in ("pushoff", "hip-energy", "hip-pd")
        for R in ("0", "0.3")
    },
}  # fmt: skip
#: Commands also run once with an empty numba cache.
COLD = ("gait --radius 0.3 --slope 3deg", "gait --model kneed (compiled)",
        "powered --radius 0 --speed 0.5 --actuation pushoff")


def _heelstrike() -> list[str]:
    exe = shutil.which("heelstrike", path=str(Path(sys.executable).parent)) or shutil.which(
        "heelstrike"
    )
    return [exe] if exe else [sys.executable, "-m", "heelstrike"]


def _argv(kind: str, args: list[str], floor: Path) -> list[str]:
    if kind.startswith("heelstrike"):
        return [*_heelstrike(), *args]
    if kind == "floor":
        return [sys.executable, str(floor)]
    return [sys.executable, *args]


def _env(kind: str) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items()
           if k not in ("HEELSTRIKE_AOT", "PYTHONDONTWRITEBYTECODE")}
    if kind == "heelstrike-jit":
        env["HEELSTRIKE_AOT"] = "0"
    return env


def _generated_code_only(folder: Path) -> str:
    """A new heelstrike cache in ``folder`` with a copy of the generated walker code (sympy's
    output, not compiled code) from the current one; returns its path."""
    from heelstrike.models._generated import cache_dir

    new = folder / "heelstrike-cache"
    new.mkdir(mode=0o700)
    for sub in ("models", "numba"):
        src = cache_dir() / sub
        if src.is_dir():
            shutil.copytree(src, new / sub, ignore=shutil.ignore_patterns("__pycache__"))
    return str(new)


def _run(argv: list[str], env: dict[str, str] | None = None) -> tuple[float, Any, int, bool]:
    """Wall time, parsed JSON output, exit status and whether a kernel was compiled."""
    t0 = time.perf_counter()
    proc = subprocess.run(argv, capture_output=True, text=True, check=False, env=env)
    wall = time.perf_counter() - t0
    try:
        out = json.loads(proc.stdout) if proc.returncode == 0 and proc.stdout else None
    except json.JSONDecodeError:
        out = None
    return wall, out, proc.returncode, "compiling" in proc.stderr


def _max_diff(a: dict[str, Any] | None, b: dict[str, Any] | None) -> float | None:
    if not a or not b:
        return None
    fa, fb = a["fixed_point"], b["fixed_point"]
    return max(abs(float(fa[k]) - float(fb[k])) for k in fa)


def run(quick: bool = False) -> dict[str, Any]:
    repeats = 1 if quick else 5
    with tempfile.TemporaryDirectory(prefix="heelstrike-bench-") as tmp:
        floor = Path(tmp) / "numba_floor.py"
        floor.write_text(FLOOR_SOURCE)
        argvs = {name: _argv(kind, args, floor) for name, (kind, args) in COMMANDS.items()}
        envs = {name: _env(kind) for name, (kind, _) in COMMANDS.items()}
        for name, argv in argvs.items():  # warm the disk caches (generated code, numba, aot)
            _run(argv, envs[name])
        times: dict[str, list[float]] = {k: [] for k in COMMANDS}
        outputs: dict[str, Any] = {}
        codes: dict[str, int] = {}
        compiled_in_rounds: set[str] = set()
        for _ in range(repeats):
            for name, argv in argvs.items():
                wall, out, code, compiled = _run(argv, envs[name])
                times[name].append(wall)
                outputs[name], codes[name] = out, code
                if compiled:
                    compiled_in_rounds.add(name)
        cold: dict[str, tuple[float, int]] = {}
        if not quick:
            for name in COLD:
                for label, jit in (("ahead-of-time build", False), ("numba JIT", True)):
                    with tempfile.TemporaryDirectory(prefix="heelstrike-cold-") as cache:
                        env = {**_env("heelstrike-jit" if jit else "heelstrike"),
                               "NUMBA_CACHE_DIR": str(Path(cache) / "numba-cache"),
                               "HEELSTRIKE_CACHE_DIR": _generated_code_only(Path(cache))}
                        wall, _, code, _ = _run(argvs[name], env)
                        cold[f"{name}, {label}"] = (wall, code)
    med = {name: statistics.median(t) for name, t in times.items()}
    base = med["impact --json"]
    rows = [
        {
            "command": name,
            "median_s": med[name],
            "min_s": min(times[name]),
            "max_s": max(times[name]),
            "ratio_to_impact": med[name] / base,
            "exit": codes[name],
            "stable": (outputs[name] or {}).get("stable")
            if isinstance(outputs[name], dict) else None,
        }
        for name in COMMANDS
    ]
    floor_s = med["trivial cached @njit function (numba floor)"]
    gait_s = med["gait --radius 0.3 --slope 3deg"]
    jit_s = med["gait --radius 0.3 --slope 3deg (JIT)"]
    notes = [
        f"{repeats} interleaved rounds after one warm-up run of each command (warm disk caches)",
        f"gait --radius 0.3 --slope 3deg / impact --json: {gait_s / base:.2f}x (target <= 3x: "
        f"{'met' if gait_s <= 3 * base else 'not met'}) on the ahead-of-time kernels; through "
        f"numba's JIT {jit_s / base:.2f}x, where the numba floor alone is {floor_s / base:.2f}x",
        f"gait --radius 0.3 --slope 3deg, scipy / compiled backend: "
        f"{med['gait --radius 0.3 --slope 3deg --backend scipy'] / gait_s:.2f}x",
    ]
    d = _max_diff(outputs.get("gait --radius 0.3 --slope 3deg"),
                  outputs.get("gait --radius 0.3 --slope 3deg --backend scipy"))
    if d is not None:
        notes.append(f"R = 0.3 fixed point, compiled vs scipy backend: max |difference| {d:.2g}")
    t_c = med["gait --model kneed (compiled)"]
    t_j = med["gait --model kneed (compiled, JIT)"]
    t_s = med["gait --model kneed --backend scipy"]
    notes.append(
        f"gait --model kneed, scipy / compiled: {t_s / t_c:.2f}x (target >= 10x: "
        f"{'met' if t_s >= 10 * t_c else 'not met'}) on the ahead-of-time kernels; scipy / "
        f"compiled through numba's JIT: {t_s / t_j:.2f}x"
    )
    d = _max_diff(outputs.get("gait --model kneed (compiled)"),
                  outputs.get("gait --model kneed --backend scipy"))
    if d is not None:
        notes.append(f"kneed fixed point, compiled vs scipy: max |difference| {d:.2g}")
    for act, R in itertools.product(("pushoff", "hip-energy", "hip-pd"), ("0", "0.3")):
        name = f"powered --radius {R} --speed 0.5 --actuation {act}"
        ref = f"{name} --backend scipy"
        line = (f"{name}: backend {(outputs.get(name) or {}).get('backend')} (the default), "
                f"scipy / compiled {med[ref] / med[name]:.2f}x")
        d = _max_diff(outputs.get(name), outputs.get(ref))
        if d is not None:
            line += f", fixed point max |difference| {d:.2g}"
        notes.append(line)
    slow = [r["command"] for r in rows if r["command"].startswith("powered")
            and r["median_s"] >= 10.0]
    notes.append("powered: every run under 10 s" if not slow else f"powered >= 10 s: {slow}")
    if compiled_in_rounds:
        notes.append("WARNING: a timed run compiled a kernel (its source changed during the "
                     "rounds), so these medians include compile time: "
                     f"{sorted(compiled_in_rounds)}")
    for name, (wall, code) in cold.items():
        notes.append(f"first run (empty numba cache, no ahead-of-time modules): `{name}` "
                     f"{wall:.1f} s (exit {code})")
    return {
        "benchmark": "commands as processes",
        "machine": machine(("numpy", "scipy", "numba")),
        "cpu_count": os.cpu_count(),
        "rows": rows,
        "cold": {k: {"wall_s": w, "exit": c} for k, (w, c) in cold.items()},
        "notes": notes,
    }


def format_table(result: dict[str, Any]) -> str:
    lines = [
        f"**{result['benchmark']}** ({result['machine']})",
        "",
        "| command | median wall (s) | min-max (s) | ratio to `impact --json` | exit | stable |",
        "| --- | ---: | ---: | ---: | ---: | --- |",
    ]
    for r in result["rows"]:
        stable = "" if r["stable"] is None else str(r["stable"]).lower()
        lines.append(
            f"| `{r['command']}` | {r['median_s']:.3g} | {r['min_s']:.3g}-{r['max_s']:.3g} | "
            f"{r['ratio_to_impact']:.2g} | "
            f"{r['exit']} | {stable} |"
        )
    lines += [""] + [f"- {n}" for n in result["notes"]]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    return run_main(__doc__, run, format_table, argv, quick_help="one timed round, no cold runs")


if __name__ == "__main__":
    sys.exit(main())
