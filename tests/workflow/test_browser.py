"""The HTML reports in a real browser: headless Chromium loads them from a local server.

Every image must decode, the console must show no error, nothing may be requested from
anywhere but the local server (or ``data:`` URIs), and the data statement must be on the
first screen. A screenshot of each page is saved in the test's tmp folder.

Needs the Debian packages ``chromium`` and ``chromium-driver`` (``.ci/run`` installs
them); without them the test is skipped with a message.
"""

from __future__ import annotations

import functools
import json
import shutil
import threading
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
def server(built):
    """The built dataset's results folder over http://127.0.0.1:<free port>/."""
    httpd = ThreadingHTTPServer(
        ("127.0.0.1", 0), functools.partial(_QuietHandler, directory=str(built.out))
    )
    thread = threading.Thread(target=httpd.serve_forever, daemon=True)
    thread.start()
    yield f"http://127.0.0.1:{httpd.server_address[1]}"
    httpd.shutdown()
    httpd.server_close()


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
    "reports/paper_report.html",
    "reports/dataset_report.html",
    "reports/condition_R1.html",
    "reports/model_R2.html",
)


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
    if page != "index.html":
        assert images, f"{page}: a report without a single figure"

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
    assert "SIMULATED DATA" in text and "SIMULATED data" in text

    shot = tmp_path / (page.replace("/", "_").removesuffix(".html") + ".png")
    assert browser.save_screenshot(str(shot))
    assert shot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and shot.stat().st_size > 10_000
