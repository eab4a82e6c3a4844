"""The built documentation site, loaded in headless Chromium (issue 12, item 1).

Needs the site built first (CI does it in .ci/run):

    pip install '.[docs]' && sphinx-build -W --keep-going -b html docs docs/_build/html

How the browser check works, and why: every gallery page is copied (with the whole site, so that
relative links resolve) into a temporary directory, and a small script is added to the copy that
runs on the page's ``load`` event, when the browser has fetched and decoded every image. It
lists the page's gallery figures (``<img>`` elements whose ``src`` is one of sphinx-gallery's
``images/sphx_glr_*`` files) with ``complete``, ``naturalWidth``/``naturalHeight`` (0 when
the browser could not load or decode the PNG) and the width they are laid out at, and writes the
list as JSON into the DOM. ``chromium --headless --dump-dom`` prints the DOM after the load,
and the test reads the JSON back. So a page passes only if a real browser displayed a decoded
figure on it; the PNG files are also checked to exist and hold a non-trivial image. The built
site itself is never modified.

Math (issue 35, item 2): the paper page is loaded the same way with the network off (a proxy at
an address where nothing listens, and no host name resolves), and a script run once MathJax has
typeset the page counts the equations that hold MathJax's output (``mjx-container``) and the raw
TeX delimiters left in the text. A control loads the same page with MathJax taken from a CDN
instead and must see raw TeX, which shows that the check really runs offline.
"""

from __future__ import annotations

import html
import importlib.util
import json
import os
import re
import shutil
import subprocess
from pathlib import Path

import pytest

pytestmark = [pytest.mark.docs, pytest.mark.slow]

ROOT = Path(__file__).resolve().parent.parent
SITE = ROOT / "docs" / "_build" / "html"
EXAMPLES = ROOT / "examples"
BUILD = "pip install '.[docs]' && sphinx-build -W --keep-going -b html docs docs/_build/html"

CHECK_SCRIPT = """
<script>
window.addEventListener("load", function () {
  var found = Array.prototype.slice.call(document.querySelectorAll("img")).filter(function (i) {
    var s = i.getAttribute("src") || "";
    return s.indexOf("images/sphx_glr_") !== -1;
  }).map(function (i) {
    return {src: i.getAttribute("src"), complete: i.complete, width: i.naturalWidth,
            height: i.naturalHeight, shown: i.getBoundingClientRect().width};
  });
  var pre = document.createElement("pre");
  pre.id = "heelstrike-figure-check";
  pre.textContent = JSON.stringify(found);
  document.body.appendChild(pre);
});
</script>
"""

# Runs when the page has loaded and, if MathJax is there, once MathJax has typeset the page
# (``MathJax.startup.promise``); counts Sphinx's math elements (``div.math`` for displayed
# equations, ``span.math`` inline), those that hold MathJax's output (``mjx-container``), the
# TeX delimiters ``\[`` and ``\(`` left in the visible text, and the MathJax script's source.
MATH_SCRIPT = r"""
<script>
window.addEventListener("load", function () {
  function report() {
    var pre = document.createElement("pre");
    pre.id = "heelstrike-math-check";
    var scripts = Array.prototype.slice.call(document.querySelectorAll("script[src]"))
      .map(function (s) { return s.getAttribute("src"); })
      .filter(function (s) { return s.indexOf("tex-chtml") !== -1; });
    pre.textContent = JSON.stringify({
      mathjax: typeof window.MathJax === "object" && !!window.MathJax.startup,
      math: document.querySelectorAll("div.math, span.math").length,
      typeset: document.querySelectorAll("div.math mjx-container, span.math mjx-container").length,
      raw: (document.body.innerText.match(/\\\[|\\\(/g) || []).length,
      scripts: scripts
    });
    document.body.appendChild(pre);
  }
  var mj = window.MathJax;
  if (mj && mj.startup && mj.startup.promise) { mj.startup.promise.then(report, report); }
  else { report(); }
});
</script>
"""
CDN = "https://cdn.jsdelivr.net/npm/mathjax@3/es5/tex-chtml.js"


def _chromium() -> str | None:
    for name in ("chromium", "chromium-browser", "google-chrome"):
        path = shutil.which(name)
        if path:
            return path
    return None


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Path:
    # CI (.ci/run) installs sphinx and chromium and builds the site first: never skip there.
    skip = pytest.fail if os.environ.get("CI") else pytest.skip
    if importlib.util.find_spec("sphinx") is None or importlib.util.find_spec(
        "sphinx_gallery"
    ) is None:
        skip(f"sphinx / sphinx-gallery not installed: {BUILD}")
    if _chromium() is None:
        skip("chromium not found (Debian: apt-get install chromium)")
    if not (SITE / "auto_examples" / "index.html").is_file():
        skip(f"documentation not built: {BUILD}")
    copy = tmp_path_factory.mktemp("site") / "html"
    shutil.copytree(SITE, copy)
    return copy


def _run_in_chromium(
    page: Path, profile: Path, script: str, marker: str, offline: bool = False
) -> object:
    """Load ``page`` (a copy) with ``script`` added in headless Chromium; the JSON it wrote.

    ``script`` must append ``<pre id="{marker}">JSON</pre>`` to the body. ``offline``: every
    request that is not a local file goes to a proxy at an address where nothing listens and
    every host name fails to resolve, so the page sees no network at all.
    """
    text = page.read_text(encoding="utf-8")
    assert "</body>" in text, page
    page.write_text(text.replace("</body>", script + "</body>", 1), encoding="utf-8")
    chromium = _chromium()
    assert chromium is not None
    cmd = [
        chromium, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
        "--no-first-run", "--disable-background-networking", "--disable-component-update",
        "--disable-sync", "--disable-dev-shm-usage", f"--user-data-dir={profile}",
        "--window-size=1280,2000", "--virtual-time-budget=10000", "--dump-dom",
    ]
    if offline:
        cmd += ["--proxy-server=127.0.0.1:9", "--host-resolver-rules=MAP * ~NOTFOUND"]
    cmd.append(page.as_uri())
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=180, check=False)
    m = re.search(rf'<pre id="{marker}">(.*?)</pre>', proc.stdout, re.S)
    assert m is not None, (
        f"chromium did not run the check on {page.name} (exit {proc.returncode}):\n"
        f"{proc.stderr[-2000:]}"
    )
    return json.loads(html.unescape(m.group(1)))


def _figures_shown(page: Path, profile: Path) -> list[dict[str, object]]:
    """Load ``page`` (a copy) in headless Chromium; the gallery figures it displayed."""
    found = _run_in_chromium(page, profile, CHECK_SCRIPT, "heelstrike-figure-check")
    assert isinstance(found, list)
    return found


def _math_shown(page: Path, profile: Path) -> dict[str, object]:
    """Load ``page`` (a copy) in headless Chromium, network off; what became of its math."""
    found = _run_in_chromium(page, profile, MATH_SCRIPT, "heelstrike-math-check", offline=True)
    assert isinstance(found, dict)
    return found


def test_gallery_has_a_page_for_every_example(site: Path) -> None:
    scripts = sorted(p.stem for p in EXAMPLES.glob("plot_*.py"))
    pages = sorted(p.stem for p in (site / "auto_examples").glob("plot_*.html"))
    assert len(scripts) >= 8
    assert pages == scripts, f"rebuild the docs ({BUILD}): pages {pages} != examples {scripts}"


def test_every_gallery_page_shows_its_figure(site: Path, tmp_path: Path) -> None:
    pages = sorted((site / "auto_examples").glob("plot_*.html"))
    assert len(pages) >= 8
    failures = []
    for i, page in enumerate(pages):
        shown = [
            f for f in _figures_shown(page, tmp_path / f"profile{i}")
            if "thumb" not in str(f["src"])
        ]
        if not shown:
            failures.append(f"{page.name}: no gallery figure on the page")
        for f in shown:
            png = (page.parent / str(f["src"])).resolve()
            ok = (
                f["complete"] is True
                and int(f["width"]) >= 200  # type: ignore[call-overload]
                and int(f["height"]) >= 150  # type: ignore[call-overload]
                and float(f["shown"]) >= 100  # type: ignore[arg-type]
                and png.is_file()
                and png.stat().st_size > 5_000
                and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
            )
            if not ok:
                failures.append(f"{page.name}: figure not displayed: {f}")
    assert not failures, "\n".join(failures)


@pytest.mark.parametrize("page", ["index.html", "paper.html"])
def test_front_page_and_paper_page_show_their_figure(site: Path, tmp_path: Path, page: str) -> None:
    # index: Fig. 3b from the gallery; paper: the model diagram (Fig. 1) from the gallery
    shown = _figures_shown(site / page, tmp_path / "profile")
    assert shown, f"{page}: no figure"
    for f in shown:
        assert f["complete"] is True and int(f["width"]) >= 200, f  # type: ignore[call-overload]
        assert float(f["shown"]) >= 100, f  # type: ignore[arg-type]


def test_gallery_index_shows_every_thumbnail(site: Path, tmp_path: Path) -> None:
    shown = _figures_shown(site / "auto_examples" / "index.html", tmp_path / "profile")
    thumbs = [f for f in shown if "thumb" in str(f["src"])]
    assert len(thumbs) >= 8
    bad = [f for f in thumbs if not (f["complete"] and int(f["width"]) > 50)]  # type: ignore[call-overload]
    assert not bad, bad


def test_paper_page_links_every_equation_to_its_code(site: Path) -> None:
    text = (site / "paper.html").read_text(encoding="utf-8")
    for n in range(1, 17):
        assert f"Eq. ({n})" in text or f"Eqs. ({n})" in text or f"and ({n})" in text, n
    for target in (
        "heelstrike.core.impact.kinetic_energy",
        "heelstrike.core.impact.impact",
        "heelstrike.models.compass.CompassGait.contact_jacobian",
        "heelstrike.core.impact.constrained_projector",
        "heelstrike.core.impact.admissible_projector",
        "heelstrike.core.impact.decompose_velocity",
        "heelstrike.core.impact.decompose_impulse",
        "heelstrike.dynamics.hybrid.heel_strike",
        "heelstrike.analysis.limit_cycle.find_limit_cycle",
        "heelstrike.analysis.powered.find_powered_gait",
        "heelstrike.analysis.heel_strike.heel_strike_study",
        "heelstrike.analysis.heel_strike.step_length",
    ):
        # a resolved cross-reference is a link to the API page's anchor of that object
        assert re.search(rf'<a class="reference internal" href="[^"]*#{re.escape(target)}"',
                         text), f"paper page does not link {target}"


def test_paper_page_typesets_its_equations_offline(site: Path, tmp_path: Path) -> None:
    """Opened from disk with the network off, the paper page shows typeset equations."""
    page = site / "paper.html"
    found = _math_shown(page, tmp_path / "profile")
    # MathJax comes with the site (sphinx-mathjax-offline), not from a CDN
    assert found["scripts"] == ["_static/mathjax/tex-chtml.js"], found
    assert (site / "_static" / "mathjax" / "tex-chtml.js").is_file()
    assert found["mathjax"] is True, found
    assert int(found["math"]) >= 16, found  # type: ignore[call-overload]  # eqs. (1)-(16) at least
    assert found["typeset"] == found["math"], f"equations left untypeset: {found}"
    assert found["raw"] == 0, f"raw TeX delimiters in the text: {found}"


def test_the_offline_check_sees_no_network(site: Path, tmp_path: Path) -> None:
    """Control: the same page with MathJax from the CDN instead shows raw TeX in the same
    check, so the check above really runs with the network off."""
    text = (site / "paper.html").read_text(encoding="utf-8")
    assert '"_static/mathjax/tex-chtml.js"' in text
    page = site / "paper_from_cdn.html"  # beside paper.html, so that relative links resolve
    page.write_text(text.replace('"_static/mathjax/tex-chtml.js"', f'"{CDN}"'), encoding="utf-8")
    found = _math_shown(page, tmp_path / "profile")
    assert found["scripts"] == [CDN], found
    assert found["mathjax"] is False and found["typeset"] == 0, found
    assert int(found["raw"]) >= 16, found  # type: ignore[call-overload]
