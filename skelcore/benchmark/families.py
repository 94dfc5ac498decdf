"""The benchmark's shape families, each with an exact curve skeleton and radius.

Random smooth tubes with varying radius; an elliptic (flattened) tube; Y, T and X junctions with
unequal radii; plant-like trees of 2-4 levels; a torus and a genus-2 "theta" shape (legitimate
cycles); a five-finger hand; a thin plate with a rim (labelled: its curve skeleton is ill-posed).
Every family is a function ``(name, rng, **params) -> BenchShape`` in :data:`FAMILIES`; random
families draw again (same generator, so still deterministic) until :func:`~.tubes.check_geometry`
accepts the shape: canal conditions with margins and no two parts touching except at a node.
Lengths are in arbitrary units (shapes span about 2-5); compare and evaluate normalize anyway.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from .tubes import BenchShape, GeometryError, Plate, Tube, check_geometry

__all__ = ["FAMILIES", "make_shape", "random_tube", "elliptic_tube", "junction", "tree", "torus",
           "genus2", "hand", "plate"]

_DRAWS = 200


def _unit(v) -> np.ndarray:
    v = np.asarray(v, float)
    return v / np.linalg.norm(v)


def _perpendicular(d: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    while True:
        p = np.cross(d, rng.normal(size=3))
        if np.linalg.norm(p) > 1e-6:
            return _unit(p)


def _rotate(d: np.ndarray, tilt: float, azimuth: float) -> np.ndarray:
    """``d`` tilted by ``tilt`` radians towards the perpendicular at ``azimuth`` around it."""
    a = np.array([1.0, 0.0, 0.0]) if abs(d[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = _unit(np.cross(d, a))
    w = np.cross(d, u)
    return _unit(np.cos(tilt) * d + np.sin(tilt) * (np.cos(azimuth) * u + np.sin(azimuth) * w))


def _draw(build: Callable[[], BenchShape], name: str) -> BenchShape:
    for _ in range(_DRAWS):
        shape = build()
        try:
            check_geometry(shape)
        except GeometryError:
            continue
        return shape
    raise GeometryError(f"{name}: no valid shape in {_DRAWS} draws; relax the parameters")


def _straight(a, b, ra: float, rb: float, start: int, end: int, k: int = 4) -> Tube:
    u = np.linspace(0.0, 1.0, k)[:, None]
    return Tube(points=(1 - u) * np.asarray(a, float) + u * np.asarray(b, float),
                radii=np.linspace(ra, rb, k), start=start, end=end)


def random_tube(name: str, rng: np.random.Generator, *, radius: float = 0.15, steps: int = 7,
                step_length: float = 0.6, max_turn_deg: float = 50.0, variation: float = 0.3) -> BenchShape:
    """A tube along a random smooth curve (a random walk of ``steps`` steps turning at most
    ``max_turn_deg``, through a cubic spline) whose radius varies by +-``variation``."""
    def build() -> BenchShape:
        d = _unit(rng.normal(size=3))
        pts = [np.zeros(3)]
        for _ in range(steps):
            d = _rotate(d, np.radians(rng.uniform(0, max_turn_deg)), rng.uniform(0, 2 * np.pi))
            pts.append(pts[-1] + step_length * d)
        pts = np.array(pts)
        radii = radius * (1 + variation * rng.uniform(-1, 1, len(pts)))
        nodes = pts[[0, -1]]
        return BenchShape(name, "tube", nodes, (Tube(pts, radii, start=0, end=1),),
                          params=dict(radius=radius, steps=steps, step_length=step_length,
                                      max_turn_deg=max_turn_deg, variation=variation))
    return _draw(build, name)


def elliptic_tube(name: str, rng: np.random.Generator, *, radius: float = 0.3, flatten: float = 0.4,
                  length: float = 3.0, bend: float = 0.25) -> BenchShape:
    """A gently bent tube with elliptic cross-sections (semi-axes r and ``flatten`` r, r varying by
    +-15 %) and half-ellipsoid caps; its radius is the minor semi-axis (the largest inscribed ball)."""
    def build() -> BenchShape:
        x = np.linspace(0.0, length, 5)
        off = bend * rng.uniform(-1, 1, (5, 2)) * np.array([[0.0, 0.0], *[[1.0, 1.0]] * 3, [0.0, 0.0]])
        pts = np.column_stack([x, off])
        radii = radius * (1 + 0.15 * rng.uniform(-1, 1, 5))
        return BenchShape(name, "elliptic", pts[[0, -1]], (Tube(pts, radii, flatten=flatten, start=0, end=1),),
                          params=dict(radius=radius, flatten=flatten, length=length, bend=bend))
    return _draw(build, name)


_JUNCTIONS = {
    # kind: [(direction angle in the xy-plane, degrees; radius at the node; length)]
    "y": [(90.0, 0.30, 2.0), (210.0, 0.20, 1.6), (330.0, 0.12, 1.4)],
    "t": [(0.0, 0.25, 1.8), (180.0, 0.25, 1.8), (90.0, 0.14, 1.6)],
    "x": [(0.0, 0.25, 1.8), (180.0, 0.25, 1.8), (70.0, 0.15, 1.5), (250.0, 0.15, 1.5)],
}


def junction(name: str, rng: np.random.Generator, *, kind: str = "y", taper: float = 0.85) -> BenchShape:
    """Straight arms of unequal radii meeting at the origin: ``kind`` "y" (three arms, 120 degrees
    apart), "t" (a bar and a thinner stem at a right angle) or "x" (two bars crossing at 70 degrees).
    Each arm's radius tapers to ``taper`` times its value at the node."""
    del rng  # deterministic family
    arms = _JUNCTIONS[kind]
    nodes = [np.zeros(3)]
    tubes = []
    for k, (deg, r, length) in enumerate(arms, start=1):
        end = length * np.array([np.cos(np.radians(deg)), np.sin(np.radians(deg)), 0.0])
        nodes.append(end)
        tubes.append(_straight(nodes[0], end, r, r * taper, 0, k))
    shape = BenchShape(name, "junction", np.array(nodes), tuple(tubes), params=dict(kind=kind, taper=taper, arms=arms))
    check_geometry(shape)
    return shape


def tree(name: str, rng: np.random.Generator, *, levels: int = 3, trunk_length: float = 1.6,
         trunk_radius: float = 0.14, spread_deg: tuple[float, float] = (25.0, 45.0),
         length_ratio: tuple[float, float] = (0.6, 0.8), radius_ratio: tuple[float, float] = (0.65, 0.8),
         taper: float = 0.9, bend: float = 0.08) -> BenchShape:
    """A plant-like tree of ``levels`` levels (the trunk is level 1): every branch ends in a fork of
    2-3 children (2 beyond level 2), tilted ``spread_deg`` from it, shorter and thinner by the ratios,
    gently bent (mid-point offset up to ``bend`` x length), tapering to ``taper`` x its base radius."""
    if not 2 <= levels <= 4:
        raise ValueError("levels must be 2, 3 or 4")

    def build() -> BenchShape:
        nodes = [np.zeros(3)]
        tubes: list[Tube] = []

        def grow(start: int, d: np.ndarray, length: float, r0: float, level: int) -> None:
            a = nodes[start]
            b = a + length * d
            mid = (a + b) / 2 + bend * length * rng.uniform(-1, 1) * _perpendicular(d, rng)
            nodes.append(b)
            end = len(nodes) - 1
            r1 = r0 * taper
            tubes.append(Tube(np.array([a, mid, b]), np.array([r0, (r0 + r1) / 2, r1]), start=start, end=end))
            if level >= levels:
                return
            k = int(rng.integers(2, 4)) if level <= 2 else 2
            az0 = rng.uniform(0, 2 * np.pi)
            for j in range(k):
                az = az0 + 2 * np.pi * j / k + rng.uniform(-0.3, 0.3)
                child = _rotate(d, np.radians(rng.uniform(*spread_deg)), az)
                child = _unit(child + 0.3 * np.array([0.0, 0.0, 1.0]))  # plants grow up
                grow(end, child, length * rng.uniform(*length_ratio), r1 * rng.uniform(*radius_ratio), level + 1)

        grow(0, np.array([0.0, 0.0, 1.0]), trunk_length, trunk_radius, 1)
        return BenchShape(name, "tree", np.array(nodes), tuple(tubes),
                          params=dict(levels=levels, trunk_length=trunk_length, trunk_radius=trunk_radius,
                                      spread_deg=list(spread_deg), length_ratio=list(length_ratio),
                                      radius_ratio=list(radius_ratio), taper=taper, bend=bend))
    return _draw(build, name)


def _circle(radius: float, n: int = 16, z: float = 0.0) -> np.ndarray:
    a = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return np.column_stack([radius * np.cos(a), radius * np.sin(a), np.full(n, z)])


def torus(name: str, rng: np.random.Generator, *, R: float = 1.0, r: float = 0.28, wobble: float = 0.15) -> BenchShape:
    """A ring: a closed tube around the z axis (centre radius R), tube radius r varying by +-``wobble``
    around it (one legitimate cycle)."""
    del rng
    a = np.linspace(0, 2 * np.pi, 16, endpoint=False)
    tube = Tube(_circle(R), r * (1 + wobble * np.cos(2 * a)), closed=True)
    shape = BenchShape(name, "torus", np.empty((0, 3)), (tube,), params=dict(R=R, r=r, wobble=wobble))
    check_geometry(shape)
    return shape


def genus2(name: str, rng: np.random.Generator, *, R: float = 1.0, r_arc: float = 0.2, r_bar: float = 0.15) -> BenchShape:
    """A "theta": two half circles of radius R and a straight bar joining their meeting points
    (0, +-R, 0) (two junctions of degree 3, two legitimate cycles: genus 2)."""
    del rng
    top, bottom = np.array([0.0, R, 0.0]), np.array([0.0, -R, 0.0])
    left = np.radians(np.linspace(90, 270, 7))
    right = np.radians(np.linspace(90, -90, 7))
    arc = lambda ang: np.column_stack([R * np.cos(ang), R * np.sin(ang), np.zeros(len(ang))])  # noqa: E731
    tubes = (Tube(arc(left), np.full(7, r_arc), start=0, end=1),
             Tube(arc(right), np.full(7, r_arc), start=0, end=1),
             _straight(top, bottom, r_bar, r_bar, 0, 1))
    shape = BenchShape(name, "genus2", np.array([top, bottom]), tubes, params=dict(R=R, r_arc=r_arc, r_bar=r_bar))
    check_geometry(shape)
    return shape


_FINGERS = [  # (angle from +z in the xz-plane, degrees; length from the palm centre; radius at the palm)
    (-95.0, 1.00, 0.10), (-45.0, 1.25, 0.09), (-15.0, 1.35, 0.09), (15.0, 1.28, 0.085), (45.0, 1.05, 0.075)]


def hand(name: str, rng: np.random.Generator, *, palm_radius: float = 0.4, palm_length: float = 1.0,
         curl: float = 0.06) -> BenchShape:
    """A five-finger hand: a thick palm tube from the wrist (origin) to the palm centre (0, 0,
    ``palm_length``), where a thumb and four fingers start (one node of degree 6); fingers taper to
    0.8 x and curl by ``curl`` x their length towards +y."""
    del rng
    wrist, palm = np.zeros(3), np.array([0.0, 0.0, palm_length])
    nodes = [wrist, palm]
    tubes = [_straight(wrist, palm, palm_radius * 0.9, palm_radius, 0, 1)]
    for deg, length, r in _FINGERS:
        d = np.array([np.sin(np.radians(deg)), 0.0, np.cos(np.radians(deg))])
        tip = palm + length * d
        mid = palm + 0.6 * length * d + np.array([0.0, curl * length, 0.0])
        nodes.append(tip)
        tubes.append(Tube(np.array([palm, mid, tip]), np.array([r, 0.9 * r, 0.8 * r]), start=1, end=len(nodes) - 1))
    shape = BenchShape(name, "hand", np.array(nodes), tuple(tubes),
                       params=dict(palm_radius=palm_radius, palm_length=palm_length, curl=curl, fingers=_FINGERS))
    check_geometry(shape)
    return shape


def plate(name: str, rng: np.random.Generator, *, radius: float = 1.0, half_thickness: float = 0.04,
          rim_radius: float = 0.12) -> BenchShape:
    """A thin disc (plate) with a round rim (a closed tube of radius ``rim_radius`` along its edge).
    Its medial axis is a sheet: a curve skeleton is ill-posed; the reference is the rim's centre circle."""
    del rng
    rim = Tube(_circle(radius), np.full(16, rim_radius), closed=True)
    return BenchShape(name, "plate", np.empty((0, 3)), (rim,), plate=Plate(radius, half_thickness),
                      ill_posed="curve skeleton ill-posed: the plate's medial axis is a sheet; the reference "
                                "is only the rim's centre circle",
                      params=dict(radius=radius, half_thickness=half_thickness, rim_radius=rim_radius))


FAMILIES: dict[str, Callable[..., BenchShape]] = {
    "tube": random_tube, "elliptic": elliptic_tube, "junction": junction, "tree": tree, "torus": torus,
    "genus2": genus2, "hand": hand, "plate": plate,
}


def make_shape(name: str, family: str, seed: np.random.SeedSequence | int, **params) -> BenchShape:
    """The shape ``name`` of ``family`` with ``params``, drawn from its own seed."""
    if family not in FAMILIES:
        raise ValueError(f"unknown shape family {family!r} (known: {', '.join(FAMILIES)})")
    return FAMILIES[family](name, np.random.default_rng(seed), **params)
