"""``report.html`` in every run folder: it parses as HTML (every element closed), needs no
server (no script, no external style sheet or link), every local link resolves to a file in
the folder, every data file is linked, and it shows the status, each analysis and its
figures; for an impact-pair run, a gearbox run and a failed run."""
from __future__ import annotations

import json
import math
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlsplit

import numpy as np
import pytest

from vibrogear.cli import main
from vibrogear.report.page.html_report import REPORT_NAME, render_html_report

ROOT = Path(__file__).resolve().parents[2]
IMPACT_PAIR = str(ROOT / "configs" / "impact_pair.toml")
GEAR_PAIR = str(ROOT / "configs" / "gear_pair.toml")
IMPACT_SMALL = [
    'scene.analyses=["time_response", "sweep", "continuation"]', "time_response.periods=5",
    "sweep.n_points=6", "sweep.omega_min=0.8", "sweep.omega_max=1.0",
    "sweep.transient_periods=40", "sweep.extra_transient_periods=0", "sweep.record_periods=8",
    "continuation.omega_min=0.8", "continuation.omega_max=1.0", "continuation.max_points=30",
]
GEAR_SMALL = [
    'scene.analyses=["time_response", "sweep"]',
    "time_response.periods=20", "time_response.samples_per_period=16",
    "sweep.n_points=3", "sweep.rpm_min=5000", "sweep.rpm_max=6500",
    "sweep.transient_periods=20", "sweep.extra_transient_periods=20",
    "sweep.record_periods=8", "sweep.max_period=4", "integration.max_steps=500000",
]
VOID = {"meta", "img", "br", "hr", "link", "input", "col", "wbr", "source", "area", "base"}


class _Page(HTMLParser):
    """Collects tags, links, image sources and text, and checks that elements nest."""

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.tags: list[str] = []
        self.links: list[str] = []
        self.images: list[str] = []
        self.ids: set[str] = set()
        self.section_ids: list[str] = []          # the ids of the <h2> sections, in order
        self.text: list[str] = []
        self.stack: list[str] = []
        self.errors: list[str] = []

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        self.tags.append(tag)
        if "id" in attrs:
            self.ids.add(attrs["id"])
            if tag == "h2":
                self.section_ids.append(attrs["id"])
        if attrs.get("href") is not None:
            self.links.append(attrs["href"])
        if attrs.get("src") is not None:
            self.links.append(attrs["src"])
            if tag == "img":
                self.images.append(attrs["src"])
        if tag not in VOID:
            self.stack.append(tag)

    def handle_startendtag(self, tag, attrs):
        self.handle_starttag(tag, attrs)
        if tag not in VOID:
            self.stack.pop()

    def handle_endtag(self, tag):
        if not self.stack or self.stack[-1] != tag:
            self.errors.append(f"</{tag}> closes {self.stack[-1:] or 'nothing'}")
        else:
            self.stack.pop()

    def handle_data(self, data):
        self.text.append(data)


def _parse(text: str) -> _Page:
    page = _Page()
    page.feed(text)
    page.close()
    assert text.lstrip().lower().startswith("<!doctype html>")
    assert not page.errors and not page.stack, (page.errors, page.stack)
    return page


def _check_page(out: Path) -> tuple[_Page, str, dict]:
    """Parse ``out/report.html`` and check what every report must hold; return the parsed
    page, its text and the run's summary."""
    summary = json.loads((out / "summary.json").read_text())
    page = _parse((out / REPORT_NAME).read_text(encoding="utf-8"))
    text = " ".join(page.text)
    # self-contained: no script, no style sheet or anything else fetched from elsewhere
    assert "script" not in page.tags and "link" not in page.tags and "iframe" not in page.tags
    local = []
    for link in page.links:
        parts = urlsplit(link)
        assert not parts.scheme and not parts.netloc, link
        if parts.path:
            local.append(unquote(parts.path))
        else:
            assert parts.fragment in page.ids, link               # in-page anchor
    for rel in local:
        target = (out / rel).resolve()
        assert target.is_file() and out.resolve() in target.parents, rel
    # every file of the folder (bar the page itself) is linked
    in_folder = {p.relative_to(out).as_posix() for p in out.rglob("*")
                 if p.is_file() and p.name != REPORT_NAME and not p.name.startswith(".")}
    assert in_folder <= set(local), in_folder - set(local)
    assert f"Computation: {summary['status']}" in " ".join(text.split())
    for name, value in summary["versions"].items():
        assert name in text and value in text
    for name in summary["analyses"]:
        assert f"a-{name}" in page.ids and name in text
    return page, text, summary


@pytest.fixture(scope="module")
def impact_pair_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("impact_pair") / "out"
    args = ["run", IMPACT_PAIR, "--quiet", "--out", str(out)]
    for o in IMPACT_SMALL:
        args += ["--set", o]
    assert main(args) == 0
    return out


def test_impact_pair_report(impact_pair_run):
    out = impact_pair_run
    page, text, summary = _check_page(out)
    assert summary["status"] == "ok"
    pngs = {p.name for p in out.glob("*.png")}
    assert pngs and pngs <= set(page.images)                   # every figure shown
    for name in ("time_response.png", "bifurcation.png", "branch_max.png"):
        assert name in page.images
    # error estimates and key values of each analysis are in the page
    assert "Error estimates" in text and "liouville_det_error" in text
    assert "accumulated_local_error" in text and "rhs_calls" in text
    folds = summary["results"]["continuation"]["folds"]
    assert f"{folds[0]:.4g}" in text
    # the findings open the page: the first section, with the verdict of summary.json
    assert page.section_ids[0] == "findings"
    assert summary["findings"]["verdict"] in " ".join(text.split())


def test_gearbox_report(tmp_path):
    out = tmp_path / "out"
    args = ["run", GEAR_PAIR, "--quiet", "--out", str(out)]
    for o in GEAR_SMALL:
        args += ["--set", o]
    assert main(args) == 0
    page, text, summary = _check_page(out)
    assert summary["model"] == "gearbox" and "gearbox" in text
    assert {"time_response.png", "bifurcation.png"} <= set(page.images)
    # every band of the findings recomputes from sweep.npz with its metric, op, threshold
    from test_findings import check_bands_recompute
    with np.load(out / "sweep.npz") as z:
        arrays = {k: z[k] for k in z.files}
    findings = summary["findings"]
    assert findings["bands"] and check_bands_recompute(arrays, findings) == len(
        [b for b in findings["bands"] if b["source"] == "sweep.npz"])
    assert page.section_ids[0] == "findings" and "findings.png" in page.images
    for name in ("time_response.csv", "time_response.npz", "sweep.csv", "sweep.npz",
                 "summary.json"):
        assert name in page.links
    _check_in_browser(out)


#: what the page reports about itself once loaded in the browser (added to a copy only)
_PROBE = """<script>
window.addEventListener('load', () => {
  const imgs = [...document.images];
  const de = document.documentElement;
  document.body.setAttribute('data-probe', JSON.stringify({
    images: imgs.length,
    broken: imgs.filter(i => !(i.complete && i.naturalWidth > 0)).map(i => i.getAttribute('src')),
    scroll_width: de.scrollWidth, client_width: de.clientWidth,
    first_section: document.querySelector('h2') ? document.querySelector('h2').id : null}));
});
</script>"""


def _check_in_browser(out: Path, first_section: str | None = "findings",
                      min_images: int = 3) -> None:
    """Debian's chromium renders the page at 1280 px: every image loads, nothing is wider
    than the window, the findings are the first section (the project's set-up installs
    chromium for the test tier: scripts/setup.sh --browser)."""
    import html as html_mod
    import re
    import shutil
    import subprocess
    browser = shutil.which("chromium")
    assert browser, "chromium is not installed: run ./scripts/setup.sh --browser"
    probe = out / "browser_probe.html"
    text = (out / REPORT_NAME).read_text(encoding="utf-8")
    probe.write_text(text.replace("</body>", _PROBE + "</body>"), encoding="utf-8")
    try:
        done = subprocess.run(
            [browser, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
             "--window-size=1280,1000", "--virtual-time-budget=10000", "--dump-dom",
             probe.as_uri()], capture_output=True, text=True, timeout=120)
    finally:
        probe.unlink()
    found = re.search(r'data-probe="([^"]*)"', done.stdout)
    assert found, done.stderr[-2000:]
    state = json.loads(html_mod.unescape(found.group(1)))
    assert state["images"] >= min_images and state["broken"] == [], state
    assert state["scroll_width"] <= state["client_width"] <= 1280, state
    if first_section is not None:
        assert state["first_section"] == first_section, state


def test_failed_run_report(tmp_path):
    """A sweep whose every point fails: exit 1, and the page says "failed" and why."""
    out = tmp_path / "out"
    args = ["run", IMPACT_PAIR, "--quiet", "--out", str(out),
            "--set", 'scene.analyses=["sweep", "continuation"]', "--set", "sweep.n_points=2",
            "--set", "sweep.transient_periods=5", "--set", "integration.max_steps=5"]
    assert main(args) == 1
    page, text, summary = _check_page(out)
    assert summary["status"] == "failed"
    assert "failed" in text and "all 4 points failed" in text
    assert "sweep.partial.jsonl" in page.links                  # the failed points are kept
    assert "not run" in text                                    # continuation never ran


def test_render_escapes_and_odd_values(tmp_path):
    """Names are escaped, non-finite and numpy numbers print, missing files are not linked,
    an interrupted status is shown."""
    (tmp_path / "a b&c.csv").write_text("x\n1\n")
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "fig.png").write_bytes(b"\x89PNG\r\n")
    (tmp_path / ".sweep.npz.123.tmp").write_text("")
    summary = {
        "scene": "<script>alert(1)</script>", "source": "x.toml", "model": "impact_pair",
        "analyses": ["sweep", "continuation"],
        "versions": {"vibrogear": "0.1.0"}, "wall_time_s": {"sweep": np.float64(1.5)},
        "status": "interrupted", "notes": ["reduced <model> note"],
        "results": {"sweep": {
            "status": "interrupted", "message": "stopped by the user <Ctrl-C>",
            "error_estimate": math.nan, "points": np.int64(7), "ratio": math.inf,
            "branches": [{"n_periods": 1, "points": 3}, {"n_periods": 2, "points": 4}],
            "files": {"csv": str(tmp_path / "a b&c.csv"), "png": ["missing.png"],
                      "other": "/elsewhere/x.png"}}},
    }
    text = render_html_report(tmp_path, summary)
    page = _parse(text)
    assert "<script>" not in text and "script" not in page.tags
    assert "&lt;script&gt;" in text and "&lt;Ctrl-C&gt;" in text and "&lt;model&gt;" in text
    joined = " ".join(page.text)
    assert "interrupted" in joined and "not run" in joined
    assert "nan" in joined and "inf" in joined and "7" in joined
    assert "a%20b%26c.csv" in page.links and "sub/fig.png" in page.images
    assert not any("missing" in link or "elsewhere" in link or ".tmp" in link
                   for link in page.links)


def test_housing_report_in_browser(tmp_path):
    """A housing scene's report with its shaded mode shapes: chromium loads every image (the
    figures of the housing pictures among them), nothing overflows at 1280 px."""
    out = tmp_path / "out"
    small = str(ROOT / "configs" / "housing_small.toml")
    assert main(["run", small, "--quiet", "--out", str(out)]) == 0
    page, text, summary = _check_page(out)
    assert "housing_modes.png" in page.images
    _check_in_browser(out, first_section=None, min_images=2)
