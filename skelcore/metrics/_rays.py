"""Union-of-caps area on an equal-area latitude raster: the kernel of the ``rays`` estimator (docs/metrics.md 2).

Computes the covered area S of paper Eq. 6 (``eq.boundedness_pts``) as a union of spherical caps.
The unit sphere of directions is cut into ``rows`` rows of equal height in z (so of equal area,
Archimedes) and every row into ``bins`` longitude bins, one direction sample per cell centre.  A cap
meets a row's centre circle in one exact longitude interval (law of cosines), marked in a per-row
difference array, so the union of any number of caps costs one ``np.bincount`` and one ``cumsum``:
the exact union area up to the grid's sampling error, with no per-sample test.  The raster's frame
is a fixed generic rotation of the world frame, so its rows never line up with the axis-aligned
silhouettes common in scanned and synthetic shapes (the row errors would add up).  Everything runs in
float32 on flat (query, point) pair arrays (the 0.01 of docs/metrics.md 2 is far above float32's precision).

Cost, error measurements and alternatives tried: docs/boundedness.md.
"""

from __future__ import annotations

import numpy as np

# A fixed, generic rotation (rotation vector (0.3, 0.7, 1.1) rad): raster frame = FRAME @ world.
_ROTVEC = np.array([0.3, 0.7, 1.1])


def _rotation_matrix(rotvec: np.ndarray) -> np.ndarray:
    angle = float(np.linalg.norm(rotvec))
    k = rotvec / angle
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(angle) * kx + (1 - np.cos(angle)) * (kx @ kx)


FRAME = _rotation_matrix(_ROTVEC)


class CapRaster:
    """The raster geometry (row heights, per-row constants) and the union-area kernel."""

    def __init__(self, rows: int, bins: int):
        if rows < 1 or bins < 1:
            raise ValueError("the raster needs at least one row and one bin")
        self.rows = int(rows)
        self.bins = int(bins)
        z = -1.0 + (np.arange(self.rows) + 0.5) * (2.0 / self.rows)
        s = np.sqrt(1.0 - z * z)
        self._inv_s = (1.0 / s).astype(np.float32)
        self._z_over_s = (z / s).astype(np.float32)
        self._bins_per_radian = np.float32(self.bins / (2.0 * np.pi))
        self._tiled: dict[int, tuple[np.ndarray, np.ndarray]] = {}

    def _row_tables(self, n_queries: int) -> tuple[np.ndarray, np.ndarray]:
        """1 / s_j and z_j / s_j tiled over n_queries blocks: indexed by the global row q * rows + j."""
        tables = self._tiled.get(n_queries)
        if tables is None:
            tables = (np.tile(self._inv_s, n_queries), np.tile(self._z_over_s, n_queries))
            if len(self._tiled) < 64:
                self._tiled[n_queries] = tables
        return tables

    def union_fraction(
        self,
        n_queries: int,
        qidx: np.ndarray,
        dx: np.ndarray,
        dy: np.ndarray,
        dz: np.ndarray,
        h: np.ndarray | float,
    ) -> np.ndarray:
        """Fraction of the raster's samples covered by the caps of (query, point) pairs, per query."""
        covered = self.covered(n_queries, qidx, dx, dy, dz, h)
        return np.count_nonzero(covered.reshape(n_queries, -1), axis=1) / float(self.rows * self.bins)

    def covered(
        self,
        n_queries: int,
        qidx: np.ndarray,
        dx: np.ndarray,
        dy: np.ndarray,
        dz: np.ndarray,
        h: np.ndarray | float,
    ) -> np.ndarray:
        """(n_queries, rows, bins) booleans: the samples covered by the caps of (query, point) pairs.

        ``qidx`` (any order) names the query of each pair in ``0..n_queries-1``; ``(dx, dy, dz)`` is
        p - q in the raster's frame (float32); ``h`` is the ball radius, a scalar or one per pair.
        A pair with |p - q| <= h contributes nothing (docs/metrics.md 2: the query is inside that ball).
        """
        rows, bins = self.rows, self.bins
        f32 = np.float32
        h = np.asarray(h, dtype=f32)
        d2 = dx * dx
        d2 += dy * dy
        d2 += dz * dz
        # no errstate (it costs more than a ufunc here): every step below stays finite
        inside = d2 <= h * h
        np.maximum(d2, f32(1e-30), out=d2)
        inv = np.sqrt(d2)
        np.divide(f32(1.0), inv, out=inv)
        uz = dz * inv
        sina = h * inv
        np.minimum(sina, f32(1.0), out=sina)
        cosa = f32(1.0) - sina * sina
        np.sqrt(cosa, out=cosa)
        rho = f32(1.0) - uz * uz
        np.maximum(rho, f32(0.0), out=rho)
        np.sqrt(rho, out=rho)
        mid = uz * cosa
        spread = rho * sina
        zhi = mid + spread
        zlo = mid - spread
        zhi[uz >= cosa] = 1.0  # the cap holds the north pole
        zlo[-uz >= cosa] = -1.0  # ... the south pole
        # rows j whose centre z_j = -1 + (j + 0.5) 2/rows lies in [zlo, zhi]:
        # first = ceil(x - 0.5) = trunc(x + 0.5), end = floor(y - 0.5) + 1 = trunc(y + 0.5)
        half_rows = f32(0.5 * rows)
        zlo += f32(1.0)
        zlo *= half_rows
        zlo += f32(0.5)
        first = zlo.astype(np.int32)
        zhi += f32(1.0)
        zhi *= half_rows
        zhi += f32(0.5)
        n = zhi.astype(np.int32)
        np.minimum(n, rows, out=n)
        n -= first
        n[inside] = 0
        sel = np.flatnonzero(n > 0)
        if len(sel) == 0:
            return np.zeros((n_queries, rows, bins), dtype=bool)
        n = n[sel]
        total = int(n.sum())
        rho = np.maximum(rho[sel], f32(1e-30))  # a cap centred on a pole: c = +-huge, full or empty
        # per pair, packed to expand with one np.repeat: c_j = (cos a - z_j u_z) / (s_j rho) is the
        # cosine of the half-width of the cap's interval on row j; longitude in bin units, shifted > 0
        packed = np.empty((len(sel), 4), dtype=f32)
        np.divide(cosa[sel], rho, out=packed[:, 0])
        np.divide(uz[sel], rho, out=packed[:, 1])
        phi = np.arctan2(dy[sel], dx[sel])
        phi *= self._bins_per_radian
        phi += f32(bins)
        phi += f32(0.5)  # bins k whose centre k + 0.5 lies in [phi - half, phi + half]: k = trunc(...)
        packed[:, 2] = phi
        # global row index q * rows + j = position in the expanded array - offset of the pair
        offsets = np.cumsum(n, dtype=np.int32)
        offsets -= n
        offsets -= first[sel]
        if n_queries > 1:
            offsets -= qidx[sel].astype(np.int32) * rows
        packed[:, 3] = offsets.view(f32)  # carried bit-exactly through the repeat
        per_row = np.repeat(packed, n, axis=0)
        row = np.arange(total, dtype=np.int32)
        row -= per_row[:, 3].view(np.int32)
        inv_s, z_over_s = self._row_tables(n_queries)
        c = per_row[:, 0] * inv_s[row]
        c -= per_row[:, 1] * z_over_s[row]
        full = c <= f32(-1.0)
        np.maximum(c, f32(-1.0), out=c)
        np.minimum(c, f32(1.0), out=c)
        half = np.arccos(c)
        half *= self._bins_per_radian
        centre = per_row[:, 2]
        start = (centre - half).astype(np.int32)
        length = (centre + half).astype(np.int32)
        length -= start
        np.maximum(length, 0, out=length)
        np.minimum(length, bins, out=length)
        length[full] = bins
        np.subtract(start, bins, out=start, where=start >= bins)
        base = row
        base *= bins + 1
        size = n_queries * rows * (bins + 1)
        stop = start + length
        wrap = np.flatnonzero(stop > bins)
        np.minimum(stop, bins, out=stop)
        stop += size
        # +1 at each interval start, -1 at its end (second half of one bincount); a wrapped interval
        # is split into [start, bins) and [0, stop - bins); written straight into one intp array
        n_wrap = len(wrap)
        marks = np.empty(2 * (total + n_wrap), dtype=np.intp)
        np.add(base, start, out=marks[:total])
        np.add(base, stop, out=marks[total : 2 * total])
        wrapped = base[wrap]
        marks[2 * total : 2 * total + n_wrap] = wrapped
        wrapped += start[wrap]
        wrapped += length[wrap] + (size - bins)
        marks[2 * total + n_wrap :] = wrapped
        counts = np.bincount(marks, minlength=2 * size)
        diff = counts[:size] - counts[size:]
        return np.cumsum(diff.reshape(n_queries, rows, bins + 1)[:, :, :bins], axis=2) > 0
