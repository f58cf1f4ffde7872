"""Remote objects: methods (with overloads), signals and properties by name.

A proxy is built from the object's MetaObject. ``proxy.method(*args)`` blocks and
returns the value; ``proxy.method(*args, _async=True)`` returns a
:class:`~naoloc.backends.naoqi.session.Future`. Overloads are chosen by argument count,
then by how well the arguments fit each parameter signature, like libqi.
"""

from __future__ import annotations

import threading
from typing import TYPE_CHECKING, Any

from naoloc.backends.naoqi.qimessaging.codec import Dynamic, ObjectRef
from naoloc.backends.naoqi.qimessaging.meta import (
    PROPERTY,
    REGISTER_EVENT,
    SET_PROPERTY,
    UNREGISTER_EVENT,
    MetaObject,
    Method,
)
from naoloc.backends.naoqi.qimessaging.signature import Sig, parse
from naoloc.backends.naoqi.session import Future
from naoloc.errors import RobotError

if TYPE_CHECKING:
    from naoloc.backends.naoqi.qimessaging.client import Channel

_U32 = parse("I")


def fit(sig: Sig, value: Any) -> int:
    """How well ``value`` fits ``sig``: 3 exact, 2 converted, 1 dynamic, 0 not at all."""
    kind = sig.kind
    if kind == "m":
        return 1
    if kind == "b":
        return 3 if isinstance(value, bool) else 0
    if kind in "cCwWiIlL":
        if isinstance(value, bool):
            return 1
        return 3 if isinstance(value, int) else 0
    if kind in "fd":
        if isinstance(value, float):
            return 3
        return 2 if isinstance(value, int) and not isinstance(value, bool) else 0
    if kind == "s":
        return 3 if isinstance(value, str) else 0
    if kind == "r":
        return 3 if isinstance(value, bytes | bytearray | memoryview) else 0
    if kind in "[#":
        if not isinstance(value, list | tuple):
            return 0
        return min((fit(sig.items[0], v) for v in value), default=3)
    if kind == "{":
        if not isinstance(value, dict):
            return 0
        pairs = [min(fit(sig.items[0], k), fit(sig.items[1], v)) for k, v in value.items()]
        return min(pairs, default=3)
    if kind == "(":
        if not isinstance(value, list | tuple) or len(value) != len(sig.items):
            return 0
        return min((fit(s, v) for s, v in zip(sig.items, value, strict=True)), default=3)
    if kind == "+":
        return 3 if value is None else fit(sig.items[0], value)
    if kind == "o":
        return 3 if isinstance(value, ObjectRef) else 0
    return 0


def choose(overloads: list[Method], args: tuple[Any, ...], where: str) -> Method:
    """The overload that best fits ``args``.

    Raises:
        RobotError: None takes these arguments (names the signatures).
    """
    best: Method | None = None
    best_score = 0
    for method in overloads:
        params = method.params.items
        if len(params) != len(args):
            continue
        score = min((fit(p, a) for p, a in zip(params, args, strict=True)), default=3)
        if score > best_score:
            best, best_score = method, score
    if best is None:
        shapes = " or ".join(str(m.params) for m in overloads)
        raise RobotError(f"{where}: arguments {_short(args)} do not match {shapes}")
    return best


def _short(args: tuple[Any, ...]) -> str:
    text = repr(args)
    return text if len(text) <= 80 else text[:77] + "..."


class RemoteSignal:
    """A remote signal: ``connect(callback) -> link``, ``disconnect(link)``."""

    def __init__(self, proxy: RemoteObject, uid: int, name: str, sig: Sig) -> None:
        self._proxy, self._uid, self._name, self.signature = proxy, uid, name, sig
        self._lock = threading.Lock()
        self._links: dict[int, Any] = {}

    def connect(self, callback: Any) -> int:
        """Subscribe ``callback(*args)``; returns the link id (for ``disconnect``)."""
        channel = self._proxy._channel
        link = channel.session._new_link(self._uid)
        channel.subscribe(
            self._proxy._service_id, self._proxy._object_id, self._uid, link, callback, self
        )
        args = (self._proxy._service_id, self._uid, link)
        self._proxy._generic(REGISTER_EVENT, "(IIL)", "L", args).value(channel.timeout_ms)
        with self._lock:
            self._links[link] = callback
        return link

    def disconnect(self, link: int) -> bool:
        """Unsubscribe a link; True when it was connected."""
        with self._lock:
            known = self._links.pop(link, None) is not None
        if not known:
            return False
        channel = self._proxy._channel
        channel.unsubscribe(self._proxy._service_id, self._proxy._object_id, self._uid, link)
        args = (self._proxy._service_id, self._uid, link)
        if not channel.closed:
            self._proxy._generic(UNREGISTER_EVENT, "(IIL)", "v", args).wait(channel.timeout_ms)
        return True

    def disconnectAll(self) -> None:
        """Unsubscribe every link made through this proxy."""
        for link in list(self._links):
            self.disconnect(link)


class RemoteProperty(RemoteSignal):
    """A remote property: ``value()``, ``setValue(v)`` and the signal of its changes."""

    def value(self, _async: bool = False) -> Any:
        """The current value."""
        future = self._proxy._generic(PROPERTY, "(m)", "m", (Dynamic(_U32, self._uid),))
        return future if _async else future.value(self._proxy._channel.timeout_ms)

    def setValue(self, value: Any, _async: bool = False) -> Any:
        """Change the value."""
        args = (Dynamic(_U32, self._uid), value)
        future = self._proxy._generic(SET_PROPERTY, "(mm)", "v", args)
        return future if _async else future.value(self._proxy._channel.timeout_ms)


class RemoteObject:
    """A remote object (a service is one); attributes are its methods, signals, properties.

    Args:
        channel: The connection it lives on.
        service: Its service id.
        obj: Its object id (1 for a service).
        meta: Its MetaObject.
        name: For messages (the service name).
    """

    def __init__(self, channel: Channel, service: int, obj: int, meta: MetaObject, name: str):
        self._channel = channel
        self._service_id, self._object_id, self._meta, self._name = service, obj, meta, name
        self._members: dict[str, Any] = {}

    def metaObject(self) -> MetaObject:
        """Its MetaObject."""
        return self._meta

    def _generic(self, uid: int, params: str, returns: str, args: tuple[Any, ...]) -> Future:
        method = Method(uid, "", parse(params), parse(returns))
        return self._channel.call(self._service_id, self._object_id, method, args)

    def call(self, name: str, *args: Any, _async: bool = False) -> Any:
        """Call method ``name`` (the qi ``proxy.call`` shape)."""
        method = getattr(self, name)
        return method(*args, _async=_async)

    def post(self, name: str, *args: Any) -> None:
        """Call method ``name`` without waiting or an answer (a QiMessaging post)."""
        overloads = self._meta.overloads(name)
        if not overloads:
            raise RobotError(f"{self._name} has no method {name!r}")
        method = choose(overloads, args, f"{self._name}.{name}")
        self._channel.post(self._service_id, self._object_id, method, args)

    def __getattr__(self, name: str) -> Any:
        if name.startswith("__"):
            raise AttributeError(name)
        member = self._members.get(name)
        if member is not None:
            return member
        uid = self._meta.property_uid(name)
        if uid is not None:
            member = RemoteProperty(self, uid, name, self._meta.properties[uid][1])
        elif (uid := self._meta.signal(name)) is not None:
            member = RemoteSignal(self, uid, name, self._meta.signals[uid][1])
        else:
            overloads = self._meta.overloads(name)
            if not overloads:
                raise AttributeError(f"{self._name} has no method, signal or property {name!r}")
            member = self._method(name, overloads)
        self._members[name] = member
        return member

    def _method(self, name: str, overloads: list[Method]) -> Any:
        channel, where = self._channel, f"{self._name}.{name}"

        def call(*args: Any, _async: bool = False) -> Any:
            method = overloads[0] if len(overloads) == 1 else choose(overloads, args, where)
            if len(overloads) == 1 and len(method.params.items) != len(args):
                raise RobotError(
                    f"{where} takes {len(method.params.items)} arguments "
                    f"{method.params}, got {len(args)}"
                )
            future = channel.call(self._service_id, self._object_id, method, args, where=where)
            return future if _async else future.value()

        call.__name__ = name
        return call

    def __repr__(self) -> str:
        return f"<naoloc qimessaging proxy {self._name} (service {self._service_id})>"
