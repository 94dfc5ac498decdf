"""PCD (Point Cloud Library): ascii, binary and binary_compressed (LZF, PCL's default in many
robotics pipelines: sizes as two uint32, then the fields stored one after another, uncompressed)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import SkelInputError
from ._common import RawData, decode_text, numeric_table
from .lzf import lzf_decompress

_HEADER_KEYS = ("VERSION", "FIELDS", "SIZE", "TYPE", "COUNT", "WIDTH", "HEIGHT", "VIEWPOINT", "POINTS", "DATA")


def is_pcd(text_head: str) -> bool:
    for line in text_head.splitlines()[:20]:
        s = line.strip()
        if not s:
            continue
        if s.startswith("#"):
            if ".PCD" in s.upper():
                return True
            continue
        return s.split(None, 1)[0].upper() in ("VERSION", "FIELDS")
    return False


def _parse_header(data: bytes, path: Path) -> tuple[dict[str, list[str]], int]:
    """Header keys -> tokens, and the byte offset where the data starts (after the DATA line)."""
    header: dict[str, list[str]] = {}
    pos = 0
    while True:
        nl = data.find(b"\n", pos)
        if nl < 0:
            raise SkelInputError("PCD header has no DATA line (truncated or not a PCD file)", path)
        line = data[pos:nl].decode("ascii", errors="replace").strip()
        pos = nl + 1
        if not line or line.startswith("#"):
            continue
        toks = line.split()
        key = toks[0].upper()
        if key not in _HEADER_KEYS:
            raise SkelInputError(f"unexpected PCD header line {line[:30]!r}", path)
        header[key] = toks[1:]
        if key == "DATA":
            return header, pos
        if pos > 65536:
            raise SkelInputError("PCD header too long (not a PCD file?)", path)


_DEFAULT_VIEWPOINT = (0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0)


def pcd_viewpoint(path: str | Path) -> np.ndarray | None:
    """The sensor position of a PCD file: the translation of its ``VIEWPOINT tx ty tz qw qx qy qz`` line
    (PCL's ``sensor_origin_``, in the cloud's coordinates), or None when the line is absent, is PCL's
    default ``0 0 0 1 0 0 0`` (which says nothing), or the file is not a PCD (docs/metrics.md 6.3)."""
    path = Path(path)
    try:
        with open(path, "rb") as fh:
            head = fh.read(65536)
    except OSError:
        return None
    if not is_pcd(head.decode("ascii", errors="replace")):
        return None
    header, _ = _parse_header(head if b"DATA" in head else head + b"\nDATA ascii\n", path)
    tokens = header.get("VIEWPOINT")
    if not tokens:
        return None
    try:
        values = tuple(float(t) for t in tokens)
    except ValueError:
        raise SkelInputError(f"PCD header: VIEWPOINT must be 7 numbers, got {' '.join(tokens)[:40]!r}", path) from None
    if len(values) != 7 or not np.all(np.isfinite(values)):
        raise SkelInputError(f"PCD header: VIEWPOINT must be 7 finite numbers (tx ty tz qw qx qy qz), got {len(values)}",
                             path)
    if values == _DEFAULT_VIEWPOINT:
        return None
    return np.array(values[:3])


def read_pcd(path: Path, data: bytes) -> RawData:
    header, start = _parse_header(data, path)
    fields = header.get("FIELDS")
    if not fields:
        raise SkelInputError("PCD header has no FIELDS line", path)
    lower = [f.lower() for f in fields]
    missing = [k for k in "xyz" if k not in lower]
    if missing:
        raise SkelInputError(f"PCD has no {'/'.join(missing)} field (fields: {' '.join(fields)})", path)
    nf = len(fields)
    counts = [int(c) for c in header.get("COUNT", ["1"] * nf)]
    if len(counts) != nf or min(counts) < 1:
        raise SkelInputError("PCD header: COUNT does not match FIELDS", path)
    n_points = _n_points(header, path)
    mode = (header["DATA"] or ["?"])[0].lower()
    offsets = np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(int)
    cols = [int(offsets[lower.index(k)]) for k in "xyz"]
    if mode == "ascii":
        text = decode_text(data[start:])
        rows = [(i, s.strip()) for i, s in enumerate(text.splitlines(), 1) if s.strip()]
        table = numeric_table(rows, path, min_cols=sum(counts), what="PCD ascii row")
        if table.shape[1] != sum(counts):
            raise SkelInputError(f"PCD rows have {table.shape[1]} values, FIELDS/COUNT say {sum(counts)}", path)
        if len(table) != n_points:
            raise SkelInputError(f"PCD header says {n_points} points, file has {len(table)} rows", path)
        return RawData(vertices=table[:, cols].copy(), edges=None, format="PCD")
    if mode == "binary":
        dtype = _record_dtype(header, fields, counts, path)
        need = n_points * dtype.itemsize
        if len(data) - start < need:
            raise SkelInputError(
                f"truncated: PCD header promises {need} bytes of point data, file has {len(data) - start}", path
            )
        rec = np.frombuffer(data, dtype=dtype, count=n_points, offset=start)
        names = dtype.names
        assert names is not None
        pts = np.column_stack([rec[names[lower.index(k)]].reshape(n_points, -1)[:, 0] for k in "xyz"])
        return RawData(vertices=pts.astype(np.float64), edges=None, format="PCD")
    if mode == "binary_compressed":
        return RawData(vertices=_compressed_xyz(data, start, header, fields, counts, n_points, path), edges=None, format="PCD")
    raise SkelInputError(f"unknown PCD DATA type {mode[:30]!r}", path)


def _n_points(header: dict[str, list[str]], path: Path) -> int:
    try:
        if "POINTS" in header:
            n = int(header["POINTS"][0])
        else:
            n = int(header["WIDTH"][0]) * int(header.get("HEIGHT", ["1"])[0])
    except (KeyError, IndexError, ValueError):
        raise SkelInputError("PCD header: bad or missing POINTS/WIDTH", path) from None
    if n < 0:
        raise SkelInputError(f"PCD header: negative point count {n}", path)
    return n


def _record_dtype(header, fields, counts, path: Path) -> np.dtype:
    sizes = header.get("SIZE")
    types = header.get("TYPE")
    if not sizes or not types or len(sizes) != len(fields) or len(types) != len(fields):
        raise SkelInputError("PCD header: SIZE/TYPE do not match FIELDS", path)
    parts = []
    for i, (name, size, typ, count) in enumerate(zip(fields, sizes, types, counts)):
        code = {"F": "f", "I": "i", "U": "u"}.get(typ.upper())
        if code is None or size not in ("1", "2", "4", "8") or (code == "f" and size not in ("4", "8")):
            raise SkelInputError(f"PCD field {name!r}: unsupported TYPE {typ} SIZE {size}", path)
        # Padding fields are all called "_"; numpy needs unique names.
        parts.append((f"{i}_{name}", f"<{code}{size}", (count,)))
    return np.dtype(parts)


def _compressed_xyz(data: bytes, start: int, header, fields, counts, n_points: int, path: Path) -> np.ndarray:
    """x, y, z of a binary_compressed PCD: uint32 compressed and uncompressed sizes, LZF data that
    decompresses to each field's column for all points in turn (structure of arrays; PCL leaves
    out padding fields named ``_`` there, so either layout is accepted by its size)."""
    dtype = _record_dtype(header, fields, counts, path)
    if len(data) - start < 8:
        raise SkelInputError("truncated: binary_compressed PCD has no size words", path)
    comp, raw = (int(v) for v in np.frombuffer(data, dtype="<u4", count=2, offset=start))
    subs = [dtype.fields[name][0] for name in dtype.names or ()]  # type: ignore[index]
    keep = list(range(len(fields)))
    if raw != n_points * dtype.itemsize:
        keep = [i for i, f in enumerate(fields) if f != "_"]
        if raw != n_points * sum(subs[i].itemsize for i in keep):
            raise SkelInputError(
                f"binary_compressed PCD: uncompressed size {raw} does not match {n_points} points "
                f"of {dtype.itemsize} bytes", path,
            )  # fmt: skip
    if len(data) - start - 8 < comp:
        raise SkelInputError(
            f"truncated: binary_compressed PCD promises {comp} compressed bytes, file has {len(data) - start - 8}", path
        )
    if raw == 0:
        return np.empty((0, 3))
    try:
        flat = lzf_decompress(data[start + 8:start + 8 + comp], raw)
    except ValueError as exc:
        raise SkelInputError(f"binary_compressed PCD: corrupt LZF data ({exc})", path) from None
    offsets: dict[int, int] = {}
    offset = 0
    for i in keep:
        offsets[i] = offset
        offset += subs[i].itemsize * n_points
    lower = [f.lower() for f in fields]
    cols = []
    for k in "xyz":
        i = lower.index(k)
        sub = subs[i]
        col = np.frombuffer(flat, dtype=sub.base, count=n_points * int(np.prod(sub.shape)), offset=offsets[i])
        cols.append(col.reshape(n_points, -1)[:, 0])
    return np.column_stack(cols).astype(np.float64)
