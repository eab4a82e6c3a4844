"""Rendering rate of the walk animation: frames per second written, before and after blitting.

The walk of ``heelstrike walk --radius 0.3 --slope 3deg --steps 8 --out walk.gif`` (the
period-one gait at R = 0.3 m, 3 deg, 8 steps, 30 frames per second of walk time) is animated
to a GIF two ways, on the same frames:

- **before**: matplotlib's ``FuncAnimation`` saved by its ``PillowWriter`` (what
  ``heelstrike.plots.gait`` did until issue 35: a full Agg draw of the figure per frame; the
  code is kept below as the reference, with the redundant post-draw skipped as it was);
- **after**: :func:`heelstrike.plots.gait.animate_walk` (the background drawn once, the moving
  artists blitted over it, the pixels handed straight to Pillow on one palette).

Rates are frames / wall time of the whole write (rendering and encoding), the best of
``repeats`` runs. Run ``python benchmarks/bench_animation.py`` (``--quick``: 2 steps, one run;
``--json PATH``).
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np
from _common import machine, run_main

FIXED_POINT = (-0.386284, 1.419327, -0.967944)  # R = 0.3 m, 3 deg (heelstrike gait)


def _frames(steps: int, fps: float) -> Any:
    from heelstrike.analysis.limit_cycle import PoincareMap
    from heelstrike.analysis.walk_tables import walk_frames
    from heelstrike.models.compass import CompassGait

    walker = CompassGait(foot_radius=0.3)
    walk = PoincareMap(walker=walker, slope=np.radians(3.0), rtol=1e-9, atol=1e-9,
                       max_step=0.5 / fps).walk(list(FIXED_POINT), steps)
    return walker, walk, walk_frames(walker, walk, fps)


def _before(frames: Any, path: Path, slope: float, fps: float) -> None:
    """The pre-issue-35 writer: one full figure draw per frame through FuncAnimation."""
    from matplotlib.animation import FuncAnimation, PillowWriter

    import heelstrike.plots.gait as g

    captured: dict[str, Any] = {}

    def grab(fig: Any, draw: Any, n: int, fps_: float, out: Path, progress: bool = False) -> Path:
        captured.update(fig=fig, draw=draw, n=n)
        return out

    real = g._save_animation
    g._save_animation = grab  # let animate_walk build the scene, then save it the old way
    try:
        g.animate_walk(frames, path, foot_radius=0.3, slope=slope, fps=fps)
    finally:
        g._save_animation = real

    class Saved(FuncAnimation):
        def _post_draw(self, framedata: Any, blit: bool) -> None:
            pass

    anim = Saved(captured["fig"], captured["draw"], frames=captured["n"],
                 interval=1000.0 / fps, blit=False)
    anim.save(str(path), writer=PillowWriter(fps=round(fps)))


def _after(frames: Any, path: Path, slope: float, fps: float) -> None:
    from heelstrike.plots.gait import animate_walk

    animate_walk(frames, path, foot_radius=0.3, slope=slope, fps=fps)


def run(*, quick: bool = False) -> dict[str, Any]:
    """Time both writers on the same frames; frames per second of each."""
    from PIL import Image

    steps, repeats, fps = (2, 1, 30.0) if quick else (8, 2, 30.0)
    _, walk, frames = _frames(steps, fps)
    n = int(frames.shape[0])
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, fn in (("before (FuncAnimation + PillowWriter)", _before),
                         ("after (blitting, frames to Pillow)", _after)):
            best = np.inf
            for r in range(repeats):
                out = Path(tmp) / f"{name.split()[0]}{r}.gif"
                t0 = time.perf_counter()
                fn(frames, out, float(walk.slope), fps)
                best = min(best, time.perf_counter() - t0)
            with Image.open(out) as im:
                written = im.n_frames
            rows.append({"writer": name, "frames": n, "frames_in_file": written,
                         "seconds": best, "frames_per_s": n / best,
                         "bytes": out.stat().st_size})
    return {"machine": machine(("numpy", "matplotlib", "pillow")), "steps": steps,
            "rows": rows}


def format_table(result: dict[str, Any]) -> str:
    """A markdown table of both writers."""
    lines = [f"machine: {result['machine']}", "",
             f"`walk --radius 0.3 --slope 3deg --steps {result['steps']}` animation, GIF:", "",
             "| writer | frames | seconds | frames/s | file (kB) |", "|---|---:|---:|---:|---:|"]
    for r in result["rows"]:
        lines.append(f"| {r['writer']} | {r['frames_in_file']} | {r['seconds']:.2f} | "
                     f"{r['frames_per_s']:.1f} | {r['bytes'] / 1e3:.0f} |")
    return "\n".join(lines)


if __name__ == "__main__":
    raise SystemExit(run_main(__doc__, run, format_table,
                              quick_help="2 steps, one run"))
