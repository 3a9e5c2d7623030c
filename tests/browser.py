"""The one rule for tests that drive a real browser (headless Chromium).

On a machine without Chromium (a newcomer's laptop, a fresh venv) these tests are skipped with a
reason that says how to enable them. CI must not skip them: ``.ci/run`` installs Chromium and sets
``EVOTOL_REQUIRE_BROWSER=1``, and then a missing browser is a failure, not a skip.
"""
from __future__ import annotations

import os

import pytest

from evotol.reporting.headless import find_chromium

REQUIRE_ENV = "EVOTOL_REQUIRE_BROWSER"


def require_chromium() -> str:
    """Path of Chromium; skip (or fail when ``EVOTOL_REQUIRE_BROWSER=1``) when there is none."""
    path = find_chromium()
    if path is None:
        msg = ("headless Chromium not found: install it (Debian/Ubuntu: apt-get install chromium) "
               f"to run the browser tests; CI sets {REQUIRE_ENV}=1 to make them mandatory")
        if os.environ.get(REQUIRE_ENV, "") not in ("", "0"):
            pytest.fail(msg)
        pytest.skip(msg)
    return path
