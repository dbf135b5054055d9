"""What a reader may allocate for one recording's chunk, checked before anything is decompressed.

Every reader of ours (``info``, ``recover``, ``report``, ``replay``, ``export``,
``animate``) checks each chunk's declared size against :data:`MAX_CHUNK_BYTES` before
decompressing it (50 KB of zstd can claim 1 GiB): a RecordingError in one line.
"""

from __future__ import annotations

import io
import struct

import lz4.frame
import zstandard
from mcap.records import Chunk

from common.errors import RecordingError

MAX_CHUNK_BYTES = 64 * 1024 * 1024   # [bytes] decompressed size of one chunk
HEAD_BYTES = 32                      # [bytes] of compressed data holding the frame header
_FIXED = struct.Struct("<QQQI")      # start, end, uncompressed_size, uncompressed_crc


def check_sizes(uncompressed_size: int, compression: str, head: bytes, where: str) -> None:
    """RecordingError when a chunk would decompress to more than :data:`MAX_CHUNK_BYTES`.

    A chunk record says how large its records are once decompressed (``uncompressed_size``), and
    the library allocates that much (zstd: the frame's own content size, when it gives one).
    50 KB of zstd can claim 1 GiB. Every reader of ours (``info``, ``recover``, ``report``,
    ``replay``, ``export``, ``animate``) checks each chunk first: a size above
    :data:`MAX_CHUNK_BYTES` — in the record or in the compressed frame's header — is a
    RecordingError (one line), and an lz4 frame that does not declare its size is decompressed
    in bounded pieces to count it. Our recorder closes a chunk at 512 KiB (or at one message
    beyond it), so 64 MiB leaves a 128-fold margin for any recording of ours.
    """
    declared = uncompressed_size
    if compression == "zstd" and head:
        try:
            size = zstandard.frame_content_size(head)
        except zstandard.ZstdError:
            size = -1   # not a frame header: the decompressor will say so
        declared = max(declared, size)
    elif compression == "lz4" and head:
        try:
            declared = max(declared, lz4.frame.get_frame_info(head)["content_size"])
        except RuntimeError:
            pass
    if declared > MAX_CHUNK_BYTES:
        raise RecordingError(f"{where}: a chunk would decompress to {declared:,} bytes, more than "
                             f"the {MAX_CHUNK_BYTES:,} any recording of ours needs; not read (if the file is "
                             f"damaged, papf recover {where} FIXED.mcap salvages the rest)")


def check_chunk(chunk: Chunk, where: str) -> None:
    """:func:`check_sizes` for a chunk record in memory; an lz4 frame without a declared size
    is decompressed in bounded pieces and counted."""
    check_sizes(chunk.uncompressed_size, chunk.compression, bytes(chunk.data[:HEAD_BYTES]), where)
    if chunk.compression == "lz4" and _lz4_size(chunk.data[:HEAD_BYTES]) == 0:
        _lz4_bounded(chunk.data, where)


def check_file_chunks(f, chunk_indexes, where: str) -> None:
    """:func:`check_sizes` for every chunk the summary indexes, reading only each chunk's
    header from the open file ``f`` (the caller's position is kept)."""
    here = f.tell()
    try:
        for ci in chunk_indexes:
            check_sizes(ci.uncompressed_size, ci.compression, b"", where)
            f.seek(ci.chunk_start_offset + 9)   # opcode (1) + record length (8)
            fixed = f.read(_FIXED.size + 4)
            if len(fixed) < _FIXED.size + 4:
                continue   # a short file: the library reports the damage
            _, _, size, _ = _FIXED.unpack_from(fixed)
            (n,) = struct.unpack_from("<I", fixed, _FIXED.size)
            compression = f.read(min(n, 16)).decode("ascii", "replace")
            f.seek(max(n - 16, 0) + 8, io.SEEK_CUR)   # rest of the name, records length
            head = f.read(HEAD_BYTES)
            check_sizes(size, compression, head, where)
            if compression == "lz4" and _lz4_size(head) == 0:
                f.seek(-len(head), io.SEEK_CUR)
                _lz4_bounded(f.read(ci.compressed_size), where)
    finally:
        f.seek(here)


def _lz4_size(head: bytes) -> int:
    try:
        return int(lz4.frame.get_frame_info(bytes(head))["content_size"])
    except RuntimeError:
        return -1


def _lz4_bounded(data: bytes, where: str) -> None:
    """Decompress an lz4 frame in pieces, refusing it past :data:`MAX_CHUNK_BYTES`."""
    dec, total, rest = lz4.frame.LZ4FrameDecompressor(), 0, bytes(data)
    try:
        while rest and not dec.eof:
            total += len(dec.decompress(rest, max_length=1 << 20))
            rest = dec.unused_data if dec.eof else b""
            while not dec.eof and dec.needs_input is False and total <= MAX_CHUNK_BYTES:
                total += len(dec.decompress(b"", max_length=1 << 20))
            if total > MAX_CHUNK_BYTES:
                break
    except RuntimeError:
        return   # damaged: the reader reports it
    if total > MAX_CHUNK_BYTES:
        raise RecordingError(f"{where}: an lz4 chunk decompresses to more than {MAX_CHUNK_BYTES:,} "
                             "bytes, more than any recording of ours needs; not read")
