/* Compiled kernel of SkelScope's coverage (docs/metrics.md 5.2: design and numbers).
 *
 * Skeleton elements x carry radii r(x) = distance to the nearest cloud point.  Per cloud point p:
 * gap(p) = min_x |p - x| - r(x) (exact: the same double arithmetic as a brute-force loop), and
 * covered(p) = some x has |p - x|^2 - R(x)^2 <= eps (R = (1 + s) r + tau, eps a rounding allowance).
 *
 * One KD-tree of bounding spheres in double precision serves both sides.  Over the cloud (for r(x)),
 * each node also keeps a slab: the plane of least spread of its points and their largest distance from
 * it; a surface patch seen from inside the shape is then bounded by its distance along the normal, not
 * by its sphere (a medial point is nearly equidistant to a whole ring of surface points).  Over the
 * elements, each node keeps max |x - c| + r(x) and max |x - c| + R(x): |p - c| minus these bounds
 * |p - x| - r(x) (resp. - R(x)) from below over the node's members.  Queries run in the tree order of
 * the query points, each seeded with the previous query's answer, nearer child first.
 *
 * Plain C with the buffer protocol (no numpy headers at build time); every entry point releases the GIL.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define LEAF_SIZE 8
#define MAX_STACK 256
#define BACK_MAX 2048  /* nodes of at most this many balls get a second sphere */
#define PI 3.14159265358979323846264338327950288

typedef struct {
    double c[3];            /* bounding-sphere centre */
    double rho;             /* max |x - c| over the members (padded) */
    double rg, rc;          /* max |x - c| + r(x), max |x - c| + R(x) (padded; set by refit) */
    double n[3], t, w;      /* disc: |n| <= 1, every member has |(x - c).n| <= t and its distance from the
                               normal line through c <= w; n = 0: none */
    double k[3], rk;        /* a second sphere: max |x - k| + r(x) (set by refit; k = c, rk = rg if none) */
    int32_t kid, lo, hi;    /* first child (second = kid + 1) or -1 for a leaf; member range [lo, hi) */
    int32_t pad_;
} Node;                     /* 136 bytes */

/* ------------------------------------------------------------------------------------------------ */
/* Build                                                                                              */

typedef struct { double x[3]; int32_t i; int32_t pad_; } Item;  /* a point and its input row */

static void select_nth(Item *v, int32_t lo, int32_t hi, int32_t nth, int axis) {
    /* quickselect on v[lo:hi] by coordinate `axis`: afterwards v[nth] is the nth smallest */
    while (hi - lo > 1) {
        int32_t mid = lo + (hi - lo) / 2;
        double a = v[lo].x[axis], b = v[mid].x[axis], c = v[hi - 1].x[axis];
        double pivot = (a < b) ? ((b < c) ? b : ((a < c) ? c : a)) : ((a < c) ? a : ((b < c) ? c : b));
        int32_t i = lo, j = hi - 1;
        while (i <= j) {
            while (v[i].x[axis] < pivot) i++;
            while (v[j].x[axis] > pivot) j--;
            if (i <= j) {
                Item t = v[i]; v[i] = v[j]; v[j] = t;
                i++; j--;
            }
        }
        if (nth <= j) hi = j + 1;
        else if (nth >= i) lo = i;
        else return;
    }
}

/* unit eigenvector of the least eigenvalue of the symmetric 3x3 matrix a (row-major) into n; 0 if none */
static int least_axis(const double *a, double *n) {
    double p1 = a[1] * a[1] + a[2] * a[2] + a[5] * a[5];
    double q = (a[0] + a[4] + a[8]) / 3.0;
    double p2 = (a[0] - q) * (a[0] - q) + (a[4] - q) * (a[4] - q) + (a[8] - q) * (a[8] - q) + 2.0 * p1;
    double p = sqrt(p2 / 6.0);
    if (!(p > 0.0)) return 0;  /* a multiple of the identity: no preferred plane */
    double b[9];
    for (int i = 0; i < 9; i++) b[i] = (a[i] - ((i % 4 == 0) ? q : 0.0)) / p;
    double det = b[0] * (b[4] * b[8] - b[5] * b[7]) - b[1] * (b[3] * b[8] - b[5] * b[6]) +
                 b[2] * (b[3] * b[7] - b[4] * b[6]);
    double r = det / 2.0;
    double phi = r <= -1.0 ? PI / 3.0 : (r >= 1.0 ? 0.0 : acos(r) / 3.0);
    double lam = q + 2.0 * p * cos(phi + 2.0 * PI / 3.0);  /* the least eigenvalue */
    const double m[9] = {a[0] - lam, a[1], a[2], a[3], a[4] - lam, a[5], a[6], a[7], a[8] - lam};
    const double *r0 = m, *r1 = m + 3, *r2 = m + 6;
    double cand[3][3] = {
        {r0[1] * r1[2] - r0[2] * r1[1], r0[2] * r1[0] - r0[0] * r1[2], r0[0] * r1[1] - r0[1] * r1[0]},
        {r0[1] * r2[2] - r0[2] * r2[1], r0[2] * r2[0] - r0[0] * r2[2], r0[0] * r2[1] - r0[1] * r2[0]},
        {r1[1] * r2[2] - r1[2] * r2[1], r1[2] * r2[0] - r1[0] * r2[2], r1[0] * r2[1] - r1[1] * r2[0]}};
    int best = -1;
    double bn = 0.0;
    for (int k = 0; k < 3; k++) {
        double l2 = cand[k][0] * cand[k][0] + cand[k][1] * cand[k][1] + cand[k][2] * cand[k][2];
        if (l2 > bn) { bn = l2; best = k; }
    }
    if (best < 0 || !(bn > 0.0) || !isfinite(bn)) return 0;
    double inv = (1.0 - 1e-12) / sqrt(bn);  /* |n| stays <= 1 after rounding: the bound stays a bound */
    for (int k = 0; k < 3; k++) n[k] = cand[best][k] * inv;
    return 1;
}

typedef struct {
    Item *v;                 /* the points, reordered in place into tree order (sequential access) */
    Node *nodes;
    int32_t n_nodes, cap, leaf;
    int slab;
    double pad;              /* absolute padding of every bound: rounding of the distances */
    volatile int32_t *stop;  /* set by another thread to abandon the build (a cancel) */
    int split_depth;         /* subtrees this many levels from the root or fewer get a thread of their own */
} Builder;

/* nodes of the subtree over n points (median splits, leaves of at most `leaf`) */
static int32_t subtree_nodes(int32_t n, int32_t leaf) {
    if (n <= leaf) return 1;
    return 1 + subtree_nodes(n / 2, leaf) + subtree_nodes(n - n / 2, leaf);
}

static void build_node(Builder *b, int32_t node, int32_t lo, int32_t hi, int depth);

typedef struct { Builder b; int32_t node, lo, hi; int depth; } BuildJob;

static void *build_job(void *arg) {
    BuildJob *j = (BuildJob *)arg;
    build_node(&j->b, j->node, j->lo, j->hi, j->depth);
    return NULL;
}

static void build_node(Builder *b, int32_t node, int32_t lo, int32_t hi, int depth) {
    Node *nd = b->nodes + node;
    memset(nd, 0, sizeof(Node));
    nd->lo = lo;
    nd->hi = hi;
    nd->kid = -1;
    if (hi - lo > 4096 && *b->stop) return;
    double mn[3] = {INFINITY, INFINITY, INFINITY}, mx[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int32_t i = lo; i < hi; i++) {
        const double *p = b->v[i].x;
        for (int k = 0; k < 3; k++) {
            if (p[k] < mn[k]) mn[k] = p[k];
            if (p[k] > mx[k]) mx[k] = p[k];
        }
    }
    double c[3], r2 = 0.0;
    for (int k = 0; k < 3; k++) c[k] = 0.5 * (mn[k] + mx[k]);
    for (int32_t i = lo; i < hi; i++) {
        const double *p = b->v[i].x;
        double dx = p[0] - c[0], dy = p[1] - c[1], dz = p[2] - c[2];
        double d2 = dx * dx + dy * dy + dz * dz;
        if (d2 > r2) r2 = d2;
    }
    memcpy(nd->c, c, sizeof c);
    nd->rho = sqrt(r2) * (1.0 + 1e-12) + b->pad;
    if (b->slab && hi - lo >= 3) {
        double m[3] = {0.0, 0.0, 0.0}, a[9] = {0.0};
        for (int32_t i = lo; i < hi; i++) {
            const double *p = b->v[i].x;
            for (int k = 0; k < 3; k++) m[k] += p[k] - c[k];
        }
        for (int k = 0; k < 3; k++) m[k] /= (double)(hi - lo);
        for (int32_t i = lo; i < hi; i++) {
            const double *p = b->v[i].x;
            double d[3] = {p[0] - c[0] - m[0], p[1] - c[1] - m[1], p[2] - c[2] - m[2]};
            for (int u = 0; u < 3; u++)
                for (int v = 0; v < 3; v++) a[3 * u + v] += d[u] * d[v];
        }
        double n[3];
        if (least_axis(a, n)) {
            double t = 0.0, w2 = 0.0;
            for (int32_t i = lo; i < hi; i++) {
                const double *p = b->v[i].x;
                double d[3] = {p[0] - c[0], p[1] - c[1], p[2] - c[2]};
                double s = d[0] * n[0] + d[1] * n[1] + d[2] * n[2];
                double l2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2] - s * s;
                if (fabs(s) > t) t = fabs(s);
                if (l2 > w2) w2 = l2;
            }
            memcpy(nd->n, n, sizeof n);
            nd->t = t * (1.0 + 1e-12) + b->pad;
            nd->w = sqrt(w2) * (1.0 + 1e-12) + b->pad;
        }
    }
    if (hi - lo <= b->leaf || b->n_nodes + 2 > b->cap) return;
    int axis = 0;
    double ext = mx[0] - mn[0];
    for (int k = 1; k < 3; k++)
        if (mx[k] - mn[k] > ext) { ext = mx[k] - mn[k]; axis = k; }
    int32_t mid = lo + (hi - lo) / 2;
    select_nth(b->v, lo, hi, mid, axis);
    int32_t first = b->n_nodes;
    b->n_nodes += 2;
    nd->kid = first;
    if (depth < b->split_depth && hi - lo > 65536) {
        /* the second subtree on its own thread, numbered as the sequential build numbers it: its nodes
         * follow all of the first subtree's (the same tree bytes with any number of threads) */
        BuildJob job = {*b, first + 1, mid, hi, depth + 1};
        job.b.n_nodes = first + 2 + (subtree_nodes(mid - lo, b->leaf) - 1);
        pthread_t th;
        if (pthread_create(&th, NULL, build_job, &job) == 0) {
            build_node(b, first, lo, mid, depth + 1);
            pthread_join(th, NULL);
            b->n_nodes = job.b.n_nodes;
            return;
        }
    }
    build_node(b, first, lo, mid, depth + 1);
    build_node(b, first + 1, mid, hi, depth + 1);
}

static double abs_scale(const double *v, Py_ssize_t n) {
    double s = 1.0;
    for (Py_ssize_t i = 0; i < n; i++) {
        double a = fabs(v[i]);
        if (a > s && isfinite(a)) s = a;
    }
    return s;
}

/* build_tree(points (n,3) f64, perm (n) i32 out, sorted (n,3) f64 out, nodes (cap) Node out, slab (0/1),
 * stop (1) i32[, leaf size, threads]) -> number of nodes, or -1 if stop was set meanwhile.  perm lists
 * the input rows in tree order, sorted holds the points in that order.  The tree does not depend on
 * threads. */
static PyObject *py_build_tree(PyObject *self, PyObject *args) {
    Py_buffer pts, perm, srt, nds, stop;
    int slab, leaf = LEAF_SIZE, threads = 1;
    if (!PyArg_ParseTuple(args, "y*w*w*w*pw*|ii", &pts, &perm, &srt, &nds, &slab, &stop, &leaf, &threads))
        return NULL;
    int32_t n = (int32_t)(pts.len / (3 * sizeof(double)));
    int32_t cap = (int32_t)(nds.len / (Py_ssize_t)sizeof(Node));
    PyObject *result = NULL;
    Item *v = NULL;
    if (perm.len / (Py_ssize_t)sizeof(int32_t) < n || srt.len < pts.len || cap < 1 ||
        stop.len < (Py_ssize_t)sizeof(int32_t)) {
        PyErr_SetString(PyExc_ValueError, "build_tree: output buffers too small");
        goto done;
    }
    v = (Item *)malloc(sizeof(Item) * (size_t)(n > 0 ? n : 1));
    if (!v) { PyErr_NoMemory(); goto done; }
    int split = 0;
    while ((1 << split) < threads && split < 6) split++;
    Builder b = {v, (Node *)nds.buf, 1, cap, leaf < 2 ? 2 : leaf, slab,
                 1e-13 * abs_scale((const double *)pts.buf, 3 * (Py_ssize_t)n), (volatile int32_t *)stop.buf, split};
    int32_t total = 0;
    Py_BEGIN_ALLOW_THREADS
    const double *src = (const double *)pts.buf;
    for (int32_t i = 0; i < n; i++) {
        memcpy(v[i].x, src + 3 * (size_t)i, 3 * sizeof(double));
        v[i].i = i;
    }
    build_node(&b, 0, 0, n, 0);
    total = b.n_nodes;
    int32_t *out = (int32_t *)perm.buf;
    double *sorted = (double *)srt.buf;
    for (int32_t i = 0; i < n; i++) {
        out[i] = v[i].i;
        memcpy(sorted + 3 * (size_t)i, v[i].x, 3 * sizeof(double));
    }
    Py_END_ALLOW_THREADS
    result = PyLong_FromLong(*b.stop ? -1 : total);
done:
    free(v);
    PyBuffer_Release(&pts); PyBuffer_Release(&perm); PyBuffer_Release(&srt); PyBuffer_Release(&nds);
    PyBuffer_Release(&stop);
    return result;
}

static inline double dist3(const double *a, const double *b) {
    double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
    return sqrt(dx * dx + dy * dy + dz * dz);
}

/* refit(nodes, points (n,3) f64 tree order, r (n) f64, R (n) f64, contact (n,3) f64 or empty, i0, i1):
 * rg and rc of nodes [i0, i1), and their second sphere.  Balls that touch the surface (r(x) = distance
 * to the nearest cloud point, contact = that point) shrink as their centres move toward it, so a sphere
 * about c bounds them loosely (by about the node's size) where it matters, near the contacts; a sphere
 * about k = c - beta m (m the mean contact direction) hugs them when k is near the surface's centre of
 * curvature.  beta is chosen among a few by the worst bound it gives at the members' contacts (where
 * the least excess is 0); every choice is a valid bound, the choice only sets how tight. */
static PyObject *py_refit(PyObject *self, PyObject *args) {
    Py_buffer nds, pts, rg, rc, con;
    Py_ssize_t i0, i1;
    if (!PyArg_ParseTuple(args, "w*y*y*y*y*nn", &nds, &pts, &rg, &rc, &con, &i0, &i1)) return NULL;
    Node *nodes = (Node *)nds.buf;
    const double *p = (const double *)pts.buf, *r = (const double *)rg.buf, *R = (const double *)rc.buf;
    const double *q = con.len > 0 ? (const double *)con.buf : NULL;
    Py_ssize_t n = pts.len / (Py_ssize_t)(3 * sizeof(double));
    double pad = 1e-13 * (abs_scale(p, 3 * n) + abs_scale(R, n));
    Py_BEGIN_ALLOW_THREADS
    for (Py_ssize_t k = i0; k < i1; k++) {
        Node *nd = nodes + k;
        double g = 0.0, c = 0.0, m[3] = {0.0, 0.0, 0.0}, rmean = 0.0;
        {   /* the sphere about the members' centres (the tree may have been built on other points) */
            double mn[3] = {INFINITY, INFINITY, INFINITY}, mx[3] = {-INFINITY, -INFINITY, -INFINITY}, r2 = 0.0;
            for (int32_t i = nd->lo; i < nd->hi; i++)
                for (int j = 0; j < 3; j++) {
                    double v = p[3 * (size_t)i + j];
                    if (v < mn[j]) mn[j] = v;
                    if (v > mx[j]) mx[j] = v;
                }
            if (nd->hi > nd->lo)
                for (int j = 0; j < 3; j++) nd->c[j] = 0.5 * (mn[j] + mx[j]);
            for (int32_t i = nd->lo; i < nd->hi; i++) {
                double d2 = 0.0;
                for (int j = 0; j < 3; j++) d2 += (p[3 * (size_t)i + j] - nd->c[j]) * (p[3 * (size_t)i + j] - nd->c[j]);
                if (d2 > r2) r2 = d2;
            }
            nd->rho = sqrt(r2) * (1.0 + 1e-12) + pad;
        }
        for (int32_t i = nd->lo; i < nd->hi; i++) {
            const double *x = p + 3 * (size_t)i;
            double dx = x[0] - nd->c[0], dy = x[1] - nd->c[1], dz = x[2] - nd->c[2];
            double d = sqrt(dx * dx + dy * dy + dz * dz);
            if (d + r[i] > g) g = d + r[i];
            if (d + R[i] > c) c = d + R[i];
            rmean += r[i];
            if (q && r[i] > 0.0)
                for (int j = 0; j < 3; j++) m[j] += (q[3 * (size_t)i + j] - x[j]) / r[i];
        }
        nd->rg = g * (1.0 + 1e-12) + pad;
        nd->rc = c * (1.0 + 1e-12) + pad;
        memcpy(nd->k, nd->c, sizeof nd->k);
        nd->rk = nd->rg;
        int32_t cnt = nd->hi - nd->lo;
        double ml = sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
        /* a large node's contacts point all around (and its scan would be long): no second sphere */
        if (!q || cnt < 1 || cnt > BACK_MAX || !(ml > 0.25 * cnt)) continue;
        rmean /= cnt;
        double best_val = -INFINITY, best_beta = 0.0, best_rk = nd->rg;
        for (int step = 0; step <= 10; step++) {
            double beta = step == 0 ? 0.0 : rmean * ldexp(1.0, step - 8);  /* r/128 ... 4 r */
            double kc[3] = {nd->c[0] - beta * m[0] / ml, nd->c[1] - beta * m[1] / ml, nd->c[2] - beta * m[2] / ml};
            double rk = 0.0, val = 0.0;
            for (int32_t i = nd->lo; i < nd->hi; i++) {
                const double *x = p + 3 * (size_t)i;
                double d = dist3(x, kc);
                if (d + r[i] > rk) rk = d + r[i];
            }
            val = INFINITY;
            for (int32_t i = nd->lo; i < nd->hi; i++) { double dq = dist3(q + 3 * (size_t)i, kc); if (dq < val) val = dq; }
            val = val - rk;
            if (val > best_val) { best_val = val; best_beta = beta; best_rk = rk; }
        }
        for (int j = 0; j < 3; j++) nd->k[j] = nd->c[j] - best_beta * m[j] / ml;
        nd->rk = best_rk * (1.0 + 1e-12) + pad + 1e-13 * best_beta;
    }
    Py_END_ALLOW_THREADS
    PyBuffer_Release(&nds); PyBuffer_Release(&pts); PyBuffer_Release(&rg); PyBuffer_Release(&rc); PyBuffer_Release(&con);
    Py_RETURN_NONE;
}

/* ------------------------------------------------------------------------------------------------ */
/* Nearest point (the radii r(x))                                                                     */

typedef struct { int32_t node, ver; double d; } Entry;  /* ver: improvements of best when pushed */


/* Squared lower bound of |q - x| over the node's members, or inf if it is >= best: their sphere (tested
 * without a root), then their disc (a cylinder of radius w and half-height t around the normal n
 * through c): one square root at most, for the distance from the cylinder's axis. */
static inline double near_bound2(const Node *nd, const double *q, double best) {
    double dx = q[0] - nd->c[0], dy = q[1] - nd->c[1], dz = q[2] - nd->c[2];
    double d2 = dx * dx + dy * dy + dz * dz;
    double s = best + nd->rho;
    if (d2 >= s * s) return INFINITY;
    if (nd->t == 0.0) {
        double d = sqrt(d2) - nd->rho;
        return d > 0.0 ? d * d : 0.0;
    }
    double h = dx * nd->n[0] + dy * nd->n[1] + dz * nd->n[2];
    double l2 = d2 - h * h, dn = fabs(h) - nd->t, b2 = 0.0;
    if (dn > 0.0) b2 = dn * dn;
    if (l2 > nd->w * nd->w) {
        double dl = sqrt(l2) - nd->w;
        b2 += dl * dl;
    }
    return b2 * (1.0 - 1e-12);
}

/* What the walk reads after a node it pushes: its children's bounds (the first 88 bytes of each, two
 * lines) or its leaf's points, asked of memory while it walks on (at 1M points the 136-byte nodes outgrow
 * the caches); no value depends on it. */
static inline void prefetch_below(const Node *nd, const Node *nodes, const double *p) {
    if (nd->kid >= 0) {
        const char *k = (const char *)(nodes + nd->kid);
        __builtin_prefetch(k);
        __builtin_prefetch(k + 80);
        __builtin_prefetch(k + sizeof(Node));
        __builtin_prefetch(k + sizeof(Node) + 80);
    } else {
        const char *a = (const char *)(p + 3 * (size_t)nd->lo), *b = (const char *)(p + 3 * (size_t)nd->hi);
        for (; a < b; a += 64) __builtin_prefetch(a);
    }
}

/* nearest(nodes, points (n,3) f64 tree order, queries (m,3) f64, i0, i1, dist out (m) f64,
 *         index out (m) i32 (tree order), stats out (2) i64: nodes visited, points tested[, others])
 * Distance from each query of [i0, i1) to its nearest point, exact (sqrt(dx^2 + dy^2 + dz^2), the
 * value a brute-force loop gives); queries in spatial order make the previous answer a good seed.
 * With `others`, the queries are the tree's own points and query k skips point k (its nearest
 * other point: 0 for a copy). */
static PyObject *py_nearest(PyObject *self, PyObject *args) {
    Py_buffer nds, pts, qs, dist, index, stats;
    Py_ssize_t i0, i1;
    int others = 0;
    if (!PyArg_ParseTuple(args, "y*y*y*nnw*w*w*|p", &nds, &pts, &qs, &i0, &i1, &dist, &index, &stats, &others))
        return NULL;
    const Node *nodes = (const Node *)nds.buf;
    const double *p = (const double *)pts.buf, *q = (const double *)qs.buf;
    const int32_t n = (int32_t)(pts.len / (Py_ssize_t)(3 * sizeof(double)));
    double *out = (double *)dist.buf;
    int32_t *oi = (int32_t *)index.buf;
    int64_t *st = (int64_t *)stats.buf;
    Py_BEGIN_ALLOW_THREADS
    Entry stack[MAX_STACK];
    int64_t visits = 0, tests = 0;
    int32_t seed = -1;
    for (Py_ssize_t k = i0; k < i1; k++) {
        const double *x = q + 3 * (size_t)k;
        double best = INFINITY, best2 = INFINITY;
        int32_t bi = -1;
        const int32_t skip = others ? (int32_t)k : -1;
        if (n == 0) { out[k] = INFINITY; oi[k] = -1; continue; }
        if (seed == skip) seed = -1;
        if (seed >= 0) {
            const double *y = p + 3 * (size_t)seed;
            double dx = x[0] - y[0], dy = x[1] - y[1], dz = x[2] - y[2];
            best2 = dx * dx + dy * dy + dz * dz;
            best = sqrt(best2);
            bi = seed;
        }
        int sp = 0;
        stack[sp].node = 0;
        stack[sp].ver = 0;
        stack[sp++].d = near_bound2(nodes, x, best);
        while (sp > 0) {
            Entry e = stack[--sp];
            if (e.d >= best2) continue;
            const Node *nd = nodes + e.node;
            visits++;
            if (nd->kid < 0) {  /* squared distances: sqrt is monotone, the least one is the same */
                double b2 = best2;
                int32_t bj = -1;
                for (int32_t i = nd->lo; i < nd->hi; i++) {
                    const double *y = p + 3 * (size_t)i;
                    double dx = x[0] - y[0], dy = x[1] - y[1], dz = x[2] - y[2];
                    double d2 = dx * dx + dy * dy + dz * dz;
                    if (d2 < b2 && i != skip) { b2 = d2; bj = i; }
                }
                if (bj >= 0) { best2 = b2; best = sqrt(b2); bi = bj; }
                tests += nd->hi - nd->lo;
                continue;
            }
            const Node *a = nodes + nd->kid, *b = a + 1;
            double da = near_bound2(a, x, best), db = near_bound2(b, x, best);
            if (da < best2) prefetch_below(a, nodes, p);
            if (db < best2) prefetch_below(b, nodes, p);
            if (da <= db) {
                if (db < best2) { stack[sp].node = nd->kid + 1; stack[sp++].d = db; }
                if (da < best2) { stack[sp].node = nd->kid; stack[sp++].d = da; }
            } else {
                if (da < best2) { stack[sp].node = nd->kid; stack[sp++].d = da; }
                if (db < best2) { stack[sp].node = nd->kid + 1; stack[sp++].d = db; }
            }
        }
        out[k] = best;
        oi[k] = bi;
        seed = bi;
    }
    st[0] += visits;
    st[1] += tests;
    Py_END_ALLOW_THREADS
    PyBuffer_Release(&nds); PyBuffer_Release(&pts); PyBuffer_Release(&qs);
    PyBuffer_Release(&dist); PyBuffer_Release(&index); PyBuffer_Release(&stats);
    Py_RETURN_NONE;
}

/* ------------------------------------------------------------------------------------------------ */
/* Gap and cover                                                                                      */

/* may the node's second sphere hold a ball with excess below best: |q - k| - rk < best */
static inline int second_ok(const Node *nd, const double *q, double best) {
    double dx = q[0] - nd->k[0], dy = q[1] - nd->k[1], dz = q[2] - nd->k[2];
    double s = best + nd->rk;
    return s > 0.0 && dx * dx + dy * dy + dz * dz < s * s;
}

/* the arguments of balls and balls_block */
typedef struct {
    Py_buffer nds, pts, rg, rc, qs, gap, cov, stats;
    Py_ssize_t i0, i1;
    double floor_, eps;
    const Node *nodes;
    const double *p, *r, *R, *q;  /* centres, r, R, queries */
    int32_t n;                    /* balls */
    double *og;                   /* gap out */
    uint8_t *oc;                  /* covered out */
    int want_gap, want_cov;
    int64_t *st;
} BallsArgs;

static int balls_args(PyObject *args, BallsArgs *a) {
    if (!PyArg_ParseTuple(args, "y*y*y*y*y*nnddw*w*w*", &a->nds, &a->pts, &a->rg, &a->rc, &a->qs, &a->i0, &a->i1,
                          &a->floor_, &a->eps, &a->gap, &a->cov, &a->stats))
        return 0;
    a->nodes = (const Node *)a->nds.buf;
    a->p = (const double *)a->pts.buf, a->r = (const double *)a->rg.buf, a->R = (const double *)a->rc.buf;
    a->q = (const double *)a->qs.buf;
    a->n = (int32_t)(a->pts.len / (Py_ssize_t)(3 * sizeof(double)));
    a->og = (double *)a->gap.buf, a->oc = (uint8_t *)a->cov.buf;
    a->want_gap = a->gap.len > 0, a->want_cov = a->cov.len > 0;
    a->st = (int64_t *)a->stats.buf;
    return 1;
}

static void balls_release(BallsArgs *a) {
    PyBuffer_Release(&a->nds); PyBuffer_Release(&a->pts); PyBuffer_Release(&a->rg); PyBuffer_Release(&a->rc);
    PyBuffer_Release(&a->qs); PyBuffer_Release(&a->gap); PyBuffer_Release(&a->cov); PyBuffer_Release(&a->stats);
}

/* Query x against a leaf's balls: the least excess (below *best, a ball skipped only when its computed
 * excess cannot be below it) and the first covering ball; how many times *best or the cover changed. */
static inline int leaf_balls(const Node *nd, const double *p, const double *r, const double *R, const double *x,
                             double eps, double floor_, double *best, int32_t *bi, int *gap_open, int *cov_open,
                             int32_t *ci) {
    int changed = 0;
    for (int32_t i = nd->lo; i < nd->hi; i++) {
        const double *b = p + 3 * (size_t)i;
        double dx = x[0] - b[0], dy = x[1] - b[1], dz = x[2] - b[2];
        double d2 = dx * dx + dy * dy + dz * dz;
        if (*gap_open) {
            /* sqrt(d2) - r < best needs d2 < (best + r)^2; the margin m keeps every
             * skipped ball's computed excess >= best */
            double t = *best + r[i], m = 1e-12 * (fabs(*best) + r[i]) + 1e-300;
            if (t + m > 0.0 && d2 < (t + m) * (t + m)) {
                double ex = sqrt(d2) - r[i];
                if (ex < *best) { *best = ex; *bi = i; changed++; if (*best <= floor_) *gap_open = 0; }
            }
        }
        if (*cov_open && d2 - R[i] * R[i] <= eps) { *cov_open = 0; *ci = i; changed++; }
    }
    return changed;
}

/* balls(nodes (refit), centres (n,3) f64 tree order, r (n) f64, R (n) f64, queries (m,3) f64, i0, i1,
 *       floor, eps, gap out (m) f64 or empty, covered out (m) u8 or empty, stats out (2) i64)
 * gap = min |q - x| - r(x) where it is above floor (elsewhere some value <= floor); covered = some x
 * with |q - x|^2 - R(x)^2 <= eps.  An empty output buffer skips that half. */
static PyObject *py_balls(PyObject *self, PyObject *args) {
    BallsArgs a;
    if (!balls_args(args, &a)) return NULL;
    const Py_ssize_t i0 = a.i0, i1 = a.i1;
    const double floor_ = a.floor_, eps = a.eps;
    const Node *nodes = a.nodes;
    const double *p = a.p, *r = a.r, *R = a.R, *q = a.q;
    const int32_t n = a.n, want_gap = a.want_gap, want_cov = a.want_cov;
    Py_BEGIN_ALLOW_THREADS
    Entry stack[MAX_STACK];
    int64_t visits = 0, tests = 0;
    const double tol = sqrt(eps > 0.0 ? eps : 0.0);  /* |q - x| <= sqrt(R^2 + eps) <= R + tol */
    int32_t seed_g = -1, seed_c = -1;
    for (Py_ssize_t k = i0; k < i1; k++) {
        const double *x = q + 3 * (size_t)k;
        double best = INFINITY;
        int32_t bi = -1, ci = -1;
        int gap_open = want_gap && n > 0, cov_open = want_cov && n > 0;
        /* the previous query's balls first: a neighbour's answer is usually this one's too */
        int32_t seeds[2] = {seed_g, seed_c};
        for (int s = 0; s < 2; s++) {
            int32_t i = seeds[s];
            if (i < 0 || (s == 1 && i == seed_g)) continue;
            const double *c = p + 3 * (size_t)i;
            double dx = x[0] - c[0], dy = x[1] - c[1], dz = x[2] - c[2];
            double d2 = dx * dx + dy * dy + dz * dz;
            if (gap_open) {
                double e = sqrt(d2) - r[i];
                if (e < best) { best = e; bi = i; }
            }
            if (cov_open && d2 - R[i] * R[i] <= eps) { cov_open = 0; ci = i; }
        }
        if (gap_open && best <= floor_) gap_open = 0;
        int sp = 0, ver = 0;
        if (gap_open || cov_open) { stack[sp].node = 0; stack[sp].ver = 0; stack[sp++].d = 0.0; }
        while (sp > 0 && (gap_open || cov_open)) {
            Entry e = stack[--sp];
            const Node *nd = nodes + e.node;
            if (e.ver != ver) {  /* best has improved (or cover closed) since the push: test again */
                double sg = best + nd->rg, sc = nd->rc + tol;
                const int g = gap_open && sg > 0.0 && e.d < sg * sg && second_ok(nd, x, best),
                          c = cov_open && e.d <= sc * sc;
                if (!g && !c) continue;
            }
            visits++;
            if (nd->kid < 0) {
                ver += leaf_balls(nd, p, r, R, x, eps, floor_, &best, &bi, &gap_open, &cov_open, &ci);
                tests += nd->hi - nd->lo;
                continue;
            }
            /* a child is needed while |q - c| - rg < best (gap) or |q - c| - rc <= tol (cover), in squares */
            const Node *kid[2] = {nodes + nd->kid, nodes + nd->kid + 1};
            double d2k[2], key[2];
            int need[2];
            for (int j = 0; j < 2; j++) {
                const Node *ch = kid[j];
                double dx = x[0] - ch->c[0], dy = x[1] - ch->c[1], dz = x[2] - ch->c[2];
                double d2 = dx * dx + dy * dy + dz * dz;
                double sg = best + ch->rg, sc = ch->rc + tol;
                int g = gap_open && sg > 0.0 && d2 < sg * sg && second_ok(ch, x, best), c = cov_open && d2 <= sc * sc;
                need[j] = g || c;
                d2k[j] = d2;
                /* nearer first by the power distance of the bound that still matters */
                key[j] = gap_open ? d2 - ch->rg * ch->rg : d2 - ch->rc * ch->rc;
            }
            int first = key[0] <= key[1] ? 0 : 1;
            for (int j = 1; j >= 0; j--) {
                int w = j == 0 ? first : 1 - first;  /* the second one pushed first */
                if (need[w]) { stack[sp].node = nd->kid + w; stack[sp].ver = ver; stack[sp++].d = d2k[w]; }
            }
        }
        if (want_gap) a.og[k] = best;
        if (want_cov) a.oc[k] = (uint8_t)(ci >= 0);
        if (bi >= 0) seed_g = bi;
        if (ci >= 0) seed_c = ci;
    }
    a.st[0] += visits;
    a.st[1] += tests;
    Py_END_ALLOW_THREADS
    balls_release(&a);
    Py_RETURN_NONE;
}

/* balls_block: the answers of balls (the same bits: each ball's excess and cover test computed alike, the
 * least excess taken over a superset of the balls that can hold it) for queries in tree order, walked once
 * per block of BLOCK consecutive queries instead of once per query.  The block's walk keeps the leaves that
 * may hold, for some query of the block, a ball with excess below that query's excess to a seed ball (the
 * previous block's last best) or a ball that covers it: a node's bounds taken at the block's bounding sphere
 * (its centre's distance less the sphere's radius), with a relative allowance that only adds leaves.  Each
 * query then tests those leaves' balls, a leaf skipped by the query's own bound as the walk of balls skips
 * it.  Queries far from every ball (the cloud around a pruned arm, asked again of the curve left) share
 * nearly all of their walk; a block with a non-finite coordinate keeps every leaf. */
#define BLOCK 16

static PyObject *py_balls_block(PyObject *self, PyObject *args) {
    BallsArgs a;
    if (!balls_args(args, &a)) return NULL;
    const Py_ssize_t i0 = a.i0, i1 = a.i1;
    const double floor_ = a.floor_, eps = a.eps;
    const Py_ssize_t n_nodes = a.nds.len / (Py_ssize_t)sizeof(Node);
    const Node *nodes = a.nodes;
    const double *p = a.p, *r = a.r, *R = a.R, *q = a.q;
    const int32_t n = a.n, want_gap = a.want_gap, want_cov = a.want_cov;
    int32_t *leaves = (int32_t *)malloc(sizeof(int32_t) * (size_t)(n_nodes > 0 ? n_nodes : 1));
    if (!leaves) {
        balls_release(&a);
        return PyErr_NoMemory();
    }
    Py_BEGIN_ALLOW_THREADS
    int32_t stack[MAX_STACK];
    int64_t visits = 0, tests = 0;
    const double tol = sqrt(eps > 0.0 ? eps : 0.0);  /* |q - x| <= sqrt(R^2 + eps) <= R + tol */
    int32_t seed = 0;
    for (Py_ssize_t b0 = i0; b0 < i1; b0 += BLOCK) {
        const Py_ssize_t b1 = b0 + BLOCK < i1 ? b0 + BLOCK : i1;
        const int m = (int)(b1 - b0);
        if (n == 0) {
            for (Py_ssize_t k = b0; k < b1; k++) {
                if (want_gap) a.og[k] = INFINITY;
                if (want_cov) a.oc[k] = 0;
            }
            continue;
        }
        /* the block's bounding sphere and each query's excess to the seed ball */
        double mn[3] = {INFINITY, INFINITY, INFINITY}, mx[3] = {-INFINITY, -INFINITY, -INFINITY};
        int finite = 1;
        for (Py_ssize_t k = b0; k < b1; k++)
            for (int j = 0; j < 3; j++) {
                double v = q[3 * (size_t)k + j];
                if (!isfinite(v)) finite = 0;
                if (v < mn[j]) mn[j] = v;
                if (v > mx[j]) mx[j] = v;
            }
        double cb[3] = {0.5 * (mn[0] + mx[0]), 0.5 * (mn[1] + mx[1]), 0.5 * (mn[2] + mx[2])}, rb = 0.0;
        double ub[BLOCK], top = -INFINITY;
        int32_t first = seed;
        for (int k = 0; k < m; k++) {
            const double *x = q + 3 * (size_t)(b0 + k), *c = p + 3 * (size_t)first;
            double d = dist3(x, cb);
            if (d > rb) rb = d;
            double dx = x[0] - c[0], dy = x[1] - c[1], dz = x[2] - c[2];
            double e = sqrt(dx * dx + dy * dy + dz * dz) - r[first];
            ub[k] = e == e ? e : INFINITY;
            if (ub[k] > top) top = ub[k];
        }
        rb = rb * (1.0 + 1e-9) + 1e-300;
        if (!want_gap) top = -INFINITY;
        /* the leaves any query of the block may need */
        int nl = 0, sp = 0;
        stack[sp++] = 0;
        while (sp > 0) {
            const int32_t ni = stack[--sp];
            const Node *nd = nodes + ni;
            double lower = -INFINITY;
            if (finite) {
                double d = dist3(cb, nd->c);
                lower = d - rb - 1e-9 * (d + rb + nd->rg + nd->rc + fabs(top) + tol) - 1e-300;
            }
            const int g = want_gap && lower - nd->rg < top, c = want_cov && lower <= nd->rc + tol;
            if (!g && !c) continue;
            if (nd->kid < 0) leaves[nl++] = ni;
            else if (sp + 2 <= MAX_STACK) { stack[sp++] = nd->kid + 1; stack[sp++] = nd->kid; }
            else { finite = 0; sp = 0; nl = 0; stack[sp++] = 0; top = INFINITY; }  /* not reached: depth < 64 */
        }
        /* each query over those leaves, as the walk of balls tests them */
        for (int k = 0; k < m; k++) {
            const Py_ssize_t qk = b0 + k;
            const double *x = q + 3 * (size_t)qk;
            double best = want_gap ? ub[k] : INFINITY;
            int32_t bi = first;
            int gap_open = want_gap && !(best <= floor_), cov_open = want_cov;
            int32_t ci = -1;
            for (int l = 0; l < nl && (gap_open || cov_open); l++) {
                const Node *nd = nodes + leaves[l];
                double dx = x[0] - nd->c[0], dy = x[1] - nd->c[1], dz = x[2] - nd->c[2];
                double d2 = dx * dx + dy * dy + dz * dz;
                double sg = best + nd->rg, sc = nd->rc + tol;
                const int g = gap_open && sg > 0.0 && d2 < sg * sg, c = cov_open && d2 <= sc * sc;
                if (!g && !c) continue;
                visits++;
                leaf_balls(nd, p, r, R, x, eps, floor_, &best, &bi, &gap_open, &cov_open, &ci);
                tests += nd->hi - nd->lo;
            }
            if (want_gap) a.og[qk] = best;
            if (want_cov) a.oc[qk] = (uint8_t)(ci >= 0);
            if (want_gap && best < INFINITY) seed = bi;
            else if (ci >= 0) seed = ci;
        }
    }
    a.st[0] += visits;
    a.st[1] += tests;
    Py_END_ALLOW_THREADS
    free(leaves);
    balls_release(&a);
    Py_RETURN_NONE;
}

static PyMethodDef methods[] = {
    {"build_tree", py_build_tree, METH_VARARGS, "KD-tree of bounding spheres (and slabs), double precision."},
    {"refit", py_refit, METH_VARARGS, "Ball bounds max |x - c| + r(x), max |x - c| + R(x) of a range of nodes."},
    {"nearest", py_nearest, METH_VARARGS, "Distance of each query to its nearest tree point (exact)."},
    {"balls", py_balls, METH_VARARGS, "Gap (least |q - x| - r) and cover (|q - x| <= R) of each query."},
    {"balls_block", py_balls_block, METH_VARARGS, "balls' answers, one walk per block of queries in tree order."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_balls",
                                    "Compiled kernel of SkelScope's coverage (docs/metrics.md, section 5.2).",
                                    -1, methods};

PyMODINIT_FUNC PyInit__balls(void) { return PyModule_Create(&module); }
