"""The docs site's search, in a real browser: typing "conform" finds the contracts page.

The site is built into a temporary directory, served on a free loopback port, and searched in headless
Chromium through Selenium (Debian's chromium and chromium-driver; ``make test`` installs them).
"""

from __future__ import annotations

import functools
import http.server
import os
import shutil
import subprocess
import sys
import threading
from collections.abc import Iterator
from pathlib import Path

import pytest

from deploy.paths import REPO_ROOT

CHROMIUM = shutil.which("chromium")
CHROMEDRIVER = shutil.which("chromedriver")
# Skipped where the browser is missing, except in CI, where make test installs it: there it must run.
pytestmark = pytest.mark.skipif(
    (CHROMIUM is None or CHROMEDRIVER is None) and not os.environ.get("CI"),
    reason="Debian's chromium and chromium-driver are not installed (make browser)",
)


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    """The built site, served on loopback: its base URL."""
    out = tmp_path_factory.mktemp("site")
    built = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--quiet", "-d", str(out)],
        cwd=REPO_ROOT,
        env={**os.environ, "NO_MKDOCS_2_WARNING": "1"},
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert built.returncode == 0, built.stderr
    handler = functools.partial(_QuietHandler, directory=str(out))
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_address[1]}/"
    finally:
        server.shutdown()
        server.server_close()
        thread.join(5.0)


class _QuietHandler(http.server.SimpleHTTPRequestHandler):
    def log_message(self, format: str, *args: object) -> None:
        pass


def _browser(profile: Path):  # type: ignore[no-untyped-def]
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    options.binary_location = str(CHROMIUM)
    for flag in (
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-quic",
        "--no-first-run",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        f"--user-data-dir={profile}",
        "--window-size=1280,900",
    ):
        options.add_argument(flag)
    return webdriver.Chrome(service=Service(str(CHROMEDRIVER)), options=options)


def test_searching_conform_finds_the_contracts_page(site: str, tmp_path: Path) -> None:
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support import expected_conditions as seen
    from selenium.webdriver.support.ui import WebDriverWait

    browser = _browser(tmp_path / "profile")
    try:
        browser.get(site)
        box = WebDriverWait(browser, 30).until(
            seen.element_to_be_clickable((By.CSS_SELECTOR, "input.md-search__input"))
        )
        box.click()
        box.send_keys("conform")

        def results(driver):  # type: ignore[no-untyped-def]
            links = driver.find_elements(By.CSS_SELECTOR, ".md-search-result__list a")
            return [link.get_attribute("href") or "" for link in links] or False

        found = WebDriverWait(browser, 30).until(results, "no search results for 'conform' within 30 s")
        assert any("/contracts/" in href for href in found), found
        meta = browser.find_element(By.CSS_SELECTOR, ".md-search-result__meta").text
        assert "Initializing search" not in meta, meta
    finally:
        browser.quit()
