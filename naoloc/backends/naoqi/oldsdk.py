"""The old NAOqi Python SDK (``from naoqi import ALProxy``) on Python 3, over naoloc.qi.

Aldebaran's ``naoqi`` module exists only for Python 2.7. This is its API on naoloc.qi
(pure Python, no libqi), against a real NAO or ``naoloc serve``:

- ``ALProxy(name, ip, port)`` (or ``ALProxy(name)`` through the script's ALBroker):
  every method of the service; ``proxy.post.method(...)`` and ``proxy.pCall("method",
  ...)`` start it in the background and return a task id; ``wait(id, ms)`` (0 = until
  it ends), ``isRunning(id)`` and ``stop(id)``.
- ``ALBroker(name, ip, port, parentIp, parentPort)``: the script's connection to the
  robot. It serves the script's modules on the address that reaches the robot
  (loopback for a robot on this machine) at ``port`` (0 = any free port), whatever
  ``ip`` says.
- ``ALModule`` subclasses: their public methods are served under the module's name
  (``ALProxy("MyModule")`` from another script reaches them), and ALMemory's
  ``subscribeToEvent(event, "MyModule", "onEvent")`` calls ``onEvent(eventName, value,
  subscriberIdentifier)`` back, with as many of these as the method takes.

Events reach modules through ALMemory's subscriber signal; where the transport has no
signals (``naoloc serve --transport zmq``) ALMemory is polled every
:data:`POLL_S` seconds instead, so a value raised twice in a row is seen once. The
SDK's process-wide broker registry is one :class:`_Runtime` per process, as in the SDK.
"""

from __future__ import annotations

import contextlib
import inspect
import itertools
import os
import sys
import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Final

from naoloc.backends.naoqi import qi

DEFAULT_URL_ENV: Final = "NAOLOC_NAOQI_URL"  # where ALProxy(name) goes without a broker
DEFAULT_URL: Final = "tcp://127.0.0.1:9559"
POLL_S: Final = 0.05
_LOCAL_TASK_IDS: Final = 1 << 24  # ids of calls posted here; the robot's are smaller
_MEMORY_EVENT_METHODS: Final = frozenset(
    {"subscribeToEvent", "unsubscribeToEvent", "subscribeToMicroEvent", "unsubscribeToMicroEvent"}
)

__all__ = ["ALBroker", "ALModule", "ALProxy"]


def robot_url(ip: Any, port: Any) -> str:
    """``tcp://ip:port`` from the SDK's (ip, port) (an ip that is a URL is kept)."""
    text = str(ip)
    if "://" in text:
        return text
    return f"tcp://{text}:{int(port)}"


@dataclass
class _Task:
    done: threading.Event = field(default_factory=threading.Event)
    stopped: threading.Event = field(default_factory=threading.Event)


class _Runtime:
    """What the SDK keeps per process: sessions by robot, the default broker, modules."""

    def __init__(self) -> None:
        self.lock = threading.RLock()
        self.sessions: dict[str, qi.Session] = {}
        self.brokers: list[ALBroker] = []
        self.modules: dict[str, ALModule] = {}
        self.tasks: dict[int, _Task] = {}
        self.task_ids = itertools.count(_LOCAL_TASK_IDS)
        self.subscriptions: dict[tuple[str, str, str], Callable[[], None]] = {}

    def session(self, url: str) -> qi.Session:
        """A connected session to ``url`` (one per robot, shared by every proxy).

        Raises:
            RuntimeError: Nothing answers at ``url``.
        """
        with self.lock:
            session = self.sessions.get(url)
            if session is not None and session.isConnected():
                return session
            session = qi.Session()
            try:
                session.connect(url)
            except RuntimeError as err:
                raise RuntimeError(f"ALBroker: cannot connect to {url}: {err}") from None
            self.sessions[url] = session
            return session

    def default_url(self) -> str:
        """The robot of the first live broker, else ``$NAOLOC_NAOQI_URL`` or loopback."""
        with self.lock:
            if self.brokers:
                return self.brokers[0].url
        return os.environ.get(DEFAULT_URL_ENV) or DEFAULT_URL

    def post(self, call: Callable[[], Any]) -> int:
        """Run ``call`` on a thread of its own; its task id."""
        task = _Task()
        with self.lock:
            task_id = next(self.task_ids)
            self.tasks[task_id] = task

        def body() -> None:
            try:
                call()
            except Exception as err:  # a posted call's failure is reported, as NAOqi logs it
                print(f"naoqi: posted call {task_id} failed: {err}", flush=True)
            finally:
                task.done.set()

        threading.Thread(target=body, name=f"naoqi-post-{task_id}", daemon=True).start()
        return task_id


_RUNTIME = _Runtime()


class _Post:
    """``proxy.post.method(...)``: start the call in the background, return its task id."""

    def __init__(self, proxy: ALProxy) -> None:
        self._proxy = proxy

    def __getattr__(self, method: str) -> Callable[..., int]:
        if method.startswith("__"):
            raise AttributeError(method)

        def post(*args: Any) -> int:
            return self._proxy.pCall(method, *args)

        post.__name__ = method
        return post


class ALProxy:
    """A proxy of a NAOqi module, as the old SDK's.

    Args:
        name: The module (service) name, e.g. "ALMotion", or a module of this process.
        ip: The robot's address (or a URL); None = the broker's robot.
        port: NAOqi's port (9559 on a NAO).

    Raises:
        RuntimeError: No robot answers, or it has no such module.
    """

    def __init__(self, name: str, ip: Any = None, port: Any = 9559) -> None:
        self._name = str(name)
        self._url = robot_url(ip, port) if ip is not None else _RUNTIME.default_url()
        self._local = _RUNTIME.modules.get(self._name) if ip is None else None
        self._service: Any = None
        if self._local is None:
            session = _RUNTIME.session(self._url)
            try:
                self._service = session.service(self._name)
            except RuntimeError as err:
                raise RuntimeError(
                    f"ALProxy::ALProxy: can't find service {self._name!r} at {self._url}: {err}"
                ) from None
        self.post = _Post(self)

    def __getattr__(self, method: str) -> Any:
        if method.startswith("_"):
            raise AttributeError(method)
        if self._local is not None:
            return getattr(self._local, method)
        if self._name == "ALMemory" and method in _MEMORY_EVENT_METHODS:
            return getattr(self, f"_{method}")
        return getattr(self._service, method)

    def __repr__(self) -> str:
        return f"<naoqi.ALProxy {self._name} at {self._url}>"

    # ------------------------------------------------------------------ tasks
    def pCall(self, method: str, *args: Any) -> int:
        """Start ``method(*args)`` in the background; its task id (for wait, stop...)."""
        if self._local is None:
            with contextlib.suppress(RuntimeError, AttributeError):
                return int(self._service.pCall(method, *args))
        call = getattr(self, method)
        return _RUNTIME.post(lambda: call(*args))

    def wait(self, task_id: int, timeout_ms: int) -> bool:
        """Wait for a task (``timeout_ms`` ms, 0 = until it ends); True when it ended."""
        task = _RUNTIME.tasks.get(task_id)
        if task is None:
            return bool(self._service.wait(task_id, timeout_ms)) if self._service else True
        return task.done.wait(None if timeout_ms == 0 else timeout_ms / 1000.0)

    def isRunning(self, task_id: int) -> bool:
        """True while a task runs."""
        task = _RUNTIME.tasks.get(task_id)
        if task is None:
            return bool(self._service.isRunning(task_id)) if self._service else False
        return not task.done.is_set()

    def stop(self, task_id: int) -> None:
        """Ask a task to stop (a posted call here cannot be interrupted: it is marked)."""
        task = _RUNTIME.tasks.get(task_id)
        if task is None:
            if self._service is not None:
                self._service.stop(task_id)
            return
        task.stopped.set()

    # ------------------------------------------------------------------ ALMemory events
    def _subscribeToEvent(self, name: str, module: str, method: str) -> None:
        """Call ``module.method(name, value, module)`` on every ``name`` event."""
        target = _RUNTIME.modules.get(module)
        if target is None:  # a module elsewhere: the robot calls it (a real NAO does)
            self._service.subscribeToEvent(name, module, method)
            return
        self._unsubscribeToEvent(name, module)
        callback = _adapt(getattr(target, method), name, module)
        _RUNTIME.subscriptions[(self._url, name, module)] = self._watch(name, callback)

    def _unsubscribeToEvent(self, name: str, module: str) -> None:
        """Stop calling ``module`` back on ``name``."""
        undo = _RUNTIME.subscriptions.pop((self._url, name, module), None)
        if undo is not None:
            undo()
        elif module not in _RUNTIME.modules:
            self._service.unsubscribeToEvent(name, module)

    def _subscribeToMicroEvent(self, name: str, module: str, message: str, method: str) -> None:
        """As subscribeToEvent; the callback's third argument is ``message``."""
        target = _RUNTIME.modules.get(module)
        if target is None:
            self._service.subscribeToMicroEvent(name, module, message, method)
            return
        self._unsubscribeToEvent(name, module)
        callback = _adapt(getattr(target, method), name, message)
        _RUNTIME.subscriptions[(self._url, name, module)] = self._watch(name, callback)

    def _unsubscribeToMicroEvent(self, name: str, module: str) -> None:
        self._unsubscribeToEvent(name, module)

    def _watch(self, name: str, callback: Callable[[Any], None]) -> Callable[[], None]:
        """Call ``callback(value)`` on each ``name`` event; returns the undo."""
        try:
            subscriber = self._service.subscriber(name)
            signal = subscriber.signal
            link = signal.connect(callback)
        except RuntimeError:
            return _poll(self._service, name, callback)
        holder = [subscriber]  # the subscriber lives as long as the link

        def undo() -> None:
            with contextlib.suppress(RuntimeError):
                signal.disconnect(link)
            holder.clear()

        return undo


def _adapt(method: Callable[..., Any], name: str, third: str) -> Callable[[Any], None]:
    """``method`` called with as many of (eventName, value, third) as it takes."""
    try:
        params = list(inspect.signature(method).parameters.values())
    except (TypeError, ValueError):
        params = []
    if any(p.kind is p.VAR_POSITIONAL for p in params):
        count = 3
    else:
        count = min(3, sum(p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD) for p in params))

    def call(value: Any) -> None:
        method(*(name, value, third)[:count])

    return call


def _poll(service: Any, name: str, callback: Callable[[Any], None]) -> Callable[[], None]:
    """Watch ALMemory ``name`` by polling (transports without signals)."""
    stop = threading.Event()

    def read() -> Any:
        try:
            return service.getData(name)
        except RuntimeError:
            return None

    def run() -> None:
        last = read()
        while not stop.wait(POLL_S):
            value = read()
            if value != last and value is not None:
                callback(value)
            last = value

    threading.Thread(target=run, name=f"naoqi-poll-{name}", daemon=True).start()
    return stop.set


class ALBroker:
    """The script's broker: its connection to the robot, serving its modules.

    Args:
        name: The broker's name.
        ip: Ignored: the modules are served on the address that reaches the robot.
        port: Port to serve the modules on (0 = any free port).
        parentIp: The robot's address (or a URL).
        parentPort: NAOqi's port on the robot.

    Raises:
        RuntimeError: The robot does not answer, or the port is taken.
    """

    def __init__(self, name: str, ip: Any, port: Any, parentIp: Any, parentPort: Any) -> None:
        self._name = str(name)
        self.url = robot_url(parentIp, parentPort)
        self.session = _RUNTIME.session(self.url)
        self._port = int(port or 0)
        self._ids: dict[str, int] = {}
        if self._port:
            inner = self.session._inner()
            address = getattr(inner, "local_address", None)  # zmq serves no modules
            if callable(address):
                try:
                    self.session.listen(f"tcp://{address()}:{self._port}")
                except RuntimeError as err:
                    if "already listens" not in str(err):
                        raise RuntimeError(f"ALBroker {name!r}: {err}") from None
        with _RUNTIME.lock:
            _RUNTIME.brokers.append(self)

    def getName(self) -> str:
        """The broker's name."""
        return self._name

    def getIP(self) -> str:
        """The robot's address this broker is connected to."""
        return self.url

    def getPort(self) -> int:
        """The port asked for its modules (0 = any)."""
        return self._port

    def register(self, module: ALModule) -> None:
        """Serve ``module`` under its name through the robot's directory.

        Over a transport that cannot serve (zmq) the module stays local: this script's
        ALProxy and ALMemory callbacks reach it, other scripts do not (one notice).
        """
        service = _module_service(module)
        try:
            self._ids[module.getName()] = int(
                self.session.registerService(module.getName(), service)
            )
        except RuntimeError as err:
            if "zmq" not in str(err):
                raise RuntimeError(f"ALModule {module.getName()!r}: {err}") from None
            print(
                f"naoqi: module {module.getName()!r} is local to this script ({err})",
                file=sys.stderr,
                flush=True,
            )

    def unregister(self, name: str) -> None:
        """Stop serving the module ``name``."""
        service_id = self._ids.pop(name, None)
        if service_id is not None:
            with contextlib.suppress(RuntimeError, Exception):
                self.session.unregisterService(service_id)

    def shutdown(self) -> None:
        """Stop serving this broker's modules and forget the broker."""
        for name in list(self._ids):
            for key in [k for k in _RUNTIME.subscriptions if k[2] == name]:
                _RUNTIME.subscriptions.pop(key)()
            self.unregister(name)
            _RUNTIME.modules.pop(name, None)
        with _RUNTIME.lock:
            if self in _RUNTIME.brokers:
                _RUNTIME.brokers.remove(self)


class ALModule:
    """Base of a script's own module (subclass it; call ``ALModule.__init__(self, name)``).

    Its public methods are served under ``name`` by the script's broker, and are the
    callbacks ALMemory's ``subscribeToEvent(event, name, method)`` reaches.

    Raises:
        RuntimeError: No ALBroker was created first, or ``name`` is taken.
    """

    def __init__(self, name: str) -> None:
        self._module_name = str(name)
        with _RUNTIME.lock:
            broker = _RUNTIME.brokers[0] if _RUNTIME.brokers else None
            if self._module_name in _RUNTIME.modules:
                raise RuntimeError(f"ALModule: a module named {name!r} already exists")
        if broker is None:
            raise RuntimeError("ALModule: create an ALBroker first (it connects to the robot)")
        _RUNTIME.modules[self._module_name] = self
        self._broker = broker
        try:
            broker.register(self)
        except RuntimeError:
            _RUNTIME.modules.pop(self._module_name, None)
            raise

    def getName(self) -> str:
        """The module's name."""
        return self._module_name

    def ping(self) -> bool:
        """True."""
        return True

    def version(self) -> str:
        """The module's version."""
        return "2.1.4"

    def exit(self) -> None:
        """Stop serving this module."""
        self._broker.unregister(self._module_name)
        _RUNTIME.modules.pop(self._module_name, None)

    def BIND_PYTHON(self, moduleName: str, methodName: str) -> None:
        """NAOqi 1.x binding call: every public method is served already."""

    def setModuleDescription(self, description: str) -> None:
        """Kept for the SDK's API; not used."""

    def addParam(self, name: str, description: str = "") -> None:
        """Kept for the SDK's API; not used."""

    def functionName(self, name: str, module: str, description: str) -> None:
        """Kept for the SDK's API; not used."""

    def setReturn(self, name: str, description: str) -> None:
        """Kept for the SDK's API; not used."""


_BASE_METHODS: Final = frozenset(n for n in dir(ALModule) if not n.startswith("_")) - {
    "ping",
    "version",
}


def _module_service(module: ALModule) -> Any:
    """An object serving ``module``'s public methods with dynamic signatures."""
    namespace: dict[str, Any] = {}
    for attr in dir(module):
        if attr.startswith("_") or attr in _BASE_METHODS:
            continue
        member = getattr(module, attr, None)
        if not callable(member) or inspect.isclass(member):
            continue
        try:
            params = [
                p
                for p in inspect.signature(member).parameters.values()
                if p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD)
            ]
        except (TypeError, ValueError):
            continue
        namespace[attr] = qi.bind(qi.Dynamic, [qi.Dynamic] * len(params), methodName=attr)(
            _forward(member)
        )
    return type(f"{module.getName()}Service", (), namespace)()


def _forward(member: Callable[..., Any]) -> Callable[..., Any]:
    def call(self: Any, *args: Any) -> Any:
        return member(*args)

    return call
