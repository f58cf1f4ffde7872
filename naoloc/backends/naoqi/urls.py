"""Listen and connect URLs (``tcp://HOST:PORT``, ``tcps://HOST:PORT``): one parser for all.

``naoloc serve --listen``, the naoqi client (``robot.url``) and the zmq transport parse
their URLs here, so a typo is one line naming the problem, never a traceback, and a port
out of range is refused instead of wrapping around (zmq binds ``:99999`` as ``:34463``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Final
from urllib.parse import urlsplit

from naoloc.errors import UrlError

SCHEMES: Final = ("tcp", "tcps")
MAX_URL_LEN: Final = 256


@dataclass(frozen=True, slots=True)
class Url:
    """A parsed network URL.

    Attributes:
        scheme: ``tcp`` or ``tcps``.
        host: Host name or IP address (IPv6 without brackets).
        port: TCP port, 0-65535 (0 = any free port, for listening only).
    """

    scheme: str
    host: str
    port: int

    def __str__(self) -> str:
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"{self.scheme}://{host}:{self.port}"


def _short(text: str) -> str:
    return repr(text if len(text) <= 60 else text[:57] + "...")


def parse_url(
    text: str,
    *,
    what: str = "URL",
    schemes: tuple[str, ...] = SCHEMES,
    allow_any_port: bool = True,
    default_port: int | None = None,
) -> Url:
    """Parse and validate ``scheme://host:port``.

    Args:
        text: The URL.
        what: What the URL is, for the error message (e.g. ``--listen``, ``robot.url``).
        schemes: Accepted schemes.
        allow_any_port: Accept port 0 (listen on any free port); False for clients.
        default_port: The port of a URL that names none (None = a port is required).

    Returns:
        The parsed URL.

    Raises:
        UrlError: One line naming ``what`` and the problem.
    """
    if not isinstance(text, str) or not text:
        raise UrlError(f"{what}: empty URL; expected {schemes[0]}://HOST:PORT")
    if len(text) > MAX_URL_LEN:
        raise UrlError(f"{what}: URL too long ({len(text)} chars, at most {MAX_URL_LEN})")
    if any(ord(c) < 33 or ord(c) == 127 for c in text):
        raise UrlError(f"{what}: URL {_short(text)} holds spaces or control characters")
    try:
        parts = urlsplit(text)
        host = parts.hostname
        port = parts.port
    except ValueError as err:
        problem = "bad port in" if "Port" in str(err) else "bad URL"
        raise UrlError(f"{what}: {problem} {_short(text)}: {err}") from None
    expected = f"expected {schemes[0]}://HOST:PORT"
    if parts.scheme not in schemes:
        got = parts.scheme or "none"
        raise UrlError(f"{what}: scheme {got!r} of {_short(text)}; {expected}")
    if parts.path not in ("", "/") or parts.query or parts.fragment:
        raise UrlError(f"{what}: {_short(text)} has a path or query; {expected}")
    if not host:
        raise UrlError(f"{what}: {_short(text)} names no host; {expected}")
    if port is None and default_port is not None:
        port = default_port
    if port is None:
        raise UrlError(f"{what}: {_short(text)} names no port; {expected}")
    if port == 0 and not allow_any_port:
        raise UrlError(f"{what}: port 0 of {_short(text)} is only for listening")
    return Url(parts.scheme, host, port)
