"""A headless Chromium that runs an engine's page from ``file://`` and returns what it computed.

The browser and its driver are the system's (Debian's ``chromium`` and ``chromium-driver``,
driven by selenium); the engines are the npm packages of ``package.json``, installed by
``npm ci`` into ``node_modules/`` (``scripts/setup.sh``).  Nothing is downloaded at run time:
Chromium starts with a fresh profile, no background networking, no component updates, and
WebGL 2 on SwiftShader (``--disable-gpu``), so the pixels do not depend on a GPU.

A page is an ES module (``fogref/engines/<engine>.js``) that sets ``window.fogrefRender(spec)``
and then ``data-ready`` on ``<body>``; :meth:`Browser.run_page` writes a small HTML file with
an import map (bare names such as ``"three"`` -> files under ``node_modules``), waits for
``data-ready`` (an event, not a clock; ``timeout`` [s] only bounds a hang) and calls
``fogrefRender`` with a JSON-able ``spec``.

Examples
--------
>>> find_chromium()[2] == "" or "chromium" in find_chromium()[2]
True
>>> node_modules_dir(must_exist=False).name
'node_modules'
"""

from __future__ import annotations

import json
import os
import shutil
import tempfile
from pathlib import Path

from fogref.errors import FogrefError

__all__ = ["Browser", "EngineUnavailable", "find_chromium", "node_modules_dir", "package_version"]

BROWSERS = ("chromium", "chromium-browser", "google-chrome")
DRIVERS = ("chromedriver",)
#: Chromium's flags: headless, no sandbox (containers), SwiftShader WebGL, nothing fetched.
FLAGS = (
    "--headless=new",
    "--no-sandbox",
    "--disable-gpu",
    "--enable-unsafe-swiftshader",
    "--disable-dev-shm-usage",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
    "--allow-file-access-from-files",
    "--force-device-scale-factor=1",
)


class EngineUnavailable(FogrefError):
    """The browser, its driver, selenium or an engine's npm package is missing (or will not start)."""


def find_chromium() -> tuple[str | None, str | None, str]:
    """``(browser, driver, why not)``: the binaries on ``PATH``, or the reason one is missing ("" if none)."""
    try:
        import selenium  # noqa: F401
    except ImportError:
        return None, None, "selenium is not installed (pip install -e '.[test]')"
    b = next((shutil.which(n) for n in BROWSERS if shutil.which(n)), None)
    d = next((shutil.which(n) for n in DRIVERS if shutil.which(n)), None)
    if not b or not d:
        missing = " and ".join(n for n, x in (("chromium", b), ("chromedriver", d)) if not x)
        why = (
            f"no {missing} on PATH: the engines run in headless Chromium (apt-get install chromium "
            "chromium-driver; scripts/setup.sh does it where it runs as root)"
        )
        return b, d, why
    return b, d, ""


def package_version(node_modules: Path, package: str) -> str:
    """The installed version of the npm ``package`` (its ``package.json``), e.g. ``"0.187.0"``."""
    return str(json.loads((Path(node_modules) / package / "package.json").read_text())["version"])


def node_modules_dir(must_exist: bool = True) -> Path:
    """The ``node_modules`` folder: ``$FOGREF_NODE_MODULES``, else the repository's (beside ``fogref/``).

    EngineUnavailable when ``must_exist`` and it is missing.
    """
    env = os.environ.get("FOGREF_NODE_MODULES")
    path = Path(env) if env else Path(__file__).resolve().parents[2] / "node_modules"
    if must_exist and not path.is_dir():
        raise EngineUnavailable(
            f"{path}: no node_modules folder: install the engines with `npm ci` in the repository "
            "(scripts/setup.sh), or set FOGREF_NODE_MODULES"
        )
    return path


class Browser:
    """A headless Chromium session (a context manager; :meth:`close` ends the browser).

    Parameters
    ----------
    timeout : float
        Seconds a page may take to load or to render before it is called hung (default 300).
    """

    def __init__(self, timeout: float = 300.0):
        self.timeout = float(timeout)
        browser, driver, why = find_chromium()
        if why:
            raise EngineUnavailable(why)
        from selenium import webdriver
        from selenium.common.exceptions import WebDriverException
        from selenium.webdriver.chrome.service import Service

        self._dir = tempfile.TemporaryDirectory(prefix="fogref-engine-")
        o = webdriver.ChromeOptions()
        o.binary_location = browser
        for a in (*FLAGS, f"--user-data-dir={Path(self._dir.name) / 'profile'}"):
            o.add_argument(a)
        o.set_capability("goog:loggingPrefs", {"browser": "ALL"})
        try:
            self.driver = webdriver.Chrome(service=Service(driver), options=o)
        except WebDriverException as e:
            self._dir.cleanup()
            text = (e.msg or str(e)).strip()
            first = text.splitlines()[0] if text else type(e).__name__
            raise EngineUnavailable(f"{browser}: Chromium did not start ({first})") from None
        self.driver.set_script_timeout(self.timeout)
        self.version = self.driver.capabilities.get("browserVersion", "?")

    def __enter__(self) -> "Browser":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        """End the browser and remove its profile."""
        try:
            self.driver.quit()
        finally:
            self._dir.cleanup()

    def run_page(self, module: Path, imports: dict[str, Path], spec: dict) -> dict:
        """Load the ES module ``module`` with ``imports`` (bare name -> file; a name ending in
        ``/`` -> a folder, the import map's prefix for the modules under it) and return
        ``window.fogrefRender(spec)``.

        EngineUnavailable when a file or folder is missing; FogrefError naming the page and the
        browser's console errors when the page does not get ready or its script throws.
        """
        from selenium.common.exceptions import JavascriptException, TimeoutException
        from selenium.webdriver.support.ui import WebDriverWait

        urls = {}
        for name, f in imports.items():
            folder = name.endswith("/")
            if not (Path(f).is_dir() if folder else Path(f).is_file()):
                raise EngineUnavailable(
                    f"{f}: missing ('{name}'); install the engines with `npm ci` (scripts/setup.sh)"
                )
            urls[name] = Path(f).resolve().as_uri() + ("/" if folder else "")
        page = Path(self._dir.name) / f"{Path(module).stem}.html"
        importmap = json.dumps({"imports": urls})
        page.write_text(
            "<!doctype html><html><head><meta charset='utf-8'>"
            f"<script type='importmap'>{importmap}</script></head><body>"
            f"<script type='module' src='{Path(module).resolve().as_uri()}'></script></body></html>",
            encoding="utf-8",
        )
        self.driver.get(page.as_uri())
        try:
            WebDriverWait(self.driver, self.timeout, poll_frequency=0.05).until(
                lambda d: d.execute_script("return document.body && document.body.getAttribute('data-ready')")
            )
        except TimeoutException:
            raise FogrefError(
                f"{module}: the page did not get ready in {self.timeout:g} s{self._console()}"
            ) from None
        try:
            return self.driver.execute_script("return window.fogrefRender(arguments[0]);", spec)
        except JavascriptException as e:
            raise FogrefError(
                f"{module}: the page's script failed: {e.msg.splitlines()[0]}{self._console()}"
            ) from None
        except TimeoutException:
            raise FogrefError(
                f"{module}: the render took more than {self.timeout:g} s{self._console()}"
            ) from None

    def _console(self) -> str:
        errors = [e.get("message", "") for e in self.driver.get_log("browser") if e.get("level") == "SEVERE"]
        return f" (console: {errors[0][:300]})" if errors else ""
