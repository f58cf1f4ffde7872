"""Whom a client trusts over ``tcps://``: how the robot's TLS certificate is checked.

NAOqi 2.9 robots present self-signed certificates and libqi accepts any, so the
password travels to whoever answers. A naoloc client checks the certificate first,
one of four ways (``robot.tls_trust`` / ``naoloc.qi.Session(tls_trust=...)``):

- ``None`` (default): trust on first use. The certificate's SHA-256 fingerprint is
  kept per ``host:port`` in a known-robots file (``$XDG_CONFIG_HOME/naoloc/
  known_robots``, else ``~/.config/naoloc/known_robots``); the first connection pins
  it (one line on stderr says so), later ones must present the same certificate.
- ``"sha256:<hex>"``: that fingerprint only.
- a path to a PEM file: a CA bundle, or the robot's own certificate; the chain must
  verify against it (host names are not checked: robots are reached by address).
- ``"insecure"``: any certificate. Anyone on the network path can then read the
  password and drive the robot; a line on stderr says so at every connection.
"""

from __future__ import annotations

import hashlib
import os
import ssl
import stat
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Final

from naoloc.errors import BackendError, ConnectionLost

INSECURE: Final = "insecure"
MAX_KNOWN_BYTES: Final = 1024 * 1024  # a known-robots file larger than this is refused
_PREFIX: Final = "sha256:"


@dataclass(frozen=True)
class Trust:
    """How to check a server's certificate (see the module docstring).

    Attributes:
        pin: Expected SHA-256 fingerprint (hex), or None.
        ca_file: PEM file the chain must verify against, or None.
        known: Known-robots file for trust on first use, or None.
        insecure: Accept any certificate.
    """

    pin: str | None = None
    ca_file: str | None = None
    known: str | None = None
    insecure: bool = False


def default_known_file() -> str:
    """The known-robots file: under ``$XDG_CONFIG_HOME`` or ``~/.config``."""
    base = os.environ.get("XDG_CONFIG_HOME") or os.path.join(os.path.expanduser("~"), ".config")
    return os.path.join(base, "naoloc", "known_robots")


def parse_trust(text: str | None) -> Trust:
    """Read a ``tls_trust`` setting.

    Raises:
        BackendError: A malformed fingerprint, or a PEM path that is not a file.
    """
    if text is None or text == "":
        return Trust(known=default_known_file())
    if text == INSECURE:
        return Trust(insecure=True)
    if text.lower().startswith(_PREFIX):
        digest = text[len(_PREFIX) :].replace(":", "").lower()
        if len(digest) != 64 or any(c not in "0123456789abcdef" for c in digest):
            raise BackendError(f"tls_trust: {text[:80]!r} is not sha256:<64 hex digits>")
        return Trust(pin=digest)
    if not Path(text).is_file():
        raise BackendError(
            f"tls_trust: {text[:200]} is not a file (give a CA or certificate PEM, "
            "sha256:<fingerprint>, or insecure)"
        )
    return Trust(ca_file=text)


def context(trust: Trust) -> ssl.SSLContext:
    """The client's TLS context: chain verification only with a CA file."""
    ctx = ssl.SSLContext(ssl.PROTOCOL_TLS_CLIENT)
    ctx.check_hostname = False
    if trust.ca_file:
        ctx.verify_mode = ssl.CERT_REQUIRED
        try:
            ctx.load_verify_locations(cafile=trust.ca_file)
        except (OSError, ssl.SSLError) as err:
            raise BackendError(f"tls_trust: cannot read {trust.ca_file}: {err}") from None
    else:
        ctx.verify_mode = ssl.CERT_NONE
    return ctx


def fingerprint(der: bytes) -> str:
    """SHA-256 of a DER certificate, hex."""
    return hashlib.sha256(der).hexdigest()


def check(trust: Trust, where: str, der: bytes) -> None:
    """Accept or refuse the certificate ``der`` that ``where`` (host:port) presented.

    Raises:
        ConnectionLost: One line: the certificate does not match, or none was sent.
    """
    if trust.insecure:
        print(
            f"naoloc: the TLS certificate of {where} is NOT verified (tls_trust: insecure): "
            "anyone on the network path can read the password and drive the robot",
            file=sys.stderr,
            flush=True,
        )
        return
    if trust.ca_file:
        return  # the handshake verified the chain
    if not der:
        raise ConnectionLost(f"{where} sent no TLS certificate")
    seen = fingerprint(der)
    if trust.pin is not None:
        if seen != trust.pin:
            raise ConnectionLost(
                f"the TLS certificate of {where} is sha256:{seen}, not the pinned "
                f"sha256:{trust.pin}: refusing to send the login"
            )
        return
    if trust.known:
        _check_known(Path(trust.known), where, seen)


def _read_known(path: Path) -> dict[str, str]:
    try:
        info = path.stat()
    except FileNotFoundError:
        return {}
    except OSError as err:
        raise ConnectionLost(f"cannot read {path}: {err.strerror or err}") from None
    if not stat.S_ISREG(info.st_mode):
        raise ConnectionLost(f"{path} is not a regular file")
    if info.st_size > MAX_KNOWN_BYTES:
        raise ConnectionLost(f"{path} is over {MAX_KNOWN_BYTES} bytes")
    known: dict[str, str] = {}
    with path.open("r", encoding="utf-8", errors="replace") as handle:
        for line in handle.read(MAX_KNOWN_BYTES).splitlines():
            parts = line.split()
            if len(parts) == 2 and parts[1].startswith(_PREFIX):
                known[parts[0]] = parts[1][len(_PREFIX) :]
    return known


def _check_known(path: Path, where: str, seen: str) -> None:
    known = _read_known(path)
    pinned = known.get(where)
    if pinned == seen:
        return
    if pinned is not None:
        raise ConnectionLost(
            f"the TLS certificate of {where} changed (now sha256:{seen}, pinned "
            f"sha256:{pinned} in {path}): refusing to send the login; if the robot was "
            "re-flashed, delete its line there"
        )
    try:
        path.parent.mkdir(parents=True, exist_ok=True, mode=0o700)
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_APPEND | os.O_NOFOLLOW, 0o600)
        with os.fdopen(fd, "a", encoding="utf-8") as handle:
            handle.write(f"{where} {_PREFIX}{seen}\n")
    except OSError as err:
        raise ConnectionLost(f"cannot pin the certificate of {where} in {path}: {err}") from None
    print(
        f"naoloc: pinned the TLS certificate of {where} (sha256:{seen}) in {path}",
        file=sys.stderr,
        flush=True,
    )
