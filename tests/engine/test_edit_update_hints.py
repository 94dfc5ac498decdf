"""The far rays' hint tables an evaluation keeps for its curve samples (docs/boundedness.md 3.18): an
update's moved samples start their rays from the nearest old sample's hits, which changes no value and
spares walks; the edited curve's tables cover every sample (the kept ones' rows carried over); above the
byte budget none are kept and the update is exact all the same."""

from __future__ import annotations

from functools import lru_cache

import numpy as np

import skelcore.edit as E
from skelcore import evaluate, shapes
from skelcore.geometry import no_checkpoint, unique_rows
from skelcore.metrics import ray_hints, rays_kernel
from skelcore.metrics.boundedness import LoneRays, boundedness, in_raster_frame, prepared_cloud, rays_radius
from skelcore.params import Params


@lru_cache(maxsize=None)
def _base():
    sh = shapes.y_shape(12000, seed=3)
    return sh.cloud, evaluate(sh.cloud, curve=(sh.curve_vertices, sh.curve_edges))


def test_the_moved_samples_seeded_by_the_old_ones_give_the_same_bits_with_fewer_walks():
    cloud, ev = _base()
    ctx = ev.source.ctx
    kept = ctx.ray_hints[0]
    assert len(kept) == len(unique_rows(ctx.samples.points, no_checkpoint)[0])
    new, change = E.prune_branch(ev.curve.curve, 0)
    up = ev.update(change)
    old = {p.tobytes() for p in ctx.samples.points}
    moved = np.array([p for p in up.source.ctx.samples.points if p.tobytes() not in old])
    assert len(moved) > 50
    prep = prepared_cloud(ctx.bounded_cloud_n)
    q = in_raster_frame(unique_rows(moved, no_checkpoint)[0], prep.centre)
    p = ctx.params
    h = rays_radius(ctx.bounded_cloud_n, p.rays_radius_factor)
    plan = rays_kernel.exact_plan(q, h / p.rays_near_angle)
    rows = p.rays_rows
    runs = {}
    for name, seeds in (("alone", None), ("seeded", kept)):
        stats = np.zeros(6, np.int64)
        beta = rays_kernel.run_plan(prep.tree, plan, q, h, rows, 2 * rows, workers=1, stats=stats, seeds=seeds)
        runs[name] = beta, stats
    assert runs["alone"][0].tobytes() == runs["seeded"][0].tobytes()
    # more rays settled by a hint, fewer node visits (here 419k -> 459k of 504k rays, 0.69M -> 0.40M)
    assert runs["seeded"][1][5] > 1.05 * runs["alone"][1][5]
    assert runs["seeded"][1][0] < 0.8 * runs["alone"][1][0]
    np.testing.assert_array_equal(up.curve.sample_boundedness, evaluate(cloud, curve=new).curve.sample_boundedness)


def test_the_edited_curves_tables_cover_its_samples_the_kept_ones_carried_over():
    cloud, ev = _base()
    ctx = ev.source.ctx
    c = ev.curve.curve
    _, change = E.move_vertex(c, 4, c.vertices[4] + np.array([0.0, 0.004, 0.0]))
    up = ev.update(change)
    tables = up.source.ctx.ray_hints[0]
    prep = prepared_cloud(ctx.bounded_cloud_n)
    want = in_raster_frame(unique_rows(up.source.ctx.samples.points, no_checkpoint)[0], prep.centre)
    assert len(tables) == len(want) and tables.cloud is ctx.bounded_cloud_n
    assert {r.tobytes() for r in tables.origins} == {r.tobytes() for r in want}
    assert not tables._joined  # joined when an edit after this one reads them
    old = {o.tobytes(): t.tobytes() for o, t in zip(ctx.ray_hints[0].origins, ctx.ray_hints[0].tables)}
    carried = [old[o.tobytes()] == t.tobytes() for o, t in zip(tables.origins, tables.tables) if o.tobytes() in old]
    assert len(carried) > 0.8 * len(want) and all(carried)
    # an edit after it: seeded from these (a moved sample's table is the one its rays left)
    c2 = up.curve.curve
    again = up.update(E.move_vertex(c2, 9, c2.vertices[9] + np.array([0.0, 0.0, 0.004]))[1])
    t2 = again.source.ctx.ray_hints[0]
    assert len(t2) == len(unique_rows(again.source.ctx.samples.points, no_checkpoint)[0])
    by_origin = {o.tobytes(): t.tobytes() for o, t in zip(tables.origins, tables.tables)}
    assert sum(by_origin.get(o.tobytes()) == t.tobytes() for o, t in zip(t2.origins, t2.tables)) > 0.8 * len(t2)
    fresh = evaluate(cloud, curve=again.curve.curve)
    np.testing.assert_array_equal(again.curve.sample_boundedness, fresh.curve.sample_boundedness)


def test_above_the_budget_no_tables_are_kept_and_the_update_stays_exact(monkeypatch):
    monkeypatch.setattr(ray_hints, "TABLES_MOST_BYTES", 1000)
    import skelcore.metrics.boundedness as B

    monkeypatch.setattr(B, "TABLES_MOST_BYTES", 1000)
    sh = shapes.y_shape(3000, seed=5)
    ev = evaluate(sh.cloud, curve=(sh.curve_vertices, sh.curve_edges))
    assert ev.source.ctx.ray_hints == []
    new, change = E.prune_branch(ev.curve.curve, 1)
    up = ev.update(change)
    assert up.source.ctx.ray_hints == []
    np.testing.assert_array_equal(up.curve.sample_boundedness, evaluate(sh.cloud, curve=new).curve.sample_boundedness)


def test_tables_of_another_cloud_are_not_used(monkeypatch):
    import skelcore.metrics.boundedness as B

    cloud, ev = _base()
    ctx = ev.source.ctx
    kept = ctx.ray_hints[0]
    seen = []
    real = B.run_plan

    def spy(*a, **kw):
        seen.append(kw.get("seeds"))
        return real(*a, **kw)

    monkeypatch.setattr(B, "run_plan", spy)
    q = ctx.samples.points[:5] + 1e-4
    a = B.boundedness_rays(ctx.bounded_cloud_n, q, share_far_field=False, seeds=kept)
    b = B.boundedness_rays(ctx.bounded_cloud_n.copy(), q, share_far_field=False, seeds=kept)
    assert seen[0] is kept and seen[1] is None and a.tobytes() == b.tobytes()
    got = ray_hints.seeds_for(kept, kept.origins[:5] + 1e-3, [0])
    assert got is not None and (got >= 0).all()


def test_the_lone_rays_setup_gives_boundednesss_bits_and_tables_inline_or_pooled():
    """:class:`LoneRays` (the setup taken once for an update's calls) against ``boundedness`` with every
    pair: the same beta and the same kept tables, seeded or not, its one stream on the calling thread
    (``workers=1``, no checkpoint) or the kernel's pool (a checkpoint to poll)."""
    cloud, ev = _base()
    ctx = ev.source.ctx
    cast = LoneRays.of(ctx.bounded_cloud_n, ctx.params)
    q = ctx.samples.points[::3]
    q = np.vstack([q, q[:5]])  # copies are scored once
    for seeds in (None, ctx.ray_hints[0]):
        for workers in (1, None):
            got, want = [], []
            beta = cast(q, workers=workers, seeds=seeds, keep=got)
            ref = boundedness(ctx.bounded_cloud_n, q, params=ctx.params, share_far_field=False, workers=workers,
                              seeds=seeds, keep=want, checkpoint=lambda f: None)
            assert beta.tobytes() == ref.tobytes()
            assert got[0].tables.tobytes() == want[0].tables.tobytes()
            assert got[0].origins.tobytes() == want[0].origins.tobytes()
    q_r = cast.in_frame(unique_rows(q, no_checkpoint)[0])
    seeds = cast.seeds(ctx.ray_hints[0])
    asked = seeds.nearest(q_r[::-1])  # asked for more queries at once, taken in rows
    got, want = [], []
    beta = cast.distinct(q_r[1::2], seeds=seeds, keep=got, workers=1, nearest=(asked[0][-2::-2], asked[1][-2::-2]))
    assert beta.tobytes() == cast.distinct(q_r[1::2], seeds=seeds, keep=want, workers=1).tobytes()
    assert got[0].tables.tobytes() == want[0].tables.tobytes()
    assert cast(q[:0]).shape == (0,)
    assert LoneRays.of(ctx.bounded_cloud_n, Params(boundedness_method="paper")) is None
