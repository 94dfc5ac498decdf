"""LZF decompression (liblzf's format, used by PCL's ``binary_compressed`` PCD), in pure Python.

A control byte below 32 starts a run of ctrl + 1 literal bytes; otherwise its top 3 bits give a
back-reference length (7 = one more length byte follows) and, with the next byte, the distance
back into the output. Works token by token with slice copies (overlapping references repeat
their pattern), so the cost is per token, not per byte. No token yields more than 88 bytes per byte it
takes (a 3-byte reference copies at most 264), so an output size beyond that is refused before its
buffer is allocated: a header cannot make a small file cost gigabytes.
"""

from __future__ import annotations

__all__ = ["MAX_EXPANSION", "lzf_decompress"]

MAX_EXPANSION = 88  # the most output bytes per input byte: a 3-byte back-reference copies 264


def lzf_decompress(src: bytes, out_len: int) -> bytes:
    """Decompress ``src`` into exactly ``out_len`` bytes; ValueError on corrupt or short data."""
    if out_len > MAX_EXPANSION * len(src):
        raise ValueError(f"{len(src)} bytes cannot expand to {out_len} (at most {MAX_EXPANSION} x)")
    out = bytearray(out_len)
    n = len(src)
    ip = op = 0
    try:
        while ip < n:
            ctrl = src[ip]
            ip += 1
            if ctrl < 32:
                length = ctrl + 1
                if ip + length > n or op + length > out_len:
                    raise ValueError("literal run past the end of the data")
                out[op:op + length] = src[ip:ip + length]
                ip += length
                op += length
                continue
            length = ctrl >> 5
            ref = op - ((ctrl & 0x1F) << 8) - 1
            if length == 7:
                length += src[ip]
                ip += 1
            ref -= src[ip]
            ip += 1
            length += 2
            if ref < 0:
                raise ValueError("back-reference before the start of the output")
            if op + length > out_len:
                raise ValueError("back-reference past the end of the output")
            dist = op - ref
            if dist >= length:
                out[op:op + length] = out[ref:ref + length]
            else:  # overlapping: the last ``dist`` bytes repeat
                pattern = bytes(out[ref:op])
                out[op:op + length] = (pattern * (length // dist + 1))[:length]
            op += length
    except IndexError:
        raise ValueError("compressed data ends in the middle of a token") from None
    if op != out_len:
        raise ValueError(f"decompressed to {op} bytes, expected {out_len}")
    return bytes(out)
