"""The HTML reports in a real browser: headless Chromium loads them from a local server.

Every image must decode, the console must show no error, nothing may be requested from
anywhere but the local server (or ``data:`` URIs), the data statement must be on the
first screen, and no page may scroll sideways (a wide table scrolls in its own box). A
screenshot of each page is saved in the test's tmp folder. The two index pages (the
dataset's and ``results/index.html`` across datasets) must also link only files that
exist and show the held-out errors of ``metrics.csv``, read here with the csv module.

Needs the Debian packages ``chromium`` and ``chromium-driver`` (``.ci/run`` installs
them); without them the test is skipped with a message.
"""

from __future__ import annotations

import contextlib
import csv
import functools
import io
import json
import shutil
import threading
import urllib.error
import urllib.request
from collections import defaultdict
from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path

import pytest

pytestmark = pytest.mark.browser

CHROMIUM = next(
    (p for p in (shutil.which("chromium"), "/usr/bin/chromium") if p and Path(p).is_file()), None
)
CHROMEDRIVER = next(
    (p for p in (shutil.which("chromedriver"), "/usr/bin/chromedriver") if p and Path(p).is_file()),
    None,
)
FIRST_SCREEN_PX = 800


class _QuietHandler(SimpleHTTPRequestHandler):
    def log_message(self, format, *args):  # noqa: A002  (the base class's name)
        pass


@pytest.fixture(scope="module")
def results(built, tmp_path_factory) -> Path:
    """A copy of the built results folder with the cross-dataset summary and page made in it."""
    from thermaxis.reports import crossdataset

    results = tmp_path_factory.mktemp("served") / "results"
    shutil.copytree(built.out, results / built.out.name)
    # The built dataset is not one of config datasets: named, as make results names its own.
    args = ["--results", str(results), "--datasets", built.out.name, "--formats", "png"]
    assert crossdataset.main(args) == 0
    return results


@contextlib.contextmanager
def _serving(folder: Path):
    """``folder`` over http://127.0.0.1:<free port>/."""
    httpd = ThreadingHTTPServer(
        ("127.0.0.1", 0), functools.partial(_QuietHandler, directory=str(folder))
    )
    thread = threading.Thread(target=httpd.serve_forever, daemon=True)
    thread.start()
    yield f"http://127.0.0.1:{httpd.server_address[1]}"
    httpd.shutdown()
    httpd.server_close()


@pytest.fixture(scope="module")
def server(results):
    with _serving(results) as url:
        yield url


@pytest.fixture(scope="module")
def two_datasets(built, tmp_path_factory):
    """A results folder holding two datasets' results, as two `thermaxis run`s leave it, its
    page across datasets made as they make it (from every dataset under results/, none
    named); served. Each holds the built dataset's held-out errors as five point-by-point
    algorithms': five long legend entries, the row that was cut at the figure's edge."""
    from thermaxis.reports import crossdataset

    with open(built.out / "tables" / "metrics.csv", newline="", encoding="utf-8") as fh:
        rows = [r for r in csv.DictReader(fh) if r["target"] == "error"]
    results = tmp_path_factory.mktemp("two") / "results"
    for name in ("models_a", "models_b"):
        (results / name / "tables").mkdir(parents=True)
        shutil.copy(built.out / "provenance.json", results / name)
        with open(results / name / "tables" / "metrics.csv", "w", newline="") as fh:
            writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
            writer.writeheader()
            for algorithm in ("mlr", "svr", "ridge", "pls", "gpr"):
                writer.writerows(
                    {**r, "approach": "pointwise", "algorithm": algorithm} for r in rows
                )
    assert crossdataset.main(["--results", str(results), "--formats", "png"]) == 0
    with _serving(results) as url:
        yield url


@pytest.fixture(scope="module")
def browser(tmp_path_factory):
    if CHROMIUM is None or CHROMEDRIVER is None:
        pytest.skip(
            "headless Chromium not found: install the Debian packages chromium and "
            "chromium-driver (.ci/run does)"
        )
    webdriver = pytest.importorskip(
        "selenium.webdriver", reason="selenium is not installed (envs/requirements.txt pins it)"
    )
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    options.binary_location = CHROMIUM
    for arg in (
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-quic",
        "--no-first-run",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--disable-dev-shm-usage",
        "--window-size=1280,900",
        f"--user-data-dir={tmp_path_factory.mktemp('chromium-profile')}",
    ):
        options.add_argument(arg)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL", "performance": "ALL"})
    driver = webdriver.Chrome(service=Service(CHROMEDRIVER), options=options)
    driver.set_page_load_timeout(60)
    yield driver
    driver.quit()


PAGES = (
    "index.html",
    "rep/index.html",
    "rep/reports/paper_report.html",
    "rep/reports/dataset_report.html",
    "rep/reports/condition_01.html",
    "rep/reports/model_02.html",
)
INDEXES = ("index.html", "rep/index.html")


def requested_urls(driver) -> list[str]:
    """URLs the page asked the network for, from Chromium's performance log."""
    urls = []
    for entry in driver.get_log("performance"):
        message = json.loads(entry["message"])["message"]
        if message.get("method") == "Network.requestWillBeSent":
            urls.append(message["params"]["request"]["url"])
    return urls


@pytest.mark.parametrize("page", PAGES)
def test_page_renders_images_without_console_errors(page, browser, server, tmp_path):
    browser.get_log("browser")  # drop what earlier pages left
    browser.get_log("performance")
    browser.get(f"{server}/{page}")
    assert browser.execute_script("return document.readyState") == "complete"

    images = browser.execute_script(
        "return Array.from(document.images)"
        ".map(i => [i.alt.slice(0, 60), i.complete, i.naturalWidth])"
    )
    broken = [alt for alt, complete, width in images if not (complete and width > 0)]
    assert broken == [], f"{page}: images that did not load: {broken}"
    assert images, f"{page}: a page without a single figure"

    errors = [e for e in browser.get_log("browser") if e["level"] == "SEVERE"]
    assert errors == [], f"{page}: console errors: {errors}"

    # Chromium's own chrome:// pages show up in the log too; the network is http(s) and ws(s).
    network = [
        u for u in requested_urls(browser) if u.split(":", 1)[0] in ("http", "https", "ws", "wss")
    ]
    foreign = [u for u in network if not u.startswith(f"{server}/")]
    assert foreign == [], f"{page}: requests beyond the local server: {foreign[:5]}"

    banner = browser.execute_script(
        "const b = document.querySelector('.tx-banner'); "
        "return b ? [b.getBoundingClientRect().top, b.getBoundingClientRect().bottom, "
        "b.innerText] : null"
    )
    assert banner is not None, f"{page}: no data statement banner"
    top, bottom, text = banner
    assert 0 <= top and bottom <= FIRST_SCREEN_PX, (
        f"{page}: the data statement is not on the first screen ({top}-{bottom} px)"
    )
    assert "SIMULATED DATA" in text
    assert "SIMULATED data" in text or page == "index.html"  # across datasets: names them

    # A wide table scrolls inside its own box: the page itself never scrolls sideways.
    width, viewport = browser.execute_script(
        "return [document.documentElement.scrollWidth, document.documentElement.clientWidth]"
    )
    assert width <= viewport, f"{page}: {width} px wide in a {viewport} px window"

    shot = tmp_path / (page.replace("/", "_").removesuffix(".html") + ".png")
    assert browser.save_screenshot(str(shot))
    assert shot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and shot.stat().st_size > 10_000


def _mean_rmse(metrics: Path) -> dict[tuple[str, str], float]:
    """Mean held-out RMSE of the error curves per (approach, algorithm), from the CSV text."""
    values = defaultdict(list)
    with open(metrics, newline="", encoding="utf-8") as fh:
        for row in csv.DictReader(fh):
            if row["target"] == "error":
                values[row["approach"], row["algorithm"]].append(float(row["rmse"]))
    return {key: sum(v) / len(v) for key, v in values.items()}


def _links_resolve(browser) -> list[str]:
    """The page's links that do not answer 200 (anchors within the page skipped)."""
    hrefs = browser.execute_script(
        "return Array.from(document.querySelectorAll('a[href]'))"
        ".filter(a => !a.getAttribute('href').startsWith('#')).map(a => a.href)"
    )
    broken = []
    for href in sorted(set(hrefs)):
        try:
            with urllib.request.urlopen(href.split("#")[0], timeout=10) as response:
                if response.status != 200:
                    broken.append(href)
        except urllib.error.URLError:
            broken.append(href)
    return broken


@pytest.mark.parametrize("page", INDEXES)
def test_index_links_resolve(page, browser, server):
    browser.get(f"{server}/{page}")
    assert _links_resolve(browser) == []


def test_dataset_index_leads_with_the_held_out_errors_of_metrics_csv(browser, server, results):
    expected = _mean_rmse(results / "rep" / "tables" / "metrics.csv")
    browser.get(f"{server}/rep/index.html")
    rows = browser.execute_script(
        "const t = document.querySelector('#headline-models table');"
        "const head = Array.from(t.tHead.rows[0].cells).map(c => c.textContent);"
        "return Array.from(t.tBodies[0].rows).map(r => Object.fromEntries(Array.from(r.cells)"
        ".map((c, i) => [head[i], c.getAttribute('data-value') ?? c.textContent])));"
    )
    shown = {(r["approach"], r["algorithm"]): float(r["mean_rmse_um"]) for r in rows}
    assert shown.keys() == expected.keys()
    for key, value in expected.items():
        assert shown[key] == pytest.approx(value, rel=1e-12)
    ordered = [float(r["mean_rmse_um"]) for r in rows]
    assert ordered == sorted(ordered), "the headline is not best first"
    # The answer is above the figures: its top on the first screen.
    top = browser.execute_script(
        "return document.querySelector('#answer').getBoundingClientRect().top"
    )
    assert top < FIRST_SCREEN_PX

    # A click on a header sorts the table in place (descending on the second click).
    header = browser.find_element(
        "xpath", "//div[@id='headline-models']//th[text()='mean_rmse_um']"
    )
    header.click()
    header.click()
    resorted = browser.execute_script(
        "return Array.from(document.querySelectorAll('#headline-models tbody tr'))"
        ".map(r => parseFloat(r.cells[3].getAttribute('data-value')))"
    )
    assert resorted == sorted(ordered, reverse=True)


def test_results_index_shows_each_datasets_best_model_and_links_its_page(browser, server, results):
    best = min(_mean_rmse(results / "rep" / "tables" / "metrics.csv").values())
    browser.get(f"{server}/index.html")
    text = browser.execute_script("return document.querySelector('#answer').innerText")
    assert f"mean RMSE of {best:.2f} µm" in text
    assert (
        browser.execute_script("return document.querySelector('#answer a').getAttribute('href')")
        == "rep/index.html"
    )


def _csv_rows(path: Path) -> list[dict]:
    """A table's rows, its '#' header lines skipped (the compensation tables carry them)."""
    with open(path, newline="", encoding="utf-8") as fh:
        return list(csv.DictReader(line for line in fh if not line.startswith("#")))


def _sentences_calling_a_model_best(text: str) -> list[str]:
    return [s.strip() for s in text.replace("\n", ". ").split(". ") if " best" in f" {s.lower()}"]


def test_the_answer_box_leads_the_dataset_index_with_the_numbers_of_its_tables(
    browser, server, results
):
    """The first screen (1280 x 800) shows the answer: the model, its held-out error beside
    the paper's configuration (recommendation.csv) and compensated beside uncompensated
    (compensation/summary.csv), and the verdict (model.json), each worked out here from
    the files with the csv and json modules; no sentence calls another model the best."""
    out = results / "rep"
    folds = _csv_rows(out / "tables" / "recommendation.csv")
    rmse = sum(float(r["rmse_um"]) for r in folds) / len(folds)
    paper = sum(float(r["paper_rmse_um"]) for r in folds) / len(folds)
    summary = _csv_rows(out / "compensation" / "summary.csv")
    before = max(float(r["largest_abs_uncompensated_um"]) for r in summary)
    after = max(float(r["largest_abs_compensated_um"]) for r in summary)
    deployment = json.loads((out / "compensation" / "model.json").read_text())["deployment"]

    browser.set_window_size(1280, FIRST_SCREEN_PX)
    try:
        browser.get(f"{server}/rep/index.html")
        viewport = browser.execute_script("return window.innerHeight")
        top, bottom, text = browser.execute_script(
            "const p = document.querySelector('#answer .tx-lead');"
            "const r = p.getBoundingClientRect(); return [r.top, r.bottom, p.innerText];"
        )
        figure = browser.execute_script(
            "const i = document.querySelector('#answer img');"
            "return i ? [i.getBoundingClientRect().top, i.complete, i.naturalWidth] : null;"
        )
        body = browser.execute_script("return document.body.innerText")
    finally:
        browser.set_window_size(1280, 900)
    assert 0 <= top and bottom <= viewport, (
        f"the answer is not on the first screen ({top}-{bottom} px)"
    )
    assert figure is not None, "the answer box has no figure"
    assert figure[0] < viewport and figure[1] and figure[2] > 0, figure
    assert deployment["candidate"] in text
    assert f"held-out RMSE {rmse:.2f} µm against {paper:.2f} µm" in text, text
    assert f"{after:.2f} µm compensated against {before:.2f} µm uncompensated" in text, text
    candidate = deployment["candidate"]
    opening = {
        "recommended": f"Deploy {candidate}:",
        "not_established": f"Not yet: {candidate},",
        "not_recommended": "Do not compensate with any candidate.",
    }[deployment["outcome"]]
    assert text.startswith(opening), text
    others = [s for s in _sentences_calling_a_model_best(body) if deployment["candidate"] not in s]
    assert others == [], others


def _touches_an_edge(png: bytes) -> list[str]:
    """The edges of an image where a pixel differs from the background (its corner's colour):
    a label or legend the figure's layout cut off."""
    import matplotlib.image as mpimg
    import numpy as np

    pixels = mpimg.imread(io.BytesIO(png), format="png")
    background = pixels[0, 0]
    edges = {
        "top": pixels[0],
        "bottom": pixels[-1],
        "left": pixels[:, 0],
        "right": pixels[:, -1],
    }
    return [side for side, line in edges.items() if not np.all(line == background)]


def test_no_figure_of_the_page_across_datasets_is_cut(browser, two_datasets):
    browser.get(f"{two_datasets}/index.html")
    listed = browser.execute_script(
        "return Array.from(document.querySelectorAll('#answer li')).map(li => li.innerText)"
    )
    assert [item.split(" ", 1)[0] for item in listed] == ["models_a", "models_b"], listed
    sources = browser.execute_script(
        "return Array.from(document.images).map(i => [i.src, i.complete, i.naturalWidth])"
    )
    assert sources, "the page across datasets has no figure"
    for src, complete, width in sources:
        assert complete and width > 0, src
        with urllib.request.urlopen(src, timeout=10) as response:
            assert _touches_an_edge(response.read()) == [], f"{src}: cut at its edge"
