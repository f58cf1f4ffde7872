"""TLS for QiMessaging connections that are read and written from different threads.

OpenSSL forbids using one ``SSL`` object from two threads at once, and Python's
``ssl.SSLSocket`` releases the GIL inside ``SSL_read``: a reader thread blocked in
``recv`` while another thread ``sendall``s corrupts the session now and then
("[SSL] internal error", or a record that never arrives). Here the TLS state lives
in an ``ssl.SSLObject`` on memory BIOs, touched only under a lock that is never held
while waiting on the network; the plain socket does the blocking I/O.
"""

from __future__ import annotations

import socket
import ssl
import threading
from typing import Final, cast

_CHUNK: Final = 256 * 1024


class TlsSocket:
    """A TLS stream over a connected socket, safe for one reader and many writers.

    Offers the part of the socket API :class:`Connection` uses: ``sendall``,
    ``recv_into``, ``recv``, ``shutdown``, ``close`` and ``getpeername``.

    Args:
        sock: A connected TCP socket (blocking; its timeouts apply to the I/O).
        tls: The TLS state, made by :func:`client` or :func:`server`.
    """

    def __init__(self, sock: socket.socket, tls: ssl.SSLObject, incoming: ssl.MemoryBIO,
                 outgoing: ssl.MemoryBIO) -> None:  # fmt: skip
        self._sock = sock
        self._tls = tls
        self._in = incoming
        self._out = outgoing
        self._state = threading.Lock()  # the SSLObject and its BIOs; never held on I/O
        self._send = threading.Lock()  # keeps TLS records in order on the wire

    def handshake(self) -> None:
        """Run the TLS handshake (before the reader thread starts).

        Raises:
            ssl.SSLError: The peer's TLS is not acceptable.
            OSError: The socket failed or timed out.
        """
        while True:
            try:
                with self._state:
                    self._tls.do_handshake()
                self._flush()
                return
            except ssl.SSLWantReadError:
                self._flush()
                if not self._fill():
                    raise ConnectionResetError("peer closed the connection during TLS") from None

    def _flush(self) -> None:
        with self._send:
            with self._state:
                data = self._out.read()
            if data:
                self._sock.sendall(data)

    def _fill(self) -> bool:
        """Feed what the network has into the TLS state; False at end of stream."""
        data = self._sock.recv(_CHUNK)
        with self._state:
            if data:
                self._in.write(data)
            else:
                self._in.write_eof()
        return bool(data)

    def sendall(self, data: bytes | bytearray | memoryview) -> None:
        """Encrypt and send all of ``data``.

        Raises:
            OSError: The socket failed (a broken TLS session reads as one).
        """
        view = memoryview(data).cast("B")
        with self._send:
            while view:
                with self._state:
                    try:
                        n = self._tls.write(view[:_CHUNK])
                    except ssl.SSLError as err:
                        raise OSError(f"TLS send failed: {err}") from None
                    out = self._out.read()
                view = view[n:]
                self._sock.sendall(out)

    def recv_into(self, buffer: memoryview, nbytes: int = 0) -> int:
        """Decrypt up to ``nbytes`` into ``buffer``; 0 at end of stream.

        Raises:
            OSError: The socket failed or the TLS session broke.
        """
        size = nbytes or len(buffer)
        eof = False
        while True:
            with self._state:
                try:
                    return cast(int, self._tls.read(size, buffer))  # type: ignore[arg-type]
                except ssl.SSLWantReadError:
                    if eof:
                        return 0
                    pending = self._out.pending
                except (ssl.SSLZeroReturnError, ssl.SSLEOFError):
                    return 0
                except ssl.SSLError as err:
                    raise OSError(f"TLS receive failed: {err}") from None
            if pending:
                self._flush()
            eof = not self._fill()

    def recv(self, nbytes: int) -> bytes:
        """Decrypt up to ``nbytes``; b"" at end of stream."""
        buf = bytearray(nbytes)
        n = self.recv_into(memoryview(buf), nbytes)
        return bytes(buf[:n])

    def shutdown(self, how: int) -> None:
        """Shut the underlying socket down (no close_notify: the peer sees the end)."""
        self._sock.shutdown(how)

    def close(self) -> None:
        """Close the underlying socket."""
        self._sock.close()

    def getpeername(self) -> object:
        """The peer's address."""
        return self._sock.getpeername()

    def peer_certificate(self) -> bytes:
        """The peer's certificate (DER; b"" when it sent none)."""
        with self._state:
            return self._tls.getpeercert(binary_form=True) or b""


def _wrap(sock: socket.socket, context: ssl.SSLContext, *, server_side: bool,
          host: str | None) -> TlsSocket:  # fmt: skip
    incoming, outgoing = ssl.MemoryBIO(), ssl.MemoryBIO()
    tls = context.wrap_bio(incoming, outgoing, server_side=server_side, server_hostname=host)
    wrapped = TlsSocket(sock, tls, incoming, outgoing)
    wrapped.handshake()
    return wrapped


def client(sock: socket.socket, context: ssl.SSLContext, host: str) -> TlsSocket:
    """Client side TLS on ``sock``, handshake done.

    Raises:
        ssl.SSLError: The handshake failed.
        OSError: The socket failed or timed out.
    """
    return _wrap(sock, context, server_side=False, host=host)


def server(sock: socket.socket, context: ssl.SSLContext) -> TlsSocket:
    """Server side TLS on ``sock``, handshake done.

    Raises:
        ssl.SSLError: The handshake failed.
        OSError: The socket failed or timed out.
    """
    return _wrap(sock, context, server_side=True, host=None)
