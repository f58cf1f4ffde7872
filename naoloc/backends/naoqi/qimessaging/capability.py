"""The capability map exchanged at connection, and the login (NAOqi 2.9+).

The client calls ``authenticate`` (service 0, object 0, action 8) with a ``{sm}`` map
of the protocol features it supports plus, for a login, ``auth_user`` and
``auth_token``; the server answers its own features and ``__qi_auth_state``:
1 refused (``__qi_auth_err_reason``), 2 continue, 3 done.
"""

from __future__ import annotations

import hmac
from typing import Any, Final

from naoloc.backends.naoqi.qimessaging.codec import Dynamic
from naoloc.backends.naoqi.qimessaging.signature import parse
from naoloc.errors import ProtocolError

STATE_KEY: Final = "__qi_auth_state"
REASON_KEY: Final = "__qi_auth_err_reason"
NEW_TOKEN_KEY: Final = "auth_newToken"
STATE_ERROR: Final = 1
STATE_CONTINUE: Final = 2
STATE_DONE: Final = 3

# What naoloc supports: no MetaObject cache (objects always carry their MetaObject),
# object uids, cancellable calls, relative endpoints ("qi:<service>" = this socket).
LOCAL: Final[dict[str, bool]] = {
    "ClientServerSocket": True,
    "MessageFlags": True,
    "MetaObjectCache": False,
    "ObjectPtrUID": True,
    "RelativeEndpointURI": True,
    "RemoteCancelableCalls": True,
}


def client_request(user: str | None = None, token: str | None = None) -> dict[str, Any]:
    """The map a client sends to ``authenticate`` (with a login when ``user`` is given)."""
    request: dict[str, Any] = dict(LOCAL)
    if user:
        request["auth_user"] = user
        request["auth_token"] = token or ""
    return request


def negotiated(peer: dict[str, Any]) -> dict[str, bool]:
    """The features both sides support (a missing key means unsupported)."""
    return {key: bool(mine and peer.get(key) is True) for key, mine in LOCAL.items()}


def server_reply(request: Any, state: int = STATE_DONE, reason: str = "") -> dict[str, Any]:
    """The map a server answers ``authenticate`` with (state as a u32, like libqi)."""
    peer = request if isinstance(request, dict) else {}
    reply: dict[str, Any] = dict(negotiated(peer))
    reply[STATE_KEY] = Dynamic(parse("I"), state)
    if reason:
        reply[REASON_KEY] = reason
    return reply


def check_reply(reply: Any) -> dict[str, bool]:
    """Read the server's answer; return the negotiated features.

    Raises:
        ProtocolError: The login was refused (with the server's reason), more steps
            were asked for, or the answer is malformed.
    """
    if not isinstance(reply, dict):
        raise ProtocolError("the authentication reply is not a capability map")
    state = reply.get(STATE_KEY)
    if state == STATE_DONE:
        return negotiated(reply)
    if state == STATE_ERROR:
        reason = reply.get(REASON_KEY) or "no reason given"
        raise ProtocolError(f"authentication refused: {reason}")
    if state == STATE_CONTINUE:
        if NEW_TOKEN_KEY in reply:
            raise ProtocolError(
                "the robot asks to set a new password first (NAOqi 2.9 first login): "
                "set one with the robot's web page or Choregraphe, then use it"
            )
        raise ProtocolError("authentication needs more steps than user and password")
    raise ProtocolError(f"authentication reply has no valid {STATE_KEY} ({state!r})")


def login_ok(users: dict[str, str], request: dict[str, Any]) -> bool:
    """True when a login request's user and token match ``users`` (constant-time compare)."""
    user, token = request.get("auth_user"), request.get("auth_token")
    if not isinstance(user, str) or not isinstance(token, str):
        return False
    expected = users.get(user)
    match = hmac.compare_digest(token.encode(), (expected or "\0").encode())
    return expected is not None and match
