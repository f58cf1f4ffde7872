"""The libqi transport: the real ``qi`` package (NAOqi's own wire protocol).

Only this module imports ``qi``, and only when the libqi transport is chosen. It
makes client sessions (with the NAOqi 2.9+ login when a user is given) and turns a
served object into a qi-bound object whose methods carry the typed signatures of
:mod:`.signatures`, so that any NAOqi client sees typed methods and receives image
buffers as binary.
"""

from __future__ import annotations

from typing import Any

from naoloc.backends.naoqi.session import QI_INSTALL_HINT
from naoloc.backends.naoqi.signatures import SERVICES

from naoloc.errors import DependencyNotInstalled, NaolocError

LIBQI_CALLER = "libqi"


def import_qi() -> Any:
    """Import and return the ``qi`` module.

    Raises:
        DependencyNotInstalled: qi is not installed (names the pip command).
    """
    try:
        import qi
    except ImportError:
        raise DependencyNotInstalled(QI_INSTALL_HINT) from None
    # libqi logs "No Application was created" and every service registration; naoloc
    # reports problems itself, so keep libqi's own log to errors.
    qi.logging.setLevel(qi.logging.ERROR)
    return qi


def new_session() -> Any:
    """A new, unconnected ``qi.Session``."""
    return import_qi().Session()


class _Authenticator:
    """NAOqi 2.9+ client login: the data sent on connection."""

    def __init__(self, user: str, password: str) -> None:
        self._user, self._password = user, password

    def initialAuthData(self) -> dict[str, str]:
        return {"user": self._user, "token": self._password}


class _AuthenticatorFactory:
    def __init__(self, user: str, password: str) -> None:
        self._user, self._password = user, password

    def newAuthenticator(self) -> _Authenticator:
        return _Authenticator(self._user, self._password)


def set_login(session: Any, user: str, password: str) -> None:
    """Make ``session`` log in as ``user`` (NAOqi 2.9+ over tcps://)."""
    session.setClientAuthenticatorFactory(_AuthenticatorFactory(user, password))


def bind_service(name: str, target: Any) -> Any:
    """A qi-bound object serving ``SERVICES[name]`` by forwarding to ``target.invoke``.

    Args:
        name: Service name, a key of :data:`~.signatures.SERVICES`.
        target: An object with ``invoke(caller, method, args)``; its naoloc errors are
            re-raised as ``RuntimeError("<ErrorType>: <message>")`` so that clients can
            map them back.

    Returns:
        An instance ready for ``qi.Session.registerService``.
    """
    qi = import_qi()
    namespace: dict[str, Any] = {"__doc__": f"naoloc virtual {name}"}
    for method, overloads in SERVICES[name].items():
        for k, overload in enumerate(overloads):
            namespace[f"{method}__{k}"] = qi.bind(
                overload.returns, list(overload.params), methodName=method
            )(_forwarder(target, method, overload.returns))
    cls = type(f"Qi{name}", (), namespace)
    return cls()


def _forwarder(target: Any, method: str, returns: str) -> Any:
    as_tuple = returns.startswith("(")

    def call(self: Any, *args: Any) -> Any:
        try:
            value = target.invoke(LIBQI_CALLER, method, list(args))
        except NaolocError as err:
            raise RuntimeError(f"{type(err).__name__}: {err}") from None
        return tuple(value) if as_tuple else value

    call.__name__ = method
    return call
