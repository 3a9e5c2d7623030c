"""Command-line argument types and checks that answer at once, before any study starts.

argparse calls the ``type=`` functions while parsing; an ``argparse.ArgumentTypeError`` becomes
the one-line ``evotol run: error: argument --seed: ...`` with exit code 2. The scheduler check
connects as a Dask client with a short timeout, so a wrong or dead address is reported in a few
seconds instead of a 60 s wait ending in a TimeoutError (issue 15).
"""
from __future__ import annotations

import argparse
from urllib.parse import urlsplit

from evotol.errors import ValidationError

#: Dask/distributed address schemes we can check with a plain TCP connection.
SCHEDULER_SCHEMES = ("tcp", "tls", "ws", "wss")
#: seconds to wait for a scheduler to accept a connection
SCHEDULER_TIMEOUT_S = 3.0


def seed(text: str) -> int:
    """``--seed``: a non-negative integer (NumPy and pymoo seeds must be >= 0).

    Parameters
    ----------
    text : str
        The option's value, in base 10.

    Returns
    -------
    int
        The seed, ``0 <= seed < 2**32``.

    Raises
    ------
    argparse.ArgumentTypeError
        ``text`` is not a base-10 integer, or is negative or ``>= 2**32``.
    """
    try:
        value = int(text, 10)
    except (TypeError, ValueError):
        value = None
    if value is None or value < 0 or value >= 2 ** 32:
        raise argparse.ArgumentTypeError(f"expected a non-negative integer below 2**32, got {text!r}")
    return value


def jobs(text: str) -> int:
    """``--jobs``: a positive integer (studies at the same time).

    Parameters
    ----------
    text : str
        The option's value, in base 10.

    Returns
    -------
    int
        The number of studies run at the same time, ``>= 1``.

    Raises
    ------
    argparse.ArgumentTypeError
        ``text`` is not a base-10 integer, or is below 1.
    """
    try:
        value = int(text, 10)
    except (TypeError, ValueError):
        value = None
    if value is None or value < 1:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}")
    return value


def parse_scheduler(address: str) -> tuple[str, str, int]:
    """Split ``tcp://host:port`` into (scheme, host, port); ValidationError on any other form.

    Parameters
    ----------
    address : str
        The scheduler address (surrounding blanks ignored); scheme one of ``SCHEDULER_SCHEMES``.

    Returns
    -------
    tuple of (str, str, int)
        The scheme, the host name and the port.

    Raises
    ------
    ValidationError
        ``address`` is not a string, has another scheme, no host, no valid port, or a path.
    """
    expected = f"an address of the form tcp://host:port (schemes: {', '.join(SCHEDULER_SCHEMES)})"
    parts = urlsplit(address.strip()) if isinstance(address, str) else None
    if parts is None or parts.scheme not in SCHEDULER_SCHEMES or not parts.hostname:
        raise ValidationError("--scheduler", address, expected)
    try:
        port = parts.port
    except ValueError:
        port = None
    if port is None or parts.path not in ("", "/"):
        raise ValidationError("--scheduler", address, expected)
    return parts.scheme, parts.hostname, port


def scheduler(text: str) -> str:
    """argparse type of ``--scheduler``: checks the address form only (no network).

    Parameters
    ----------
    text : str
        The option's value.

    Returns
    -------
    str
        ``text`` unchanged.

    Raises
    ------
    argparse.ArgumentTypeError
        ``text`` is not of the form :func:`parse_scheduler` accepts (its message).
    """
    try:
        parse_scheduler(text)
    except ValidationError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    return text


async def _identity(address: str, timeout: float) -> dict:
    """Ask the server at ``address`` who it is (Dask's ``identity`` handler, after the handshake)."""
    import asyncio

    from distributed.comm import connect

    comm = await connect(address, timeout=timeout)
    try:
        await comm.write({"op": "identity", "reply": True})
        return await asyncio.wait_for(comm.read(), timeout)
    finally:
        comm.abort()


def check_scheduler_answers(address: str, timeout: float = SCHEDULER_TIMEOUT_S) -> None:
    """ValidationError naming the address unless a Dask *scheduler* answers within ``timeout`` s.

    A bare TCP connect is not enough (a firewall or proxy may accept any connection), so this
    performs Dask's handshake and asks the server's identity, then disconnects.

    Parameters
    ----------
    address : str
        The scheduler address, ``tcp://host:port``.
    timeout : float, optional
        Seconds to wait for the connection and the answer (default ``SCHEDULER_TIMEOUT_S`` = 3 s).

    Raises
    ------
    ValidationError
        The address has a bad form (:func:`parse_scheduler`); ``distributed`` is not installed;
        nothing answering Dask's protocol is there within ``timeout``; or the server that answers
        is not a Dask scheduler (e.g. a worker).
    """
    import asyncio

    _, host, port = parse_scheduler(address)
    try:
        import distributed  # noqa: F401
    except ImportError:
        raise ValidationError("--scheduler", address, "dask.distributed installed (pip install distributed)") from None
    try:
        ident = asyncio.run(_identity(address, timeout))
    except Exception as exc:  # noqa: BLE001 -- whatever answered (or nothing did), it is not a usable scheduler
        reason = (" ".join(str(exc).split())[:120] if isinstance(exc, OSError)
                  else "the server there does not speak Dask's protocol")
        raise ValidationError("--scheduler", address,
                              f"a Dask scheduler answering at {host}:{port} within {timeout:g} s ({reason})") from None
    if not isinstance(ident, dict) or ident.get("type") != "Scheduler":
        raise ValidationError("--scheduler", address, f"a Dask scheduler; the server at {host}:{port} "
                                                      f"is {ident.get('type') if isinstance(ident, dict) else ident!r}")
