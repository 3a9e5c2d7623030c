"""Drive a headless Chromium through the DevTools protocol over a pipe (no extra dependency).

Used by the tests and benchmarks that open an evotol HTML report, click a preset and read what
the page shows, and that time how long plotly takes to draw 32 768 parallel-coordinate lines.
Chromium reads protocol commands from file descriptor 3 and writes replies to descriptor 4
(``--remote-debugging-pipe``); each message is one JSON object terminated by a NUL byte.

Example::

    with HeadlessChromium() as browser:
        page = browser.open(Path("report.html"))
        print(page.evaluate("document.title"))
"""
from __future__ import annotations

import json
import os
import select
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

from evotol.errors import EvotolError

#: flags that keep a headless Chromium quiet, offline and deterministic
CHROMIUM_FLAGS = ("--headless", "--no-sandbox", "--disable-quic", "--no-first-run",
                  "--disable-background-networking", "--disable-component-update", "--disable-sync",
                  "--window-size=1400,1000")

#: WebGL back ends for machines without a GPU: flags and environment. ``swiftshader`` is
#: Chromium's own CPU rasteriser; ``llvmpipe`` is Mesa's (package libgl1-mesa-dri), through ANGLE
#: on a surfaceless EGL display.
WEBGL_BACKENDS = {
    "swiftshader": (("--disable-gpu", "--enable-unsafe-swiftshader", "--use-angle=swiftshader"), {}),
    "llvmpipe": (("--use-gl=angle", "--use-angle=gl-egl", "--ignore-gpu-blocklist"), {"EGL_PLATFORM": "surfaceless"}),
}


def find_chromium() -> str | None:
    """Path of a Chromium/Chrome executable, or None when there is none on this machine.

    Returns
    -------
    str or None
        The first of ``chromium``, ``chromium-browser``, ``google-chrome``,
        ``google-chrome-stable``, ``chrome`` found on ``PATH``.
    """
    for name in ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable", "chrome"):
        path = shutil.which(name)
        if path:
            return path
    return None


class BrowserError(EvotolError):
    """The browser did not start, timed out, or a page script raised."""


class Page:
    """One tab, attached with a flat DevTools session.

    Made by :meth:`HeadlessChromium.open`.

    Parameters
    ----------
    browser : HeadlessChromium
        The browser the tab belongs to (its pipe carries the tab's commands).
    session_id : str
        The DevTools session id of the tab.
    """

    def __init__(self, browser: "HeadlessChromium", session_id: str):
        self.browser, self.session_id = browser, session_id

    def send(self, method: str, params: dict | None = None, timeout: float = 60.0) -> dict:
        """Send one DevTools command to this tab and wait for its reply.

        Parameters
        ----------
        method : str
            The DevTools method, e.g. ``"Page.navigate"``.
        params : dict, optional
            Its parameters.
        timeout : float, default 60.0
            Seconds to wait for the reply.

        Returns
        -------
        dict
            The reply's ``result``.

        Raises
        ------
        BrowserError
            The command failed, timed out, or the browser closed the pipe.
        """
        return self.browser.send(method, params, session_id=self.session_id, timeout=timeout)

    def evaluate(self, expression: str, timeout: float = 60.0):
        """Evaluate a JavaScript expression (awaiting a returned promise) and return its value.

        Parameters
        ----------
        expression : str
            JavaScript source evaluated in the page.
        timeout : float, default 60.0
            Seconds to wait for the result.

        Returns
        -------
        object
            The value, converted from JSON (None for ``undefined``).

        Raises
        ------
        BrowserError
            The expression raised (the message carries its description), or the command failed
            or timed out.
        """
        reply = self.send("Runtime.evaluate", {"expression": expression, "awaitPromise": True,
                                               "returnByValue": True}, timeout=timeout)
        if "exceptionDetails" in reply:
            details = reply["exceptionDetails"]
            text = details.get("exception", {}).get("description") or details.get("text")
            raise BrowserError(f"page script raised: {text}")
        return reply.get("result", {}).get("value")

    def wait_for(self, expression: str, timeout: float = 60.0, poll: float = 0.05):
        """Poll ``expression`` until it is truthy; returns its value.

        Parameters
        ----------
        expression : str
            JavaScript expression evaluated at each poll.
        timeout : float, default 60.0
            Seconds after which polling stops (also the timeout of each evaluation).
        poll : float, default 0.05
            Seconds between polls.

        Returns
        -------
        object
            The first truthy value.

        Raises
        ------
        BrowserError
            Still falsy after ``timeout``, or the expression raised.
        """
        t_end = time.monotonic() + timeout
        while True:
            value = self.evaluate(expression, timeout=timeout)
            if value:
                return value
            if time.monotonic() > t_end:
                raise BrowserError(f"timed out after {timeout} s waiting for {expression!r}")
            time.sleep(poll)


class HeadlessChromium:
    """A headless Chromium process spoken to over ``--remote-debugging-pipe``.

    The process starts with :meth:`start` (or on entering a ``with`` block) and stops with
    :meth:`close` (or on leaving it), in a temporary profile folder.

    Parameters
    ----------
    executable : str, optional
        Path of the browser; by default :func:`find_chromium`.
    extra_flags : tuple of str, default ()
        Command-line flags added after :data:`CHROMIUM_FLAGS` and the WebGL flags.
    webgl : str, default "swiftshader"
        WebGL back end, a key of :data:`WEBGL_BACKENDS` (``"swiftshader"`` or ``"llvmpipe"``).

    Raises
    ------
    BrowserError
        No executable is found, or ``webgl`` is unknown.
    """

    def __init__(self, executable: str | None = None, extra_flags: tuple[str, ...] = (), webgl: str = "swiftshader"):
        self.executable = executable or find_chromium()
        if self.executable is None:
            raise BrowserError("no chromium executable found on PATH")
        if webgl not in WEBGL_BACKENDS:
            raise BrowserError(f"webgl={webgl!r}: expected one of {sorted(WEBGL_BACKENDS)}")
        self.webgl = webgl
        self.extra_flags = tuple(extra_flags)
        self._proc = None
        self._next_id = 0
        self._buffer = b""
        self._profile = None

    # --- process ----------------------------------------------------------------------
    def __enter__(self) -> "HeadlessChromium":
        self.start()
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def start(self) -> None:
        """Launch the browser process (headless, on a fresh temporary profile) and connect the pipes."""
        self._profile = tempfile.TemporaryDirectory(prefix="evotol-chromium-")
        cmd_r, cmd_w = os.pipe()    # we write commands, chromium reads fd 3
        out_r, out_w = os.pipe()    # chromium writes replies on fd 4, we read

        def _child_fds():
            os.dup2(cmd_r, 3)
            os.dup2(out_w, 4)

        gl_flags, gl_env = WEBGL_BACKENDS[self.webgl]
        args = [self.executable, *CHROMIUM_FLAGS, *gl_flags, *self.extra_flags, "--remote-debugging-pipe",
                f"--user-data-dir={self._profile.name}", "about:blank"]
        self._proc = subprocess.Popen(args, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                      stderr=subprocess.DEVNULL, pass_fds=(3, 4), preexec_fn=_child_fds,
                                      env={**os.environ, **gl_env})
        os.close(cmd_r)
        os.close(out_w)
        self._write, self._read = cmd_w, out_r

    def close(self) -> None:
        """Ask the browser to close (killed after 10 s), close the pipes and remove the profile."""
        if self._proc is not None:
            try:
                self.send("Browser.close", timeout=5)
            except (BrowserError, OSError):
                pass
            try:
                self._proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self._proc.kill()
                self._proc.wait()
            for fd in (self._write, self._read):
                try:
                    os.close(fd)
                except OSError:
                    pass
            self._proc = None
        if self._profile is not None:
            self._profile.cleanup()
            self._profile = None

    # --- protocol ---------------------------------------------------------------------
    def send(self, method: str, params: dict | None = None, *, session_id: str | None = None,
             timeout: float = 60.0) -> dict:
        """Send one DevTools command and wait for its reply (events in between are dropped).

        Parameters
        ----------
        method : str
            The DevTools method, e.g. ``"Target.createTarget"``.
        params : dict, optional
            Its parameters.
        session_id : str, optional
            The session of a tab (flat sessions); None sends to the browser.
        timeout : float, default 60.0
            Seconds to wait for the reply.

        Returns
        -------
        dict
            The reply's ``result``.

        Raises
        ------
        BrowserError
            The reply is an error, none came within ``timeout``, or the browser closed the pipe.
        """
        self._next_id += 1
        msg = {"id": self._next_id, "method": method, "params": params or {}}
        if session_id:
            msg["sessionId"] = session_id
        os.write(self._write, json.dumps(msg).encode() + b"\0")
        t_end = time.monotonic() + timeout
        while True:
            while b"\0" in self._buffer:
                raw, self._buffer = self._buffer.split(b"\0", 1)
                reply = json.loads(raw)
                if reply.get("id") == self._next_id:
                    if "error" in reply:
                        raise BrowserError(f"{method}: {reply['error']}")
                    return reply.get("result", {})
            left = t_end - time.monotonic()
            if left <= 0:
                raise BrowserError(f"{method}: no reply within {timeout} s")
            ready, _, _ = select.select([self._read], [], [], left)
            if ready:
                chunk = os.read(self._read, 1 << 20)
                if not chunk:
                    raise BrowserError("chromium closed the DevTools pipe")
                self._buffer += chunk

    def open(self, path_or_url, timeout: float = 120.0) -> Page:
        """Open a file path or URL in a new tab and wait until the document has loaded.

        Parameters
        ----------
        path_or_url : str or Path
            A URL (``http:``, ``https:``, ``file:``, ``about:``, ``data:``) or a file path,
            relative to the working directory or absolute.
        timeout : float, default 120.0
            Seconds to wait for the navigation and for ``document.readyState`` to be
            ``"complete"``.

        Returns
        -------
        Page
            The new tab.

        Raises
        ------
        BrowserError
            A command failed or the page did not load within ``timeout``.
        """
        url = Path(path_or_url).resolve().as_uri() if not str(path_or_url).startswith(("http:", "https:", "file:", "about:", "data:")) else str(path_or_url)
        target = self.send("Target.createTarget", {"url": "about:blank"})["targetId"]
        session = self.send("Target.attachToTarget", {"targetId": target, "flatten": True})["sessionId"]
        page = Page(self, session)
        page.send("Page.enable")
        page.send("Runtime.enable")
        page.send("Page.navigate", {"url": url}, timeout=timeout)
        page.wait_for("document.readyState === 'complete'", timeout=timeout)
        return page
