"""A headless Chromium (Debian's ``chromium`` + ``chromium-driver``) driven by selenium, for the
HTML report tests and ``scripts/make_html_examples.py`` (the engines' driver is
:mod:`fogref.engines.browser`).  Nothing is downloaded: the browser and
driver are the system's (``scripts/setup.sh`` installs them where it can)."""

from __future__ import annotations

import json
import time
from pathlib import Path


def find_browser() -> tuple[str | None, str | None, str]:
    """``(browser, driver, why not)``: the binaries, or None and the reason they are missing
    (:func:`fogref.engines.browser.find_chromium`, the one search)."""
    from fogref.engines.browser import find_chromium

    return find_chromium()


def start(width: int = 1400, height: int = 1100, webgl: bool = False):
    """A headless Chromium with console and network logging.

    ``webgl``: WebGL 2 on SwiftShader (Chromium's CPU rasteriser; ``--enable-unsafe-swiftshader``
    since Chromium 137) and ES modules and ``fetch``-free XHR from ``file://``
    (``--allow-file-access-from-files``), for the engine pages of ``tests/web/``.
    """
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    browser, driver, why = find_browser()
    if why:
        raise RuntimeError(why)
    o = webdriver.ChromeOptions()
    o.binary_location = browser
    gpu = (
        ("--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--allow-file-access-from-files")
        if webgl
        else ("--disable-gpu",)
    )
    for a in (
        "--headless=new",
        "--no-sandbox",
        *gpu,
        "--disable-dev-shm-usage",
        f"--window-size={width},{height}",
        "--force-device-scale-factor=1",
        "--hide-scrollbars",
    ):
        o.add_argument(a)
    o.set_capability("goog:loggingPrefs", {"browser": "ALL", "performance": "ALL"})
    return webdriver.Chrome(service=Service(driver), options=o)


def load(drv, path, timeout: float = 300.0) -> None:
    """Open ``path`` (file://) and wait until the page's script has decoded its data (the event;
    ``timeout`` [s] only catches a hang, generous for a loaded machine)."""
    drv.get(Path(path).resolve().as_uri())
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        if drv.execute_script("return document.body && document.body.getAttribute('data-ready')"):
            return
        time.sleep(0.05)
    raise TimeoutError(f"{path}: the page did not get ready in {timeout} s")


def console_errors(drv) -> list[dict]:
    """Console messages of level SEVERE (errors) since the last call."""
    return [e for e in drv.get_log("browser") if e.get("level") == "SEVERE"]


def requests(drv) -> list[str]:
    """URLs the page requested since the last call (Network.requestWillBeSent)."""
    out = []
    for e in drv.get_log("performance"):
        msg = json.loads(e["message"])["message"]
        if msg.get("method") == "Network.requestWillBeSent":
            out.append(msg["params"]["request"]["url"])
    return out


def screenshot(drv, path, full: bool = False) -> Path:
    """A PNG of the viewport (``full``: of the whole page, by resizing the window to it)."""
    if full:
        h = drv.execute_script("return document.documentElement.scrollHeight")
        drv.set_window_size(1400, min(int(h) + 40, 6000))
    drv.save_screenshot(str(path))
    return Path(path)
