"""A validating MCAP record reader: lengths, CRCs and decompressed sizes checked before use.

The ``mcap`` package's stream reader trusts what a file declares: record lengths up to
4 GiB, chunks decompressed without a bound, and CRCs only when asked. This reader walks the
records itself and uses the package only to parse record bodies it has already bounded:

- every record must fit in the file; a record running past the end is a truncated tail
  (a writer that died) unless the file ends with the closing magic, when it is corruption;
- chunks are decompressed into at most their declared size, itself capped, and their CRC
  is checked; the data section CRC (``DataEnd``) and the summary CRC (``Footer``) too;
- anything else that does not parse is corruption.

Every problem is a :class:`naoloc.errors.DatasetError` of one line naming the file and the
byte offset. Attachments, indexes and unknown records are skipped.
"""

from __future__ import annotations

import io
import os
import struct
import zlib
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

from naoloc.errors import DatasetError
from naoloc.safe_yaml import open_regular

MAGIC = b"\x89MCAP0\r\n"
# Upper bounds on what a file may declare (a survey frame is well under 10 MB).
MAX_RECORD_BYTES = 512 * 2**20
MAX_CHUNK_BYTES = 256 * 2**20
_PREFIX = struct.Struct("<BQ")
_MESSAGE_HEADER = 2 + 4 + 8 + 8  # channel id, sequence, log time, publish time


@dataclass(frozen=True)
class StreamEnd:
    """Yielded last by :func:`read_records`.

    Attributes:
        finished: The file has its data-end record, footer and closing magic (the writer
            closed it); False for a truncated file.
    """

    finished: bool


def read_records(path: Path) -> Iterator[Any]:
    """Yield the Header, Schema, Channel, Message and Metadata records of an MCAP file.

    Records inside chunks are yielded in place of their chunk. A :class:`StreamEnd` comes
    last.

    Raises:
        DatasetError: Missing, not MCAP, or corrupt (a CRC, length or record does not check).
    """
    stream = open_regular(Path(path), "dataset", DatasetError)  # never a FIFO or a device
    with stream:
        yield from _Walker(path, stream).records()


class _Walker:
    def __init__(self, path: Path, stream: IO[bytes]) -> None:
        self.path = path
        self.stream = stream
        self.size = os.fstat(stream.fileno()).st_size
        self.ends_with_magic = False
        if self.size >= 2 * len(MAGIC):
            stream.seek(self.size - len(MAGIC))
            self.ends_with_magic = stream.read(len(MAGIC)) == MAGIC
            stream.seek(0)

    def corrupt(self, offset: int, what: str) -> DatasetError:
        return DatasetError(f"{self.path}: corrupt MCAP at byte {offset}: {what}")

    def records(self) -> Iterator[Any]:
        from mcap.opcode import Opcode

        if self.stream.read(len(MAGIC)) != MAGIC:
            raise DatasetError(f"{self.path}: not an MCAP file")
        pos = len(MAGIC)
        data_crc = zlib.crc32(MAGIC)
        summary_crc: int | None = None  # running CRC after DataEnd
        while True:
            if self.size - pos < _PREFIX.size:
                if self.ends_with_magic:
                    raise self.corrupt(pos, "the file ends before its footer")
                if pos == len(MAGIC):
                    raise DatasetError(f"{self.path}: not an MCAP file (empty or truncated)")
                break  # a writer died here
            prefix = self.stream.read(_PREFIX.size)
            opcode, length = _PREFIX.unpack(prefix)
            if length > self.size - pos - _PREFIX.size:
                if self.ends_with_magic:
                    raise self.corrupt(pos, f"a record of {length} bytes runs past the end")
                break  # the tail a dead writer left
            if length > MAX_RECORD_BYTES:
                raise self.corrupt(pos, f"a record of {length} bytes (limit {MAX_RECORD_BYTES})")
            body = self.stream.read(length)
            if opcode == Opcode.FOOTER:
                self._check_footer(pos, prefix, body, summary_crc)
                if self.stream.read(len(MAGIC) + 1) != MAGIC:
                    raise self.corrupt(pos + _PREFIX.size + length, "no closing magic")
                yield StreamEnd(finished=summary_crc is not None)
                return
            if opcode == Opcode.DATA_END:
                self._check_data_end(pos, body, data_crc)
                summary_crc = 0
            elif summary_crc is not None:
                summary_crc = zlib.crc32(body, zlib.crc32(prefix, summary_crc))
            else:
                data_crc = zlib.crc32(body, zlib.crc32(prefix, data_crc))
                yield from self._parse(pos, opcode, body)
            pos += _PREFIX.size + length
        yield StreamEnd(finished=False)

    def _parse(self, pos: int, opcode: int, body: bytes) -> Iterator[Any]:
        from mcap.data_stream import ReadDataStream
        from mcap.opcode import Opcode
        from mcap.records import Channel, Chunk, Header, Message, Metadata, Schema

        readers: dict[int, Any] = {
            Opcode.HEADER: Header.read,
            Opcode.SCHEMA: Schema.read,
            Opcode.CHANNEL: Channel.read,
            Opcode.METADATA: Metadata.read,
            Opcode.CHUNK: Chunk.read,
        }
        if opcode == 0:
            raise self.corrupt(pos, "record opcode 0")
        if opcode != Opcode.MESSAGE and opcode not in readers:
            return  # indexes, attachments, statistics, unknown records: not needed
        if opcode == Opcode.MESSAGE and len(body) < _MESSAGE_HEADER:
            raise self.corrupt(pos, "a message record shorter than its header")
        try:
            rs = ReadDataStream(_Exact(body))
            if opcode == Opcode.MESSAGE:
                record = Message.read(rs, len(body))
            else:
                record = readers[opcode](rs)
        except Exception as err:  # struct, EndOfFile, UnicodeDecodeError...: bytes that lie
            raise self.corrupt(
                pos, f"a garbled {_name(opcode)} record ({type(err).__name__})"
            ) from None
        if rs.count > len(body):
            raise self.corrupt(pos, f"a {_name(opcode)} record longer than its length")
        if isinstance(record, Chunk):
            yield from self._chunk(pos, record)
        else:
            yield record

    def _chunk(self, pos: int, chunk: Any) -> Iterator[Any]:
        from mcap.opcode import Opcode

        size = int(chunk.uncompressed_size)
        if size > MAX_CHUNK_BYTES:
            raise self.corrupt(pos, f"a chunk declares {size} bytes (limit {MAX_CHUNK_BYTES})")
        raw = _decompress(chunk.compression, bytes(chunk.data), size)
        if raw is None:
            raise self.corrupt(pos, f"a chunk does not decompress ({chunk.compression!r})")
        if len(raw) != size:
            raise self.corrupt(pos, f"a chunk holds {len(raw)} bytes, declares {size}")
        if chunk.uncompressed_crc != 0 and zlib.crc32(raw) != chunk.uncompressed_crc:
            raise self.corrupt(pos, "chunk CRC mismatch")
        at = 0
        while at < len(raw):
            if len(raw) - at < _PREFIX.size:
                raise self.corrupt(pos, "a chunk ends inside a record")
            opcode, length = _PREFIX.unpack_from(raw, at)
            start = at + _PREFIX.size
            if length > len(raw) - start:
                raise self.corrupt(pos, "a record inside a chunk runs past the chunk")
            if opcode in (Opcode.SCHEMA, Opcode.CHANNEL, Opcode.MESSAGE):
                yield from self._parse(pos, opcode, raw[start : start + length])
            at = start + length

    def _check_data_end(self, pos: int, body: bytes, crc: int) -> None:
        if len(body) < 4:
            raise self.corrupt(pos, "a garbled data-end record")
        (declared,) = struct.unpack_from("<I", body)
        if declared != 0 and declared != crc:
            raise self.corrupt(pos, "data section CRC mismatch")

    def _check_footer(self, pos: int, prefix: bytes, body: bytes, crc: int | None) -> None:
        if len(body) < 20:
            raise self.corrupt(pos, "a garbled footer")
        (declared,) = struct.unpack_from("<I", body, 16)
        if crc is None:
            crc = 0  # no data-end record before the footer: nothing to check
        if declared != 0 and declared != zlib.crc32(body[:16], zlib.crc32(prefix, crc)):
            raise self.corrupt(pos, "summary CRC mismatch")


class _Exact(io.BytesIO):
    """A byte buffer whose ``read(n)`` gives exactly n bytes or raises (no silent short read)."""

    def read(self, size: int | None = -1, /) -> bytes:
        data = super().read(size)
        if size is not None and size >= 0 and len(data) != size:
            raise EOFError("a field runs past its record")
        return data


def _name(opcode: int) -> str:
    from mcap.opcode import Opcode

    try:
        return Opcode(opcode).name.lower()
    except ValueError:
        return f"opcode {opcode}"


def _decompress(compression: str, data: bytes, size: int) -> bytes | None:
    """``data`` decompressed, reading at most ``size + 1`` bytes of output; None if it fails."""
    try:
        if compression == "":
            return data
        if compression == "zstd":
            import zstandard

            out = bytearray()
            with zstandard.ZstdDecompressor().stream_reader(io.BytesIO(data)) as reader:
                while len(out) <= size:
                    piece = reader.read(size + 1 - len(out))
                    if not piece:
                        break
                    out += piece
            return bytes(out)
        if compression == "lz4":
            import lz4.frame

            return bytes(lz4.frame.LZ4FrameDecompressor().decompress(data, max_length=size + 1))
    except Exception:  # each library has its own error types for bad input
        return None
    return None
