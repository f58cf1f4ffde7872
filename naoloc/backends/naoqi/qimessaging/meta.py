"""MetaObject (an object's methods, signals and properties) and ServiceInfo.

Every object answers the same generic actions (0-8); its own methods start at 100.
A MetaObject travels as the tuple ``(methods, signals, properties, description)``
with ``methods = {uid: (uid, returnSignature, name, parametersSignature,
description, parameters, returnDescription)}``, ``signals = {uid: (uid, name,
signature)}`` and ``properties`` like signals.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any, Final

from naoloc.backends.naoqi.qimessaging.codec import METAOBJECT_SIGNATURE
from naoloc.backends.naoqi.qimessaging.signature import Sig, parse
from naoloc.errors import BackendError, ProtocolError

REGISTER_EVENT: Final = 0
UNREGISTER_EVENT: Final = 1
META_OBJECT: Final = 2
TERMINATE: Final = 3
PROPERTY: Final = 5
SET_PROPERTY: Final = 6
PROPERTIES: Final = 7
REGISTER_EVENT_WITH_SIGNATURE: Final = 8
FIRST_USER_ACTION: Final = 100

SERVICE_INFO_SIGNATURE: Final = (
    "(sIsI[s]ss)<ServiceInfo,name,serviceId,machineId,processId,endpoints,sessionId,objectUid>"
)
SERVICE_INFO_FIELDS: Final = (
    "name", "serviceId", "machineId", "processId", "endpoints", "sessionId", "objectUid",
)  # fmt: skip

# The generic methods every object answers: uid -> (name, params, returns).
GENERIC_METHODS: Final = {
    REGISTER_EVENT: ("registerEvent", "(IIL)", "L"),
    UNREGISTER_EVENT: ("unregisterEvent", "(IIL)", "v"),
    META_OBJECT: ("metaObject", "(I)", METAOBJECT_SIGNATURE),
    TERMINATE: ("terminate", "(I)", "v"),
    PROPERTY: ("property", "(m)", "m"),
    SET_PROPERTY: ("setProperty", "(mm)", "v"),
    PROPERTIES: ("properties", "()", "[s]"),
    REGISTER_EVENT_WITH_SIGNATURE: ("registerEventWithSignature", "(IILs)", "L"),
}


@dataclass(frozen=True)
class Method:
    """One method overload.

    Attributes:
        uid: Its action id.
        name: Method name.
        params: Parameter tuple signature, e.g. ``(ddd)``.
        returns: Return signature.
    """

    uid: int
    name: str
    params: Sig
    returns: Sig


@dataclass
class MetaObject:
    """An object's interface, looked up by name or action id.

    Attributes:
        methods: uid -> method.
        signals: uid -> (name, signature).
        properties: uid -> (name, signature).
        description: Free text.
    """

    methods: dict[int, Method] = field(default_factory=dict)
    signals: dict[int, tuple[str, Sig]] = field(default_factory=dict)
    properties: dict[int, tuple[str, Sig]] = field(default_factory=dict)
    description: str = ""

    def overloads(self, name: str) -> list[Method]:
        """The methods called ``name`` (several when overloaded)."""
        return [m for m in self.methods.values() if m.name == name]

    def signal(self, name: str) -> int | None:
        """The uid of signal ``name``, or None."""
        return next((uid for uid, (n, _) in self.signals.items() if n == name), None)

    def property_uid(self, name: str) -> int | None:
        """The uid of property ``name``, or None."""
        return next((uid for uid, (n, _) in self.properties.items() if n == name), None)

    def to_wire(self) -> tuple[Any, ...]:
        """The MetaObject tuple as it is serialized."""
        methods: dict[int, tuple[Any, ...]] = {
            m.uid: (m.uid, str(m.returns), m.name, str(m.params), "", [], "")
            for m in self.methods.values()
        }
        signals = {uid: (uid, n, str(s)) for uid, (n, s) in self.signals.items()}
        props = {uid: (uid, n, str(s)) for uid, (n, s) in self.properties.items()}
        return (methods, signals, props, self.description)

    @classmethod
    def from_wire(cls, value: Any) -> MetaObject:
        """Read a decoded MetaObject tuple.

        Raises:
            ProtocolError: Malformed entries or signatures.
        """
        try:
            methods_raw, signals_raw, props_raw, description = value
            meta = cls(description=str(description))
            for uid, entry in methods_raw.items():
                returns, name, params = entry[1], entry[2], entry[3]
                params_sig = parse(str(params))
                if params_sig.kind != "(":
                    params_sig = Sig("(", (params_sig,))
                meta.methods[int(uid)] = Method(
                    int(uid), str(name), params_sig, parse(str(returns))
                )
            for uid, entry in signals_raw.items():
                meta.signals[int(uid)] = (str(entry[1]), parse(str(entry[2])))
            for uid, entry in props_raw.items():
                meta.properties[int(uid)] = (str(entry[1]), parse(str(entry[2])))
        except (TypeError, ValueError, IndexError, AttributeError) as err:
            raise ProtocolError(f"malformed MetaObject: {err}") from None
        return meta


def build(
    methods: Iterable[tuple[str, str, str]],
    *,
    signals: Iterable[tuple[str, str]] = (),
    properties: Iterable[tuple[str, str]] = (),
    description: str = "",
) -> MetaObject:
    """A MetaObject with the generic methods plus ``methods`` numbered from 100.

    Args:
        methods: ``(name, params tuple signature, return signature)`` in order.
        signals: ``(name, tuple signature)``.
        properties: ``(name, signature)``; each is also a signal of the same uid.
        description: Free text.
    """
    meta = MetaObject(description=description)
    for uid, (name, params, returns) in GENERIC_METHODS.items():
        meta.methods[uid] = Method(uid, name, parse(params), parse(returns))
    uid = FIRST_USER_ACTION
    for name, params, returns in methods:
        meta.methods[uid] = Method(uid, name, parse(params), parse(returns))
        uid += 1
    for name, sig in signals:
        meta.signals[uid] = (name, parse(sig))
        uid += 1
    for name, sig in properties:
        meta.properties[uid] = (name, parse(sig))
        meta.signals[uid] = (name, parse(f"({sig})"))
        uid += 1
    return meta


def describe(target: Any) -> tuple[list[tuple[str, str, str]], dict[str, str]]:
    """The methods and signals of a Python object to serve.

    Methods are those marked by ``naoloc.qi.bind`` (a ``_qi_signature`` of ``(name,
    params, returns)``); signals are attributes with ``connect`` and ``disconnect``
    (a ``signature`` attribute gives their type, else ``(m)``).

    Returns:
        ``([(name, params tuple signature, return signature)], {signal: signature})``.
    """
    methods: list[tuple[str, str, str]] = []
    signals: dict[str, str] = {}
    for attr in dir(target):
        if attr.startswith("_"):
            continue
        member = getattr(target, attr)
        declared = getattr(member, "_qi_signature", None)
        if declared is not None:
            name, params, returns = declared
            methods.append((str(name), "(" + "".join(params) + ")", str(returns)))
        elif callable(getattr(member, "connect", None)) and callable(
            getattr(member, "disconnect", None)
        ):
            signals[attr] = str(getattr(member, "signature", "(m)"))
    return methods, signals


def service_info_dict(value: Any) -> dict[str, Any]:
    """A decoded ServiceInfo tuple as the dict qi.Session.services() gives.

    Raises:
        ProtocolError: Not a 6- or 7-member ServiceInfo.
    """
    if not isinstance(value, tuple | list) or len(value) not in (6, 7):
        raise ProtocolError("malformed ServiceInfo")
    info = dict(zip(SERVICE_INFO_FIELDS, value, strict=False))
    info.setdefault("objectUid", "")
    return info


def signature_table(name: str) -> list[tuple[str, str, str]]:
    """``(method, params, returns)`` of every overload naoloc serves for service ``name``.

    Raises:
        BackendError: No signatures are known for ``name``.
    """
    from naoloc.backends.naoqi.signatures import SERVICES

    if name not in SERVICES:
        raise BackendError(f"no signatures for service {name!r}; pass methods=[...]")
    return [
        (method, "(" + "".join(o.params) + ")", o.returns)
        for method, overloads in SERVICES[name].items()
        for o in overloads
    ]
