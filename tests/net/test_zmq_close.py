"""Closing a zmq session never touches a socket or a pipe its I/O thread still uses.

libzmq aborts the whole process (SIGABRT, no traceback) when a socket is used from two
threads, and a closed pipe's descriptor number is soon reused by whatever the process
opens next. So ``close`` releases the context and the wake pipe only once the I/O thread
has ended; when it cannot wait for it, the I/O thread releases them as it ends.
"""

from __future__ import annotations

import os
import threading
import time
from collections.abc import Iterator

import pytest

from naoloc.backends.naoqi import zmq_transport
from naoloc.backends.naoqi.zmq_transport import ZmqSession

pytestmark = pytest.mark.net


class _Echo:
    def echo(self, value: object) -> object:
        time.sleep(0.05)  # the caller's addCallback comes first, so it runs on the I/O thread
        return value


@pytest.fixture
def server() -> Iterator[ZmqSession]:
    session = ZmqSession()
    session.listenStandalone("tcp://127.0.0.1:0")
    session.registerService("Echo", _Echo())
    try:
        yield session
    finally:
        session.close()


def test_close_leaves_a_busy_io_thread_its_sockets_and_it_releases_them(
    server: ZmqSession, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(zmq_transport, "CLOSE_WAIT_S", 0.2)
    client = ZmqSession()
    client.connect(server.endpoints()[0])
    assert client.service("Echo").echo(3) == 3
    entered, release = threading.Event(), threading.Event()

    def stuck(_future: object) -> None:  # runs on the client's I/O thread
        entered.set()
        release.wait(10)

    client.service("Echo").echo(4, _async=True).addCallback(stuck)
    assert entered.wait(5)
    io_thread = client._thread
    assert io_thread is not None
    client.close()  # waits 0.2 s, then hands the release to the I/O thread
    assert io_thread.is_alive()
    ctx, wake = client._ctx, client._wake
    assert ctx is not None and not ctx.closed, "the context was destroyed under its I/O thread"
    assert wake is not None
    os.fstat(wake.read_fd)  # the pipe is still open: its descriptor cannot be reused yet
    release.set()
    io_thread.join(5)
    assert not io_thread.is_alive()
    assert ctx.closed and client._ctx is None and client._wake is None
    client.close()  # twice is fine


def test_close_after_the_io_thread_ended_releases_at_once(server: ZmqSession) -> None:
    client = ZmqSession()
    client.connect(server.endpoints()[0])
    ctx = client._ctx
    assert ctx is not None
    client.close()
    assert client._thread is not None and not client._thread.is_alive()
    assert ctx.closed and client._ctx is None and client._wake is None


def test_a_poke_after_close_writes_nothing_into_a_reused_descriptor() -> None:
    wake = zmq_transport._Wake()
    wake.close()
    read_fd, write_fd = os.pipe()  # takes the lowest free numbers: those wake just closed
    try:
        os.set_blocking(read_fd, False)
        wake.poke()
        with pytest.raises(BlockingIOError):
            os.read(read_fd, 1)
    finally:
        os.close(read_fd)
        os.close(write_fd)
