/* Compiled ring extraction of SkelScope's curve centeredness (docs/metrics.md 3, paper Eq. 11; design and
 * numbers: docs/performance.md, section 6.5).
 *
 * For a curve sample p with unit direction u and plane axes g, h: the slab points x (|u . (x - p)| < half),
 * their plane coordinates fg = g . (x - p), fh = h . (x - p) and distance hypot(fg, fh), sorted by distance
 * (equal distances in the grid's row order) and cut by the ring rule (keep while the next distance is
 * < growth x the last kept one).  Only the sorted list's head up to the ring's end matters.  The slab points
 * within 2-D distance R of p lie in the ball of radius sqrt(R^2 + half^2) around p, so the grid cells meeting
 * that ball (and the slab) hold them: sorted, they are the head of the whole slab's sorted list, and the ring
 * is final when it breaks inside them, when growth x its last distance <= R (the next point, beyond R, breaks
 * it) or when the ball's cells are all the grid's.  Otherwise R doubles (at least to growth x the last): the
 * new cells' points join those already found beyond the last R, and the ones now within R, sorted, extend
 * the head (each point is found, and sorted, once).
 *
 * Every value is numpy's, operation for operation (the array code in centeredness.py stays the reference):
 * x - p per coordinate, dot products as ((a0 b0 + a1 b1) + a2 b2), libm's hypot, and the order of a stable
 * sort by distance in grid order: an LSD radix sort of the distances' bits (non-negative doubles order as
 * their bits; NaN last, as numpy's sort), runs of equal distances then by grid row.  Built without FMA
 * contraction (the extension's flags), as numpy's loops are.  The order and the ring rule read square roots
 * of fg^2 + fh^2 where they settle them as hypot would, hypot where two distances come within 1e-13
 * (extend_head; docs/performance.md 6.10).  The rings go into buffers the caller lends and keeps.
 *
 * Plain C with the buffer protocol (no numpy headers at build time); the entry point releases the GIL.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include "_pairwise_sum.h"
#ifdef __SSE2__
#include <emmintrin.h>
#endif

#define SMALL_SORT 32        /* up to this many keys an insertion sort; a bucket of over 4 x this: radix */
#define MARGIN 1e-9          /* relative allowance of the cell tests for round-off (a superset of cells is harmless) */
/* relative: a pool point whose fg^2 + fh^2 exceeds (R (1 + this))^2 lies beyond R whatever the rounding of the
 * square (a few units in the last place) and of hypot (under one), so its distance is not computed yet */
#define REACH_SLACK 1e-6
/* relative: where fg^2 + fh^2 lies in [SQ_LO, SQ_HI] (no underflow or overflow of the squares), its square
 * root and libm's hypot differ by a few units in the last place; two distances farther apart than this are
 * ordered (and compared with R or a ring's growth) the same by either, nearer ones are decided by hypot */
#define CLOSE 1e-13
#define SQ_LO 1e-290
#define SQ_HI 1e290
/* where a sample's first ball does not end its ring, the second reaches at least HINT x growth x the last ring
 * distance of the sample before it (a neighbour along the curve as a rule): a tube's cross-section in two balls,
 * not five doubled ones; a ring the first ball ends (a neuron's thin branch) costs what it did.  The balls
 * only find the ring, so any reach gives the same ring (docs/performance.md 6.10) */
#define HINT 1.25

typedef struct {             /* slab points: distance (in the pool its square, extend_head), plane coordinates, grid row */
    double *d, *fg, *fh;
    int32_t *row;
    Py_ssize_t n, cap;
} Pts;

static int pts_reserve(Pts *a, Py_ssize_t need) {
    if (need <= a->cap) return 1;
    Py_ssize_t cap = a->cap ? a->cap : 4096;
    while (cap < need) cap *= 2;
    void *p;
#define GROW(f, t) p = realloc(a->f, (size_t)cap * sizeof(t)); if (!p) return 0; a->f = (t *)p;
    GROW(d, double) GROW(fg, double) GROW(fh, double) GROW(row, int32_t)
#undef GROW
    a->cap = cap;
    return 1;
}

static void pts_free(Pts *a) { free(a->d); free(a->fg); free(a->fh); free(a->row); }

typedef struct {             /* sort scratch: keys and positions, twice, the pool positions sorted, buckets */
    uint64_t *key, *key2;
    int32_t *idx, *idx2, *from;
    uint32_t *bucket;
    Py_ssize_t cap;
} Scratch;

static int scratch_reserve(Scratch *a, Py_ssize_t need) {
    if (need <= a->cap) return 1;
    Py_ssize_t cap = a->cap ? a->cap : 4096;
    while (cap < need) cap *= 2;
    void *p;
#define GROW(f, t) p = realloc(a->f, (size_t)cap * sizeof(t)); if (!p) return 0; a->f = (t *)p;
    GROW(key, uint64_t) GROW(key2, uint64_t) GROW(idx, int32_t) GROW(idx2, int32_t) GROW(from, int32_t)
#undef GROW
    p = realloc(a->bucket, ((size_t)cap + 2) * sizeof(uint32_t));
    if (!p) return 0;
    a->bucket = (uint32_t *)p;
    a->cap = cap;
    return 1;
}

static void scratch_free(Scratch *a) {
    free(a->key); free(a->key2); free(a->idx); free(a->idx2); free(a->from); free(a->bucket);
}

/* A distance's sort key: a non-negative double orders as its bits; every NaN after +inf (numpy's sorts put
 * NaN last). */
static inline uint64_t dist_key(double d) {
    uint64_t k;
    if (d != d) return UINT64_MAX;
    memcpy(&k, &d, sizeof k);
    return k;
}

/* Stable insertion sort of (key, idx)[0..n) by key. */
static void insertion(uint64_t *key, int32_t *idx, Py_ssize_t n) {
    for (Py_ssize_t i = 1; i < n; i++) {
        const uint64_t k = key[i];
        const int32_t at = idx[i];
        Py_ssize_t j = i;
        while (j > 0 && key[j - 1] > k) {
            key[j] = key[j - 1];
            idx[j] = idx[j - 1];
            j--;
        }
        key[j] = k;
        idx[j] = at;
    }
}

/* Stable LSD radix sort of (key, idx)[0..n) by key, with (tk, ti)[0..n) as scratch; bytes all keys share
 * are skipped.  The result is left in (key, idx). */
static void radix(uint64_t *key, int32_t *idx, uint64_t *tk, int32_t *ti, Py_ssize_t n) {
    uint32_t count[8][256];
    memset(count, 0, sizeof count);
    uint64_t *k0 = key;
    int32_t *i0 = idx;
    for (Py_ssize_t i = 0; i < n; i++) {
        const uint64_t k = key[i];
        for (int b = 0; b < 8; b++) count[b][(k >> (8 * b)) & 255]++;
    }
    for (int b = 0; b < 8; b++) {
        uint32_t *cnt = count[b];
        if (cnt[(key[0] >> (8 * b)) & 255] == (uint32_t)n) continue;
        uint32_t sum = 0;
        for (int v = 0; v < 256; v++) {
            const uint32_t t = cnt[v];
            cnt[v] = sum;
            sum += t;
        }
        for (Py_ssize_t i = 0; i < n; i++) {
            const uint32_t at = cnt[(key[i] >> (8 * b)) & 255]++;
            tk[at] = key[i];
            ti[at] = idx[i];
        }
        uint64_t *sk = key; key = tk; tk = sk;
        int32_t *si = idx; idx = ti; ti = si;
    }
    if (key != k0) {
        memcpy(k0, key, (size_t)n * sizeof(uint64_t));
        memcpy(i0, idx, (size_t)n * sizeof(int32_t));
    }
}

/* s->idx[0..n) = positions 0..n-1 in the stable order of key[0..n) (equal keys keep their positions' order):
 * a counting sort into about n buckets of equal spans of the keys (a key's bucket grows with the key: NaN's
 * last), then each bucket by insertion (a long one by radix). */
static void stable_order(Scratch *s, Py_ssize_t n) {
    uint64_t *key = s->key, *key2 = s->key2;
    int32_t *idx = s->idx, *idx2 = s->idx2;
    for (Py_ssize_t i = 0; i < n; i++) idx[i] = (int32_t)i;
    if (n <= SMALL_SORT) {
        insertion(key, idx, n);
        return;
    }
    uint64_t lo = UINT64_MAX, hi = 0;
    for (Py_ssize_t i = 0; i < n; i++) {
        const uint64_t k = key[i];
        if (k == UINT64_MAX) continue;
        lo = k < lo ? k : lo;
        hi = k > hi ? k : hi;
    }
    if (lo > hi) return;  /* every distance NaN: the order as it is */
    int shift = 0;
    while (((hi - lo) >> shift) >= (uint64_t)n) shift++;
    const Py_ssize_t nb = (Py_ssize_t)((hi - lo) >> shift) + 2;  /* the last bucket: NaN */
    uint32_t *cnt = s->bucket;
    memset(cnt, 0, (size_t)nb * sizeof(uint32_t));
#define BUCKET(k) ((k) == UINT64_MAX ? nb - 1 : (Py_ssize_t)(((k) - lo) >> shift))
    for (Py_ssize_t i = 0; i < n; i++) cnt[BUCKET(key[i])]++;
    uint32_t sum = 0;
    for (Py_ssize_t b = 0; b < nb; b++) {
        const uint32_t t = cnt[b];
        cnt[b] = sum;
        sum += t;
    }
    for (Py_ssize_t i = 0; i < n; i++) {
        const uint32_t at = cnt[BUCKET(key[i])]++;
        key2[at] = key[i];
        idx2[at] = idx[i];
    }
#undef BUCKET
    /* cnt[b] is now bucket b's end */
    Py_ssize_t start = 0;
    for (Py_ssize_t b = 0; b < nb - 1; b++) {
        const Py_ssize_t end = (Py_ssize_t)cnt[b], m = end - start;
        if (m > 4 * SMALL_SORT) {
            Py_ssize_t tied = 1;  /* a long bucket of one distance (a tube's exact radius) is in order already */
            while (tied < m && key2[start + tied] == key2[start]) tied++;
            if (tied < m) radix(key2 + start, idx2 + start, key + start, idx + start, m);
        } else if (m > 1) {
            insertion(key2 + start, idx2 + start, m);
        }
        start = end;
    }
    memcpy(s->idx, idx2, (size_t)n * sizeof(int32_t));
}

static inline Py_ssize_t lower_bound(const int64_t *keys, Py_ssize_t lo, Py_ssize_t hi, int64_t want) {
    while (lo < hi) {
        Py_ssize_t mid = lo + (hi - lo) / 2;
        if (keys[mid] < want) lo = mid + 1;
        else hi = mid;
    }
    return lo;
}

typedef struct {
    const double *X, *Y, *Z;        /* the grid's points, columns, rows in grid (cell) order */
    const int64_t *keys, *starts, *counts;  /* occupied cells, ascending keys i + d0 (j + d1 k) */
    const int64_t *lines;           /* per line (j, k) of cells: its first occupied cell (d1 d2 + 1 entries) */
    const double *centres;          /* (cells, 3) */
    Py_ssize_t n_cells;
    double lo[3], cell, half_cell, size;
    int64_t dims[3];
} Grid;

typedef struct {             /* one sample, and what its search holds */
    double p[3], u[3], g[3], h[3], half, reach, R, ball;
    int whole;
    Pts pool;                /* slab points found, not yet in the head (beyond the last R), in grid order */
    Pts spare;               /* the pool's merge buffer */
    Pts head;                /* the sorted head of the slab's list */
    Scratch sort;
    int approx;              /* order by square roots first (hypot only where two come close): 0 after a sample
                              * whose distances mostly came close (a tube's exact radius), for the call's rest */
    char *taken;             /* per cell: its points found (cleared after each sample through `cells`) */
    int32_t *cells;
    Py_ssize_t n_taken;
} Search;

/* A call's point and sort buffers, kept for the next calls (at most KEPT sets, one per call running at once):
 * a ring of a whole slab grows them to tens of thousands of rows, and fresh ones each call cost their page
 * faults again (evaluate's spans of 4 samples on a neuron: about a quarter of the kernel's time).  Taken and given
 * back while the caller holds the GIL, so no lock. */
#define KEPT 4
typedef struct { Pts pool, spare, head; Scratch sort; } Buffers;
static Buffers kept[KEPT];
static int n_kept = 0;

static void lend_buffers(Search *S) {
    if (n_kept == 0) return;
    const Buffers *b = &kept[--n_kept];
    S->pool = b->pool; S->spare = b->spare; S->head = b->head; S->sort = b->sort;
}

static void keep_buffers(Search *S) {
    if (n_kept < KEPT) {
        Buffers *b = &kept[n_kept++];
        b->pool = S->pool; b->spare = S->spare; b->head = S->head; b->sort = S->sort;
        return;
    }
    pts_free(&S->pool); pts_free(&S->spare); pts_free(&S->head); scratch_free(&S->sort);
}

/* Cell `at`'s slab points into the pool, when the cell can meet the slab (and, unless whole, the ball) and
 * was not taken before. */
static inline int take_cell(const Grid *G, Py_ssize_t at, Search *S) {
    if (S->taken[at]) return 1;
    const double p0 = S->p[0], p1 = S->p[1], p2 = S->p[2];
    const double u0 = S->u[0], u1 = S->u[1], u2 = S->u[2];
    const double g0 = S->g[0], g1 = S->g[1], g2 = S->g[2], h0 = S->h[0], h1 = S->h[1], h2 = S->h[2];
    const double half = S->half;
    const double *cc = G->centres + 3 * at;
    const double v0 = cc[0] - p0, v1 = cc[1] - p1, v2 = cc[2] - p2;
    if (!(fabs(v0 * u0 + v1 * u1 + v2 * u2) <= S->reach)) return 1;
    if (!S->whole && !(sqrt(v0 * v0 + v1 * v1 + v2 * v2) <= S->ball)) return 1;
    S->taken[at] = 1;
    S->cells[S->n_taken++] = (int32_t)at;
    const Py_ssize_t r0 = (Py_ssize_t)G->starts[at], r1 = r0 + (Py_ssize_t)G->counts[at];
    Pts *pool = &S->pool;
    if (!pts_reserve(pool, pool->n + (r1 - r0))) return 0;
    Py_ssize_t n = pool->n;
    for (Py_ssize_t r = r0; r < r1; r++) {  /* every point written, kept by the count: no branch to mispredict */
        const double x = G->X[r] - p0, y = G->Y[r] - p1, z = G->Z[r] - p2;
        const double fg = x * g0 + y * g1 + z * g2, fh = x * h0 + y * h1 + z * h2;
        pool->d[n] = fg * fg + fh * fh;  /* its square, a bound: the distance is taken in extend_head */
        pool->fg[n] = fg;
        pool->fh[n] = fh;
        pool->row[n] = (int32_t)r;
        n += fabs(x * u0 + y * u1 + z * u2) < half;
    }
    pool->n = n;
    return 1;
}

/* The box of cells (i0, i1, j0, j1, k0, k1) that holds the ball of radius rad around p; 1 when it is the
 * whole grid. */
static int ball_box(const Grid *G, const double *p, double rad, int64_t *box) {
    int whole = 1;
    for (int a = 0; a < 3; a++) {
        const double lo = floor((p[a] - rad - G->lo[a]) / G->cell) - 1.0;
        const double hi = floor((p[a] + rad - G->lo[a]) / G->cell) + 1.0;
        const int64_t top = G->dims[a] - 1;
        box[2 * a] = lo > 0.0 ? (lo < (double)top ? (int64_t)lo : top) : 0;  /* NaN: the whole axis */
        box[2 * a + 1] = hi < (double)top ? (hi > 0.0 ? (int64_t)hi : 0) : top;
        whole &= box[2 * a] == 0 && box[2 * a + 1] == top;
    }
    return whole;
}

/* The cells i0..i1 of line (j, k) of the box narrowed to those whose centres may pass take_cell's tests: within
 * the ball's reach of p (a chord of the line) and, where the line crosses the slab at an angle, within the
 * slab's reach of its mid-plane; 0 when none may.  A superset, by a cell and a relative allowance on each side
 * (the centres as the grid computes them, lo + (index + 1/2) cell, may differ from these in the last place):
 * the cells it leaves out take_cell would refuse, and the ones kept keep their order. */
static inline int line_span(const Grid *G, const Search *S, int64_t j, int64_t k, int64_t *i0, int64_t *i1) {
    const double cell = G->cell;
    const double vy = G->lo[1] + ((double)j + 0.5) * cell - S->p[1];
    const double vz = G->lo[2] + ((double)k + 0.5) * cell - S->p[2];
    const double slack = (G->size + S->ball + S->reach + cell) * 1e-9;
    const double ball = S->ball + slack, chord2 = ball * ball - (vy * vy + vz * vz);
    const double u0 = S->u[0], a = vy * S->u[1] + vz * S->u[2], reach = S->reach + slack;
    if (chord2 != chord2 || a != a) return 1;  /* NaN: the whole span */
    if (chord2 < 0.0) return 0;
    const double chord = sqrt(chord2);
    double lo = S->p[0] - chord, hi = S->p[0] + chord;  /* the centres' x within the ball's reach */
    if (fabs(u0) * cell > 1e-3 * reach) {  /* the line crosses the slab: centres' x with |(x - p0) u0 + a| <= reach */
        const double e0 = S->p[0] + (-reach - a) / u0, e1 = S->p[0] + (reach - a) / u0;
        lo = fmax(lo, fmin(e0, e1));
        hi = fmin(hi, fmax(e0, e1));
    } else if (fabs(a) > reach + fabs(u0) * chord * 2.0) {  /* along the slab: the line as a whole out of it */
        return 0;
    }
    const double f0 = floor((lo - G->lo[0]) / cell - 0.5) - 1.0, f1 = ceil((hi - G->lo[0]) / cell - 0.5) + 1.0;
    if (f0 > (double)*i0) *i0 = f0 < (double)*i1 ? (int64_t)f0 : *i1;  /* NaN: as it was */
    if (f1 < (double)*i1) *i1 = f1 > (double)*i0 ? (int64_t)f1 : *i0;
    return f0 <= f1 || f0 != f0 || f1 != f1;
}

/* This round's new cells into the pool: those of the box meeting the ball (every cell when whole). */
static int gather(const Grid *G, Search *S, const int64_t *box) {
    if (S->whole) {
        for (Py_ssize_t at = 0; at < G->n_cells; at++)
            if (!take_cell(G, at, S)) return 0;
        return 1;
    }
    const int64_t d0 = G->dims[0], d1 = G->dims[1];
    for (int64_t k = box[4]; k <= box[5]; k++) {
        for (int64_t j = box[2]; j <= box[3]; j++) {
            const int64_t line = j + d1 * k;
            const Py_ssize_t end = (Py_ssize_t)G->lines[line + 1];
            if ((Py_ssize_t)G->lines[line] == end) continue;  /* no occupied cell on the line */
            int64_t i0 = box[0], i1 = box[1];
            if (!line_span(G, S, j, k, &i0, &i1)) continue;
            const int64_t first = i0 + d0 * line, last = i1 + d0 * line;
            Py_ssize_t at = lower_bound(G->keys, (Py_ssize_t)G->lines[line], end, first);
            for (; at < end && G->keys[at] <= last; at++)
                if (!take_cell(G, at, S)) return 0;
        }
    }
    return 1;
}

/* The pool in grid order again after a round: its old points [0, a) and the round's [a, n) (each in grid
 * order) merged by row. */
static int merge_pool(Search *S, Py_ssize_t a) {
    Pts *p = &S->pool, *q = &S->spare;
    const Py_ssize_t n = p->n;
    if (a == 0 || a == n || p->row[a - 1] < p->row[a]) return 1;
    if (!pts_reserve(q, n)) return 0;
    Py_ssize_t i = 0, j = a, k = 0;
    while (i < a || j < n) {
        const Py_ssize_t t = (j >= n || (i < a && p->row[i] < p->row[j])) ? i++ : j++;
        q->d[k] = p->d[t];
        q->fg[k] = p->fg[t];
        q->fh[k] = p->fh[t];
        q->row[k] = p->row[t];
        k++;
    }
    q->n = n;
    Pts t = *p; *p = *q; *q = t;
    return 1;
}

/* A head or pool point's distance as libm's hypot gives it (numpy's np.hypot calls it). */
static inline double exact_d(const Pts *a, Py_ssize_t i) { return hypot(a->fg[i], a->fh[i]); }

/* Whether distance a (within a few units in the last place of its hypot, or that) is <= b (exact): decided
 * by a where it is not within CLOSE of b, else by the hypot of pool point i. */
static inline int within(double a, double b, const Pts *pool, Py_ssize_t i) {
    if (a < b * (1.0 - CLOSE)) return 1;
    if (a > b * (1.0 + CLOSE)) return 0;
    return exact_d(pool, i) <= b;
}

/* Stable insertion sort of positions pos[0..n) by (key of their exact distance, position). */
static void insertion_by_exact(uint64_t *key, int32_t *pos, Py_ssize_t n) {
    for (Py_ssize_t i = 1; i < n; i++) {
        const uint64_t k = key[i];
        const int32_t at = pos[i];
        Py_ssize_t j = i;
        while (j > 0 && (key[j - 1] > k || (key[j - 1] == k && pos[j - 1] > at))) {
            key[j] = key[j - 1];
            pos[j] = pos[j - 1];
            j--;
        }
        key[j] = k;
        pos[j] = at;
    }
}

/* After sorting by square roots (s->idx: positions 0..m-1 of the entries, which are in grid order): every run
 * of neighbours within CLOSE of each other (equal ones included) takes hypot's distances and is sorted again by
 * (distance, position), the order hypot alone gives (apart from their runs, square roots and hypot order the
 * points alike).  0 when a run is too long for an insertion sort: the caller sorts by hypot from the start. */
static int settle_close(Search *S, Py_ssize_t m) {
    Pts *pool = &S->pool;
    Scratch *s = &S->sort;
    int32_t *idx = s->idx, *from = s->from;
    uint64_t *key = s->key2;  /* free after the sort */
    Py_ssize_t t = 0;
    while (t < m) {
        Py_ssize_t e = t + 1;
        while (e < m && pool->d[from[idx[e]]] <= pool->d[from[idx[e - 1]]] * (1.0 + CLOSE)) e++;
        if (e - t > 1) {
            if (e - t > SMALL_SORT) return 0;
            for (Py_ssize_t i = t; i < e; i++) {
                const int32_t k = from[idx[i]];
                pool->d[k] = exact_d(pool, k);
                key[i] = dist_key(pool->d[k]);
            }
            insertion_by_exact(key + t, idx + t, e - t);
        }
        t = e;
    }
    return 1;
}

/* The pool's points within R (all when whole), in the stable order of their distances (the pool is in grid
 * order), onto the head's end; the rest stay in the pool, in grid order.  The pool holds each point's
 * fg^2 + fh^2 (take_cell): a point whose square already puts it beyond R (REACH_SLACK below) stays without a
 * distance.  With S->approx the others are ordered by the square root of it, libm's hypot taken only where
 * two distances, or a distance and R, come within CLOSE (settle_close, within); else (and where the square
 * could underflow or overflow) by hypot itself: the same test, order and distances as calling hypot for all.
 * The head's distances may be square roots then: the ring rule reads them through `continues`. */
static int extend_head(Search *S) {
    Pts *pool = &S->pool, *head = &S->head;
    Scratch *s = &S->sort;
    if (!scratch_reserve(s, pool->n) || !pts_reserve(head, head->n + pool->n)) return 0;
    Py_ssize_t m = 0, keep = 0;
    const double bound = S->R * (1.0 + REACH_SLACK), far = bound * bound;
    const int bounded = !S->whole && far > 1e-200 && far < 1e200;  /* no overflow or underflow of squares */
    const int approx = S->approx;
    for (Py_ssize_t i = 0; i < pool->n; i++) {
        const double sq = pool->d[i];
        if (bounded && sq > far && sq < INFINITY) continue;  /* hypot > R for certain: it stays in the pool */
        const int rough = approx && sq >= SQ_LO && sq <= SQ_HI;
        const double d = rough ? sqrt(sq) : exact_d(pool, i);
        if (S->whole || (rough ? within(d, S->R, pool, i) : d <= S->R)) {
            s->key[m] = dist_key(d);
            s->from[m] = (int32_t)i;
            pool->d[i] = d;
            pool->row[i] = -1 - pool->row[i];  /* marked: it moves to the head */
            m++;
        }
    }
    if (m == 0) return 1;
    stable_order(s, m);
    if (approx && !settle_close(S, m)) {  /* distances mostly within CLOSE: sorted again by hypot alone */
        S->approx = 0;
        for (Py_ssize_t j = 0; j < m; j++) {
            const int32_t k = s->from[j];
            pool->d[k] = exact_d(pool, k);
            s->key[j] = dist_key(pool->d[k]);
        }
        stable_order(s, m);
    }
    for (Py_ssize_t i = 0; i < m; i++) {
        const int32_t k = s->from[s->idx[i]];
        head->d[head->n + i] = pool->d[k];
        head->fg[head->n + i] = pool->fg[k];
        head->fh[head->n + i] = pool->fh[k];
    }
    head->n += m;
    for (Py_ssize_t i = 0; i < pool->n; i++) {
        if (pool->row[i] < 0) continue;
        pool->d[keep] = pool->d[i];
        pool->fg[keep] = pool->fg[i];
        pool->fh[keep] = pool->fh[i];
        pool->row[keep] = pool->row[i];
        keep++;
    }
    pool->n = keep;
    return 1;
}

/* Whether head point i goes on with the ring after point i - 1 (its distance < growth x the last one), in
 * hypot's distances: decided by the head's (maybe square-root) distances unless they come within CLOSE. */
static inline int continues(const Pts *hd, Py_ssize_t i, double growth) {
    const double a = hd->d[i], b = growth * hd->d[i - 1];
    if (a < b * (1.0 - CLOSE)) return 1;
    if (a > b * (1.0 + CLOSE)) return 0;
    return exact_d(hd, i) < growth * exact_d(hd, i - 1);
}

/* One sample's ring: the first *ring points of the head (S->head.fg, S->head.fh), from a first ball of reach
 * `first`, the second at least `hint` (where the first did not end it); *ends: growth x the ring's last
 * distance (the reach that would have ended it in one ball; 0: no ring). */
static int one_ring(const Grid *G, Search *S, double growth, double first, double hint, Py_ssize_t *ring,
                    double *ends) {
    double R = first, last = 0.0;
    Py_ssize_t len = 0;  /* the ring's length within the head so far */
    int64_t box[6];
    S->pool.n = S->head.n = 0;
    S->reach = S->half + G->half_cell * (fabs(S->u[0]) + fabs(S->u[1]) + fabs(S->u[2])) * (1.0 + MARGIN)
               + G->size * MARGIN + 1e-12;
    int ok = 1;
    for (;;) {
        const double rad = sqrt(R * R + S->half * S->half) * (1.0 + MARGIN) + G->size * MARGIN;
        S->R = R;
        S->whole = !(R < INFINITY) || ball_box(G, S->p, rad, box);
        S->ball = rad + G->half_cell * sqrt(3.0) * (1.0 + MARGIN) + G->size * MARGIN + 1e-12;
        const Py_ssize_t old = S->pool.n;
        if (!(ok = gather(G, S, box) && merge_pool(S, old) && extend_head(S))) break;
        const Pts *hd = &S->head;
        if (len == 0 && hd->n > 0) len = 1;
        while (len < hd->n && continues(hd, len, growth)) len++;
        last = len ? exact_d(hd, len - 1) : 0.0;
        if (S->whole || len < hd->n || (len > 0 && growth * last <= R)) break;
        const double grown = len ? growth * last : 0.0;
        R = 2.0 * R > grown ? 2.0 * R : grown;
        R = R > hint ? R : hint;
        hint = 0.0;
    }
    for (Py_ssize_t i = 0; i < S->n_taken; i++) S->taken[S->cells[i]] = 0;
    S->n_taken = 0;
    *ring = len;
    *ends = growth * last;
    return ok;
}

/* The part of ellipse_fit.ellipse_sums before its BLAS product, for sets lo..hi - 1 of x, y (set i is
 * starts[i]:starts[i + 1]): a set of >= 5 finite points gets its centroid (running sums / n), its RMS radius
 * (sqrt of numpy's pairwise mean of cx^2 + cy^2) and, where that is > 0, its rows [cx^2, cx cy, cy^2, cx, cy, 1]
 * of the centred points / radius from row starts[i] - starts[lo] of `design`; ok[i - lo] = 1 for those. */
static void design_rows(const double *x, const double *y, const int64_t *starts, Py_ssize_t lo, Py_ssize_t hi,
                        double *design, double *origin, double *scale, int8_t *ok, double *t) {
    for (Py_ssize_t i = lo; i < hi; i++) {
        const Py_ssize_t a = (Py_ssize_t)starts[i], n = (Py_ssize_t)starts[i + 1] - a;
        const double *xs = x + a, *ys = y + a;
        ok[i - lo] = 0;
        if (n < 5) continue;
        double sx = xs[0], sy = ys[0];
        for (Py_ssize_t j = 1; j < n; j++) { sx += xs[j]; sy += ys[j]; }
        if (!(isfinite(sx) && isfinite(sy))) {  /* finite sums: every point finite (inf and NaN do not cancel) */
            int finite = 1;
            for (Py_ssize_t j = 0; j < n; j++) finite &= isfinite(xs[j]) && isfinite(ys[j]);
            if (!finite) continue;
        }
        const double ox = sx / (double)n, oy = sy / (double)n;
        for (Py_ssize_t j = 0; j < n; j++) {
            const double cx = xs[j] - ox, cy = ys[j] - oy;
            t[j] = cx * cx + cy * cy;
        }
        const double sc = sqrt(pairwise_sum(t, n) / (double)n);
        if (!(sc > 0)) continue;
        double *d = design + 6 * (a - (Py_ssize_t)starts[lo]);
#ifdef __SSE2__
        /* x and y divided in one instruction: a division rounds alike in either (IEEE 754), in half the time */
        const __m128d o = _mm_set_pd(oy, ox), scv = _mm_set1_pd(sc);
        for (Py_ssize_t j = 0; j < n; j++, d += 6) {
            double c[2];
            _mm_storeu_pd(c, _mm_div_pd(_mm_sub_pd(_mm_set_pd(ys[j], xs[j]), o), scv));
            const double cx = c[0], cy = c[1];
            d[0] = cx * cx; d[1] = cx * cy; d[2] = cy * cy; d[3] = cx; d[4] = cy; d[5] = 1.0;
        }
#else
        for (Py_ssize_t j = 0; j < n; j++, d += 6) {
            const double cx = (xs[j] - ox) / sc, cy = (ys[j] - oy) / sc;
            d[0] = cx * cx; d[1] = cx * cy; d[2] = cy * cy; d[3] = cx; d[4] = cy; d[5] = 1.0;
        }
#endif
        origin[2 * (i - lo)] = ox;
        origin[2 * (i - lo) + 1] = oy;
        scale[i - lo] = sc;
        ok[i - lo] = 1;
    }
}

/* design(x (M,) f64, y (M,) f64, starts (S + 1,) i64, lo, hi, design out (>= rows of sets lo..hi-1, 6) f64,
 *        origin out (hi - lo, 2) f64, scale out (hi - lo,) f64, ok out (hi - lo,) i8) */
static PyObject *py_design(PyObject *self, PyObject *args) {
    Py_buffer xb, yb, sb, db, ob, cb, kb;
    Py_ssize_t lo, hi;
    if (!PyArg_ParseTuple(args, "y*y*y*nnw*w*w*w*", &xb, &yb, &sb, &lo, &hi, &db, &ob, &cb, &kb)) return NULL;
    const int64_t *starts = (const int64_t *)sb.buf;
    const Py_ssize_t m = xb.len / (Py_ssize_t)sizeof(double), n_sets = sb.len / (Py_ssize_t)sizeof(int64_t) - 1;
    int ok = yb.len == xb.len && 0 <= lo && lo <= hi && hi <= n_sets
             && ob.len == 2 * (hi - lo) * (Py_ssize_t)sizeof(double)
             && cb.len == (hi - lo) * (Py_ssize_t)sizeof(double) && kb.len == hi - lo;
    Py_ssize_t big = 0;
    for (Py_ssize_t i = lo; ok && i < hi; i++) {
        ok = starts[i] >= 0 && starts[i] <= starts[i + 1] && starts[i + 1] <= m;
        if (ok && starts[i + 1] - starts[i] > big) big = (Py_ssize_t)(starts[i + 1] - starts[i]);
    }
    ok = ok && (hi == lo || db.len >= 6 * (Py_ssize_t)(starts[hi] - starts[lo]) * (Py_ssize_t)sizeof(double));
    double *t = ok ? (double *)malloc((size_t)(big + 1) * sizeof(double)) : NULL;
    if (ok && t) {
        Py_BEGIN_ALLOW_THREADS
        design_rows((const double *)xb.buf, (const double *)yb.buf, starts, lo, hi, (double *)db.buf, (double *)ob.buf,
                    (double *)cb.buf, (int8_t *)kb.buf, t);
        Py_END_ALLOW_THREADS
    }
    free(t);
    PyBuffer_Release(&xb); PyBuffer_Release(&yb); PyBuffer_Release(&sb); PyBuffer_Release(&db);
    PyBuffer_Release(&ob); PyBuffer_Release(&cb); PyBuffer_Release(&kb);
    if (!ok) {
        PyErr_SetString(PyExc_ValueError, "design: inconsistent sets or output arrays");
        return NULL;
    }
    if (!t) return PyErr_NoMemory();
    Py_RETURN_NONE;
}

/* rings(columns (3, N) f64, keys (C,) i64, starts (C,) i64, counts (C,) i64, lines (d1 d2 + 1,) i64,
 *       centres (C, 3) f64,
 *       frame (lo0, lo1, lo2, cell, size) f64, dims (3,) i64, points (S, 3), u, g, h (S, 3) f64,
 *       half, growth, first, fx out (M,) f64, fy out (M,) f64, bounds out (S + 1,) i64, offset, by_roots=True)
 *   -> (done, need): the rings of samples 0 .. done - 1 written to fx, fy from row `offset` on, sample s's
 *   at rows bounds[s] .. bounds[s + 1] - 1 (bounds[0] = offset); done < S when sample `done`'s ring, of
 *   `need` points, did not fit in the M rows (the caller grows the buffers and asks again from there).
 *   The caller's buffers are kept from call to call: no output is allocated here.  by_roots: distances ordered
 *   by square roots first (extend_head); False: by hypot alone (the same rings). */
static PyObject *py_rings(PyObject *self, PyObject *args) {
    Py_buffer col, ky, st, ct, ln, ce, fr, dm, pt, ub, gb, hb, xo, yo, bo;
    double half, growth, first;
    Py_ssize_t offset;
    int by_roots = 1;
    if (!PyArg_ParseTuple(args, "y*y*y*y*y*y*y*y*y*y*y*y*dddw*w*w*n|p", &col, &ky, &st, &ct, &ln, &ce, &fr, &dm, &pt,
                          &ub, &gb, &hb, &half, &growth, &first, &xo, &yo, &bo, &offset, &by_roots))
        return NULL;
    Py_buffer *all[] = {&col, &ky, &st, &ct, &ln, &ce, &fr, &dm, &pt, &ub, &gb, &hb, &xo, &yo, &bo};
    const int n_buf = (int)(sizeof all / sizeof all[0]);
    const Py_ssize_t n_pts = col.len / (Py_ssize_t)(3 * sizeof(double));
    const Py_ssize_t n_cells = ky.len / (Py_ssize_t)sizeof(int64_t);
    const Py_ssize_t n_s = pt.len / (Py_ssize_t)(3 * sizeof(double));
    const Py_ssize_t cap = xo.len / (Py_ssize_t)sizeof(double);
    const double *frame = (const double *)fr.buf;
    const int64_t *dims = (const int64_t *)dm.buf;
    int ok = col.len == 3 * n_pts * (Py_ssize_t)sizeof(double) && st.len == ky.len && ct.len == ky.len
             && ce.len == 3 * n_cells * (Py_ssize_t)sizeof(double) && fr.len == 5 * (Py_ssize_t)sizeof(double)
             && dm.len == 3 * (Py_ssize_t)sizeof(int64_t) && ub.len == pt.len && gb.len == pt.len && hb.len == pt.len
             && n_pts < INT32_MAX && n_cells < INT32_MAX && half > 0 && growth > 0 && first > 0 && frame[3] > 0
             && yo.len == xo.len && bo.len == (n_s + 1) * (Py_ssize_t)sizeof(int64_t) && 0 <= offset && offset <= cap;
    for (int a = 0; ok && a < 3; a++) ok = dims[a] >= 1 && dims[a] <= 1 << 20;
    const Py_ssize_t n_lines = ok ? (Py_ssize_t)(dims[1] * dims[2]) : 0;
    const int64_t *lines = (const int64_t *)ln.buf;
    ok = ok && ln.len == (n_lines + 1) * (Py_ssize_t)sizeof(int64_t);
    for (Py_ssize_t i = 0; ok && i <= n_lines; i++)
        ok = lines[i] >= 0 && lines[i] <= n_cells && (i == 0 || lines[i] >= lines[i - 1]);
    const int64_t *starts = (const int64_t *)st.buf, *counts = (const int64_t *)ct.buf;
    const int64_t *keys = (const int64_t *)ky.buf;
    for (Py_ssize_t i = 0; ok && i < n_cells; i++)
        ok = starts[i] >= 0 && counts[i] >= 0 && starts[i] + counts[i] <= n_pts && keys[i] >= 0
             && (i == 0 || keys[i] > keys[i - 1]) && keys[i] < dims[0] * dims[1] * dims[2];
    if (!ok) {
        for (int i = 0; i < n_buf; i++) PyBuffer_Release(all[i]);
        PyErr_SetString(PyExc_ValueError, "rings: inconsistent grid, sample or output arrays");
        return NULL;
    }
    Grid G = {(const double *)col.buf, (const double *)col.buf + n_pts, (const double *)col.buf + 2 * n_pts,
              keys, starts, counts, lines, (const double *)ce.buf, n_cells,
              {frame[0], frame[1], frame[2]}, frame[3], 0.5 * frame[3], frame[4], {dims[0], dims[1], dims[2]}};
    const double *P = (const double *)pt.buf, *U = (const double *)ub.buf, *Gv = (const double *)gb.buf,
                 *H = (const double *)hb.buf;
    double *fx = (double *)xo.buf, *fy = (double *)yo.buf;
    int64_t *bounds = (int64_t *)bo.buf;
    Search S;
    memset(&S, 0, sizeof S);
    lend_buffers(&S);
    S.half = half;
    S.approx = by_roots;
    S.taken = (char *)calloc((size_t)n_cells + 1, 1);
    S.cells = (int32_t *)malloc(((size_t)n_cells + 1) * sizeof(int32_t));
    int good = S.taken && S.cells;
    Py_ssize_t done = 0, need = 0;
    double hint = 0.0;  /* the second ball's least 2-D reach for the next sample */
    Py_BEGIN_ALLOW_THREADS
    bounds[0] = (int64_t)offset;
    for (Py_ssize_t s = 0; good && s < n_s; s++) {
        double size = G.size;  /* the coordinates' magnitude, for the cell tests' allowance */
        for (int a = 0; a < 3; a++) {
            S.p[a] = P[3 * s + a]; S.u[a] = U[3 * s + a]; S.g[a] = Gv[3 * s + a]; S.h[a] = H[3 * s + a];
            size = fabs(S.p[a]) > size ? fabs(S.p[a]) : size;
        }
        Grid Gs = G;
        Gs.size = size;
        Py_ssize_t len = 0;
        double ends = 0.0;
        good = one_ring(&Gs, &S, growth, first, hint, &len, &ends);
        hint = ends * HINT < INFINITY ? ends * HINT : 0.0;  /* NaN: none */
        if (!good) break;
        const Py_ssize_t at = (Py_ssize_t)bounds[s];
        if (len > cap - at) {
            need = len;
            break;
        }
        memcpy(fx + at, S.head.fg, (size_t)len * sizeof(double));
        memcpy(fy + at, S.head.fh, (size_t)len * sizeof(double));
        bounds[s + 1] = (int64_t)(at + len);
        done = s + 1;
    }
    Py_END_ALLOW_THREADS
    for (int i = 0; i < n_buf; i++) PyBuffer_Release(all[i]);
    keep_buffers(&S);
    free(S.taken); free(S.cells);
    if (!good) return PyErr_NoMemory();
    return Py_BuildValue("(nn)", done, need);
}

static PyMethodDef methods[] = {
    {"rings", py_rings, METH_VARARGS, "Per curve sample: its slab ring's plane coordinates, in ring order."},
    {"design", py_design, METH_VARARGS, "Per point set: centroid, RMS radius and the ellipse fit's design rows."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_rings",
                                    "Compiled ring extraction of curve centeredness (docs/metrics.md, section 3).",
                                    -1, methods};

PyMODINIT_FUNC PyInit__rings(void) { return PyModule_Create(&module); }
