"""The shape's interior as voxels, and its Betti numbers (docs/diagnostics.md
"Cycles").

A voxel is inside when it holds cloud points or when the rays from its centre along the 26 lattice
directions hit the (one voxel thicker) cloud-holding voxels in more than beta* of them: the
boundedness of docs/metrics.md 2 (the share of rays from a point that hit the sampled surface), on the voxel lattice.
Scoring every voxel with the ``rays`` estimator itself would cost 13 s for a 48-voxel torus of 4096
points; the lattice rays cost a few sweeps over the grid at any cloud size (compiled with the cells'
count, the parts and the hole fill: ``metrics/_voxels.c``).

The interior is the union of its closed voxel cubes; its Betti numbers come from the Euler
characteristic (beta1 = beta0 + beta2 - chi), beta0 from its 26-connected components and beta2 from
the 6-connected components of the rest that do not reach the grid's border (cavities). The tunnels
``missing_cycles`` counts are those that three ways of building the interior all keep (:func:`firm_tunnels`).
"""

from __future__ import annotations

import threading
import weakref
from dataclasses import dataclass, field

import numpy as np
from scipy import ndimage

from ..geometry import Checkpoint, bounding_box, no_checkpoint
from ..metrics import _voxels

__all__ = ["VoxelShape", "voxelize_interior", "betti_numbers", "wide_tunnels", "median_spacing", "cloud_subsample",
           "supported_voxels", "ray_interior", "ray_hits_share", "firm_tunnels", "resolved_part", "resolved_radius", "fill_holes", "grow_by_one",
           "lattice_hit_counts",
           "LATTICE_DIRECTIONS"]

#: the 26 lattice directions (each component -1, 0 or 1, not all 0)
LATTICE_DIRECTIONS = np.array([(a, b, c) for a in (-1, 0, 1) for b in (-1, 0, 1) for c in (-1, 0, 1)
                               if (a, b, c) != (0, 0, 0)], dtype=np.int64)
#: empty voxels around the cloud's box, so the outside is one component touching the border
PAD = 3


@dataclass
class VoxelShape:
    """The interior on a grid: voxel (i, j, k) has centre ``origin + (i, j, k) * size``.

    inside : bool (nx, ny, nz). occupied : voxels holding cloud points. hits : the share of the
    26 lattice rays from each voxel that meet the surface voxels.
    """

    inside: np.ndarray
    occupied: np.ndarray
    hits: np.ndarray
    origin: np.ndarray
    size: float
    _solid: np.ndarray | None = field(default=None, repr=False, compare=False)
    _tunnels: int | None = field(default=None, repr=False, compare=False)

    def solid(self) -> np.ndarray:
        """``inside`` with its cavities filled (the outside test's "in the shape"), made once per grid."""
        if self._solid is None:
            self._solid = fill_holes(self.inside)
        return self._solid

    def solid_tunnels(self) -> int:
        """The tunnels of :meth:`solid` (its beta1, :func:`betti_numbers`), counted once per grid: the
        cycle test asks it of every curve an edit's update scores against the same cloud."""
        if self._tunnels is None:
            self._tunnels = betti_numbers(self.solid(), filled=True)[1]
        return self._tunnels

    def index_of(self, points: np.ndarray) -> np.ndarray:
        """(n, 3) voxel indices of points (clipped to the grid)."""
        ijk = np.floor((np.asarray(points, float) - self.origin) / self.size + 0.5).astype(np.int64)
        return np.clip(ijk, 0, np.array(self.inside.shape) - 1)

    def centres(self, ijk: np.ndarray) -> np.ndarray:
        return self.origin + np.asarray(ijk, float) * self.size


def grow_by_one(mask: np.ndarray) -> np.ndarray:
    """``mask`` dilated by the 3 x 3 x 3 cube (``scipy.ndimage.binary_dilation``'s voxels, nothing
    beyond the grid): the cube is three unit segments one after the other, each two shifted ORs."""
    grown = np.array(mask, dtype=bool)
    for axis in range(grown.ndim):
        step = grown.copy()
        lo = [slice(None)] * grown.ndim
        hi = [slice(None)] * grown.ndim
        lo[axis], hi[axis] = slice(None, -1), slice(1, None)
        step[tuple(hi)] |= grown[tuple(lo)]
        step[tuple(lo)] |= grown[tuple(hi)]
        grown = step
    return grown


def fill_holes(mask: np.ndarray) -> np.ndarray:
    """``mask`` (3-D) with its holes filled: ``scipy.ndimage.binary_fill_holes`` (the same voxels), by a
    compiled flood of the empty voxels face-connected to the grid's border (``metrics/_voxels.c``; a
    labelling of the rest took ten times longer on the interior's grids, docs/performance.md 6.7).
    Empty parts not touching the grid's border are holes."""
    mask = np.ascontiguousarray(mask, dtype=bool)
    if mask.ndim != 3:
        raise ValueError(f"expected a 3-D grid, got shape {mask.shape}")
    out = np.empty(mask.shape, bool)
    _voxels.fill(mask.view(np.uint8), *mask.shape, out.view(np.uint8))
    return out


def lattice_hit_counts(target: np.ndarray) -> np.ndarray:
    """Per voxel, how many of the 26 lattice directions d have a ``target`` voxel at v + t d, t >= 1
    (uint8): the compiled sweeps of ``metrics/_voxels.c``, one direction after the other, each
    voxel reading the answer of its neighbour along d (docs/performance.md 6.7). The longest axis is
    made the contiguous one (the 26 directions map onto themselves): fewer, longer rows."""
    target = np.asarray(target, dtype=bool)
    last = int(np.argmax(target.shape))
    order = [a for a in range(3) if a != last] + [last]
    grid = np.ascontiguousarray(target.transpose(order))
    count = np.zeros(grid.shape, np.uint8)
    _voxels.hits(grid.view(np.uint8), *grid.shape, count)
    return count.transpose(np.argsort(order))


def cloud_subsample(cloud: np.ndarray, max_points: int, seed: int = 0) -> np.ndarray:
    """The cloud itself, or a random subset of ``max_points`` of its rows (in their order) when larger:
    the same subset for the same cloud, size and seed."""
    cloud = np.asarray(cloud, dtype=float)
    if len(cloud) <= max_points:
        return cloud
    pick = np.random.default_rng(seed).choice(len(cloud), int(max_points), replace=False)
    return cloud[np.sort(pick)]


# the last clouds' spacings, reused while the same array comes back (the diagnostics ask three times, of
# the cloud and of its subsample's tree data: one entry would make them evict each other at every update)
_last_spacing: dict = {}
_SPACINGS_KEPT = 4
_spacing_lock = threading.Lock()


def median_spacing(cloud: np.ndarray, max_points: int = 20000, spacings: np.ndarray | None = None) -> float:
    """The cloud's median nearest-neighbour spacing, from a random subsample of at most
    ``max_points`` (seed 0) scaled by sqrt(m / n): a surface sample's spacing shrinks as
    1 / sqrt(density). Exact for clouds of at most ``max_points``; for those, ``spacings`` (each row's
    exact distance to its nearest other row, when the caller has them) give the same value without a
    search."""
    from scipy.spatial import cKDTree

    cloud = np.asarray(cloud, dtype=float)
    n = len(cloud)
    if n < 2:
        return 0.0
    hit = _last_spacing.get((id(cloud), n, max_points))
    if hit is not None and hit[0]() is cloud:
        return hit[1]
    m = min(n, int(max_points))
    if m == n and spacings is not None and len(spacings) == n:
        value = float(np.median(np.asarray(spacings, dtype=float)))
    else:
        sub = cloud if m == n else cloud[np.random.default_rng(0).choice(n, m, replace=False)]
        d, _ = cKDTree(sub).query(sub, k=2)
        value = float(np.median(d[:, 1])) * float(np.sqrt(m / n))
    key = (id(cloud), n, max_points)
    try:
        ref = weakref.ref(cloud, lambda r, k=key, kept=_last_spacing: kept.pop(k, None)
                          if kept.get(k, (None,))[0] is r else None)
    except TypeError:  # not weak-referenceable: no cache
        return value
    with _spacing_lock:  # the diagnostics run side by side
        _last_spacing[key] = (ref, value)
        while len(_last_spacing) > _SPACINGS_KEPT:  # the oldest first (dicts keep their insertion order)
            _last_spacing.pop(next(iter(_last_spacing)), None)
    return value


def voxelize_interior(
    cloud: np.ndarray,
    *,
    voxels: int = 96,
    min_spacing_factor: float = 1.0,
    inside_share: float = 0.75,
    checkpoint: Checkpoint = no_checkpoint,
) -> VoxelShape:
    """Voxelize the solid bounded by ``cloud``.

    The voxel size is the larger of (longest box side / ``voxels``) and ``min_spacing_factor`` x the
    cloud's median nearest-neighbour spacing (estimated on at most 20 000 points), so that the
    cloud-holding voxels, grown by one, close the surface. A voxel is inside when it holds points or
    more than ``inside_share`` of its 26 lattice rays hit the grown surface.
    """
    cloud = np.asarray(cloud, dtype=float)
    lo, hi = bounding_box(cloud)
    longest = float(np.max(hi - lo)) or 1.0
    spacing = median_spacing(cloud)
    size = max(longest / max(int(voxels), 4), min_spacing_factor * spacing)
    origin = lo - PAD * size
    shape = tuple(int(s) for s in np.floor((hi - lo) / size + 0.5).astype(np.int64) + 2 * PAD + 1)
    ijk = np.floor((cloud - origin) / size + 0.5).astype(np.int64)
    occ = np.zeros(shape, bool)
    occ[ijk[:, 0], ijk[:, 1], ijk[:, 2]] = True
    checkpoint(0.2)
    hits = ray_hits_share(occ, lambda f: checkpoint(0.2 + 0.8 * f))
    inside = occ | (hits > inside_share)
    return VoxelShape(inside=inside, occupied=occ, hits=hits, origin=origin, size=size)


def ray_hits_share(surface: np.ndarray, checkpoint: Checkpoint = no_checkpoint) -> np.ndarray:
    """Per voxel, the share of its 26 lattice rays that meet ``surface`` grown by one voxel."""
    count = lattice_hit_counts(grow_by_one(surface))
    checkpoint(1.0)
    return count / float(len(LATTICE_DIRECTIONS))


def supported_voxels(cloud: np.ndarray, vs: VoxelShape, *, block: int = 5, min_points: int = 3,
                     share: float = 0.05) -> np.ndarray:
    """The occupied voxels whose block of ``block``^3 voxels around them holds at least max(``min_points``,
    ``share`` x the median such count over the cloud's points) points: a stray point alone in the
    box's air is dropped, a surface patch (even one 10 x sparser than the rest) is kept. The median is
    taken over points, not voxels, so that strays (one voxel each) do not set it."""
    ijk = vs.index_of(cloud)
    counts = np.zeros(vs.occupied.shape, np.float64)
    np.add.at(counts, (ijk[:, 0], ijk[:, 1], ijk[:, 2]), 1.0)
    around = np.rint(ndimage.uniform_filter(counts, size=int(block), mode="constant") * float(block) ** 3)
    need = max(float(min_points), float(share) * float(np.median(around[ijk[:, 0], ijk[:, 1], ijk[:, 2]])))
    return vs.occupied & (around >= need)


def ray_interior(surface: np.ndarray, shares: tuple[float, ...],
                 checkpoint: Checkpoint = no_checkpoint) -> list[np.ndarray]:
    """The interiors bounded by the voxels ``surface``, one per inside share (``surface`` or more than
    that share of the lattice rays meet it grown by one), cavities filled: :func:`voxelize_interior`'s
    rule on given surface voxels, at several shares for one sweep of the rays."""
    hits = ray_hits_share(surface, checkpoint)
    return [fill_holes(surface | (hits > s)) for s in shares]


def betti_numbers(solid: np.ndarray, filled: bool = False) -> tuple[int, int, int]:
    """(beta0, beta1, beta2) of the union of the closed unit cubes of ``solid`` (a bool grid with
    an empty border): chi = V - E + F - C counted on the cubical complex. ``filled``: ``solid`` has
    no cavity (:func:`fill_holes`' output), so beta2 = 0 without labelling the rest."""
    s = np.pad(np.asarray(solid, bool), 1)
    # a face normal to axis a lies between the two cubes beside it along a, an edge along a between the
    # 4 cubes around it, a vertex between 8; beta0 from the 26-connected parts (``metrics/_voxels.c``,
    # scipy.ndimage.label's count with the full structure)
    c, faces, edges, verts = _voxels.cells(s.view(np.uint8), *s.shape)
    chi = verts - edges + faces - c
    b0 = _voxels.parts(s.view(np.uint8), *s.shape)
    if filled:
        return int(b0), int(b0 - chi), 0
    lab, nc = ndimage.label(~s)
    border = np.unique(np.concatenate([lab[0].ravel(), lab[-1].ravel(), lab[:, 0].ravel(), lab[:, -1].ravel(),
                                       lab[:, :, 0].ravel(), lab[:, :, -1].ravel()]))
    b2 = int(nc - np.count_nonzero(border))
    return int(b0), int(b0 + b2 - chi), b2


def wide_tunnels(solid: np.ndarray) -> int:
    """How many tunnels of ``solid`` a one-voxel thickening does not close, bounded from above: the sum
    over its 26-connected parts of min(beta1(part), beta1(part grown by one voxel)).

    Tunnels at most two voxels across (a stray point's voxel touching the surface twice, noise
    bridging a gap) are below the interior's resolution and made most ``missing_cycles`` false alarms
    (docs/diagnostics.md "Cycles"). The exact count, the persistent beta1 of solid -> grown (gudhi in
    the tests), is never above the bound: parts are grown apart, so the bound only keeps a tunnel that
    growing a part creates, it never hides a wide one.
    """
    cube = np.ones((3, 3, 3), bool)
    labels, _ = ndimage.label(np.asarray(solid, bool), structure=cube)
    total = 0
    for k, box in enumerate(ndimage.find_objects(labels), start=1):
        if box is None:
            continue
        part = labels[box] == k
        if part.sum() < 4:  # fewer than four cubes enclose nothing
            continue
        tunnels = betti_numbers(part)[1]
        if tunnels:
            total += min(tunnels, betti_numbers(grow_by_one(np.pad(part, 1)))[1])
    return total


def resolved_part(solid: np.ndarray, radius: float) -> np.ndarray:
    """``solid`` opened by a ball of ``radius`` voxels (Euclidean distance transforms): the union of the
    balls of that radius that fit inside it. A ring with a part thinner than the ball, or two parts
    joined through a neck thinner than it, loses its tunnel; a thicker ring keeps it."""
    core = ndimage.distance_transform_edt(solid) > radius
    if not core.any():
        return core
    return ndimage.distance_transform_edt(~core) <= radius


def resolved_radius(cloud: np.ndarray, vs: VoxelShape, diameter: float, voxels: float = 0.0) -> float:
    """The ball, in voxels, of :func:`resolved_part` for parts ``diameter`` median cloud spacings
    across, and at least ``voxels`` voxels across (the grid's resolution: where the box sets the voxel,
    a gap between two parts finer than it closes): half that in voxels, plus one voxel (half a voxel
    from an inside voxel's centre to the interior's boundary, and half a voxel by which the voxels
    holding surface points stand out beyond the surface on average); 0 when ``diameter`` is 0 (no test)."""
    if not diameter > 0:
        return 0.0
    return 0.5 * max(float(diameter) * median_spacing(cloud) / float(vs.size), float(voxels)) + 1.0


def firm_tunnels(cloud: np.ndarray, vs: VoxelShape, *, inside_share: float, strict_share: float, block: int = 5,
                 min_points: int = 3, share: float = 0.05, resolved_diameter: float = 0.0,
                 resolved_voxels: float = 0.0, checkpoint: Checkpoint = no_checkpoint) -> int:
    """The tunnels of the interior that survive each way it can invent one, bounded from above: the
    least :func:`wide_tunnels` count of the interior, of its part the sampling resolves
    (:func:`resolved_part`: parts at least ``resolved_diameter`` median spacings and ``resolved_voxels``
    voxels across; two thin branches passing closer than the cloud or the grid resolves join into a
    ring no thicker), of the interior
    rebuilt without the voxels of isolated points (:func:`supported_voxels`: a stray's voxel and its ray
    shadow bridge nothing) and of that one at the ``strict_share`` (a gap between noisy strands passes
    beta* but not the stricter share; a tube's inside passes both). Each interior keeps the resolved
    tunnels, so the least count never hides one; a false one goes where any lacks it
    (docs/diagnostics.md "Cycles")."""
    count = wide_tunnels(vs.solid())
    if count == 0:
        return 0
    radius = resolved_radius(cloud, vs, resolved_diameter, resolved_voxels)
    if radius > 0:
        count = min(count, wide_tunnels(resolved_part(vs.solid(), radius)))
        if count == 0:
            return 0
    kept = supported_voxels(cloud, vs, block=block, min_points=min_points, share=share)
    if np.array_equal(kept, vs.occupied):  # nothing isolated: the same rays, only the stricter share
        solids = [fill_holes(vs.occupied | (vs.hits > strict_share))]
    else:
        solids = ray_interior(kept, (inside_share, strict_share), checkpoint)
    for solid in solids:
        count = min(count, wide_tunnels(solid))
        if count == 0:
            break
    return count
