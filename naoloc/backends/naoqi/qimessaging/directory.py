"""The service directory's interface and the services clients register with it.

As on a NAO, a client may register a service of its own (an old-SDK ALBroker's modules,
NaolocLocalization from another process): the directory lists it with the endpoints the
client gave, and other clients call it there. :class:`ClientServices` keeps those
registrations, each owned by the client that made it, within :data:`MAX_CLIENT_SERVICES`
in all and :data:`MAX_SERVICES_PER_CLIENT` per client, so that a client's services can
be dropped when it leaves.
"""

from __future__ import annotations

from typing import Any, Final

from naoloc.backends.naoqi.qimessaging.meta import SERVICE_INFO_SIGNATURE, MetaObject, Method, build
from naoloc.backends.naoqi.qimessaging.signature import parse

MAX_CLIENT_SERVICES: Final = 32  # services registered by clients, all together
MAX_SERVICES_PER_CLIENT: Final = 16  # services one client registers (as a relayed libqi one)


def directory_meta() -> MetaObject:
    """The ServiceDirectory's MetaObject (libqi's action and signal ids)."""
    info = SERVICE_INFO_SIGNATURE
    meta = build([])
    for uid, name, params, returns in (
        (100, "service", "(s)", info),
        (101, "services", "()", f"[{info}]"),
        (102, "registerService", f"({info})", "I"),
        (103, "unregisterService", "(I)", "v"),
        (104, "serviceReady", "(I)", "v"),
        (105, "updateServiceInfo", f"({info})", "v"),
        (108, "machineId", "()", "s"),
    ):
        meta.methods[uid] = Method(uid, name, parse(params), parse(returns))
    meta.signals[106] = ("serviceAdded", parse("(Is)"))
    meta.signals[107] = ("serviceRemoved", parse("(Is)"))
    return meta


class ClientServices:
    """Services registered by clients: ServiceInfo tuples by service id, with their owner.

    Not locked: the server calls it while holding its own lock.

    Args:
        total: Most services all clients may hold together.
        each: Most services one client may hold.
    """

    def __init__(self, total: int = MAX_CLIENT_SERVICES, each: int = MAX_SERVICES_PER_CLIENT):
        self._total = total
        self._each = each
        self._infos: dict[int, tuple[Any, ...]] = {}
        self._owners: dict[int, str] = {}

    def __contains__(self, service_id: object) -> bool:
        return service_id in self._infos

    def find(self, name: str) -> tuple[Any, ...] | None:
        """The ServiceInfo of the client service called ``name``, or None."""
        return next((i for i in self._infos.values() if i[0] == name), None)

    def infos(self) -> list[tuple[Any, ...]]:
        """Every client service's ServiceInfo."""
        return list(self._infos.values())

    def refusal(self, owner: str) -> str:
        """Why ``owner`` may not register one more service ("" = it may)."""
        if len(self._infos) >= self._total:
            return f"at most {self._total} client services"
        if sum(1 for o in self._owners.values() if o == owner) >= self._each:
            return f"at most {self._each} services per client"
        return ""

    def add(self, owner: str, service_id: int, info: tuple[Any, ...]) -> None:
        """List ``info`` (its id replaced by ``service_id``) as ``owner``'s."""
        self._infos[service_id] = (info[0], service_id, *info[2:])
        self._owners[service_id] = owner

    def pop(self, service_id: int) -> tuple[Any, ...] | None:
        """Drop one service; its ServiceInfo, or None when it was not listed."""
        self._owners.pop(service_id, None)
        return self._infos.pop(service_id, None)

    def of(self, owner: str) -> list[int]:
        """The ids of ``owner``'s services."""
        return [s for s, o in self._owners.items() if o == owner]
