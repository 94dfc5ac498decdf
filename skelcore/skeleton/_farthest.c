/* Compiled farthest-point sampling by spheres: the toolbox's farthest_sampling_by_sphere, as
 * skelcore/skeleton/cao_curve.py reads it (design and numbers: docs/repair.md "The repair's cost",
 * "The fill curves compiled").
 *
 * Each start point k not yet taken opens a run; the run takes the point of largest distance to its
 * sample (first index among equals) as the next sample while any point is unlabelled, and the sample's
 * ball (squared distance <= r^2) takes the points it is closer to.  A ball whose points are all
 * labelled sets its centre's distance to 0 and adds no sample.  The heap of (distance, index) with
 * stale entries skipped is the Python loop's; the pop order is the total order (distance down, index
 * up) of the live entries, so any binary heap gives the same samples.
 *
 * The arithmetic is the Python loop's, bit for bit: membership is cKDTree's leaf test (the squared
 * differences summed x, y, z, against r * r), the distance numpy's norm of the same differences
 * (sqrt of that sum).  The balls come from a uniform grid of cells a little wider than r (each ball
 * within the 3 x 3 x 3 cells around its centre's).  Built with -ffp-contract=off: no fused
 * multiply-add.
 *
 * Plain C with the buffer protocol (no numpy headers at build time); the GIL is released but for the
 * caller's check, run every 256 samples tried as the Python loop runs it.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

typedef struct {
    double d;
    int64_t i;
} Entry;

/* a before b in the pop order: larger distance first, then smaller index */
static inline int before(const Entry *a, const Entry *b) {
    return a->d > b->d || (a->d == b->d && a->i < b->i);
}

typedef struct {
    Entry *e;
    size_t n, cap;
} Heap;

static int heap_push(Heap *h, double d, int64_t i) {
    if (h->n == h->cap) {
        size_t cap = h->cap ? 2 * h->cap : 1024;
        Entry *e = (Entry *)realloc(h->e, cap * sizeof(Entry));
        if (!e) return -1;
        h->e = e;
        h->cap = cap;
    }
    size_t c = h->n++;
    Entry x = {d, i};
    while (c > 0) {
        size_t p = (c - 1) / 2;
        if (!before(&x, &h->e[p])) break;
        h->e[c] = h->e[p];
        c = p;
    }
    h->e[c] = x;
    return 0;
}

static void heap_pop(Heap *h) {
    Entry x = h->e[--h->n];
    size_t c = 0;
    for (;;) {
        size_t l = 2 * c + 1, best = c;
        const Entry *bx = &x;
        if (l < h->n && before(&h->e[l], bx)) { best = l; bx = &h->e[l]; }
        if (l + 1 < h->n && before(&h->e[l + 1], bx)) best = l + 1;
        if (best == c) break;
        h->e[c] = h->e[best];
        c = best;
    }
    if (h->n) h->e[c] = x;
}

typedef struct {
    int64_t key, idx;
} Keyed;

static int by_key(const void *a, const void *b) {
    const Keyed *x = (const Keyed *)a, *y = (const Keyed *)b;
    if (x->key != y->key) return x->key < y->key ? -1 : 1;
    return x->idx < y->idx ? -1 : (x->idx > y->idx);
}

typedef struct {
    int64_t n, ncell, dims[3];
    double lo[3], inv;
    int64_t *cell_key, *cell_start; /* ncell + 1 starts */
    int64_t *order;                 /* point indices, cell by cell */
    double *xyz;                    /* their coordinates in that order */
} Grid;

static void grid_free(Grid *g) {
    free(g->cell_key); free(g->cell_start); free(g->order); free(g->xyz);
}

/* 0: built; 1: the grid would be too large (the caller falls back); -1: out of memory */
static int grid_build(Grid *g, const double *p, int64_t n, double radius) {
    memset(g, 0, sizeof(*g));
    g->n = n;
    double cell = radius * (1.0 + 1e-6), hi[3];
    g->inv = 1.0 / cell;
    for (int a = 0; a < 3; a++) { g->lo[a] = INFINITY; hi[a] = -INFINITY; }
    for (int64_t k = 0; k < n; k++)
        for (int a = 0; a < 3; a++) {
            double v = p[3 * k + a];
            if (v < g->lo[a]) g->lo[a] = v;
            if (v > hi[a]) hi[a] = v;
        }
    double total = 1.0;
    for (int a = 0; a < 3; a++) {
        double span = (hi[a] - g->lo[a]) * g->inv;
        if (!(span < 1e8)) return 1;
        g->dims[a] = (int64_t)floor(span) + 1;
        total *= (double)g->dims[a];
    }
    if (!(total < 4e18)) return 1;
    Keyed *kd = (Keyed *)malloc((size_t)n * sizeof(Keyed));
    g->order = (int64_t *)malloc((size_t)n * sizeof(int64_t));
    g->xyz = (double *)malloc((size_t)n * 3 * sizeof(double));
    g->cell_key = (int64_t *)malloc((size_t)n * sizeof(int64_t));
    g->cell_start = (int64_t *)malloc(((size_t)n + 1) * sizeof(int64_t));
    if (!kd || !g->order || !g->xyz || !g->cell_key || !g->cell_start) { free(kd); return -1; }
    for (int64_t k = 0; k < n; k++) {
        int64_t c[3];
        for (int a = 0; a < 3; a++) {
            c[a] = (int64_t)floor((p[3 * k + a] - g->lo[a]) * g->inv);
            if (c[a] < 0) c[a] = 0;
            if (c[a] >= g->dims[a]) c[a] = g->dims[a] - 1;
        }
        kd[k].key = (c[0] * g->dims[1] + c[1]) * g->dims[2] + c[2];
        kd[k].idx = k;
    }
    qsort(kd, (size_t)n, sizeof(Keyed), by_key);
    int64_t m = 0;
    for (int64_t k = 0; k < n; k++) {
        if (k == 0 || kd[k].key != kd[k - 1].key) {
            g->cell_key[m] = kd[k].key;
            g->cell_start[m++] = k;
        }
        g->order[k] = kd[k].idx;
        memcpy(g->xyz + 3 * k, p + 3 * kd[k].idx, 3 * sizeof(double));
    }
    g->cell_start[m] = n;
    g->ncell = m;
    free(kd);
    return 0;
}

/* the first cell whose key is >= key */
static int64_t lower_cell(const Grid *g, int64_t key) {
    int64_t a = 0, b = g->ncell;
    while (a < b) {
        int64_t mid = a + (b - a) / 2;
        if (g->cell_key[mid] < key) a = mid + 1;
        else b = mid;
    }
    return a;
}

/* the ball of point q (squared distance <= r2): indices into nb, squared distances into d2; returns the
 * count (nb and d2 hold n entries) */
static int64_t ball(const Grid *g, const double *q, double r2, int64_t *nb, double *d2) {
    int64_t c[3], m = 0;
    for (int a = 0; a < 3; a++) {
        c[a] = (int64_t)floor((q[a] - g->lo[a]) * g->inv);
        if (c[a] < 0) c[a] = 0;
        if (c[a] >= g->dims[a]) c[a] = g->dims[a] - 1;
    }
    for (int64_t x = c[0] - 1; x <= c[0] + 1; x++) {
        if (x < 0 || x >= g->dims[0]) continue;
        for (int64_t y = c[1] - 1; y <= c[1] + 1; y++) {
            if (y < 0 || y >= g->dims[1]) continue;
            int64_t z0 = c[2] > 0 ? c[2] - 1 : 0, z1 = c[2] + 1 < g->dims[2] ? c[2] + 1 : g->dims[2] - 1;
            int64_t base = (x * g->dims[1] + y) * g->dims[2];
            int64_t u = lower_cell(g, base + z0);
            int64_t s = u < g->ncell ? g->cell_start[u] : g->n, e = s;
            while (u < g->ncell && g->cell_key[u] <= base + z1) e = g->cell_start[++u];
            for (int64_t t = s; t < e; t++) {
                const double *v = g->xyz + 3 * t;
                double dx = v[0] - q[0], dy = v[1] - q[1], dz = v[2] - q[2];
                double s2 = 0.0;
                s2 += dx * dx;
                s2 += dy * dy;
                s2 += dz * dz;
                if (s2 <= r2) {
                    nb[m] = g->order[t];
                    d2[m++] = s2;
                }
            }
        }
    }
    return m;
}

/* sample(points (n, 3) f64, radius, check or None, corresp out (n,) i64, samples out (n,) i64)
 * -> number of samples, or None when the grid would be too large (the caller runs the Python loop) */
static PyObject *py_sample(PyObject *self, PyObject *args) {
    Py_buffer pb, cb, sb;
    double radius;
    PyObject *check;
    if (!PyArg_ParseTuple(args, "y*dOw*w*", &pb, &radius, &check, &cb, &sb)) return NULL;
    const int64_t n = (int64_t)(pb.len / (Py_ssize_t)(3 * sizeof(double)));
    PyObject *out = NULL;
    if (pb.len != (Py_ssize_t)(n * 3 * sizeof(double)) || cb.len != (Py_ssize_t)(n * sizeof(int64_t))
        || sb.len != cb.len || !(radius > 0.0) || !isfinite(radius)) {
        PyErr_SetString(PyExc_ValueError, "sample: inconsistent arrays or a radius not positive and finite");
        goto done;
    }
    const double *p = (const double *)pb.buf;
    int64_t *corresp = (int64_t *)cb.buf, *samples = (int64_t *)sb.buf;
    const double r2 = radius * radius;
    Grid g;
    Heap h = {NULL, 0, 0};
    double *mindst = (double *)malloc(((size_t)n + 1) * sizeof(double));
    double *d2 = (double *)malloc(((size_t)n + 1) * sizeof(double));
    int64_t *nb = (int64_t *)malloc(((size_t)n + 1) * sizeof(int64_t));
    int built = 1, failed = 0, cancelled = 0;
    int64_t ns = 0;
    if (!mindst || !d2 || !nb) failed = 1;
    Py_BEGIN_ALLOW_THREADS
    if (!failed) {
        built = grid_build(&g, p, n, radius);
        if (built < 0) failed = 1;
    }
    if (!failed && built == 0) {
        int64_t unlabelled = n, steps = 0;
        for (int64_t k = 0; k < n; k++) { corresp[k] = -1; mindst[k] = NAN; }
        for (int64_t k = 0; k < n && !failed && !cancelled; k++) {
            if (corresp[k] >= 0) continue;
            mindst[k] = INFINITY;
            if (heap_push(&h, INFINITY, k)) { failed = 1; break; }
            while (unlabelled > 0) {
                while (h.n && h.e[0].d != mindst[h.e[0].i]) heap_pop(&h);
                if (!h.n) break;
                const int64_t idx = h.e[0].i;
                if (h.e[0].d == 0.0) break;
                if (++steps % 256 == 0 && check != Py_None) {
                    Py_BLOCK_THREADS
                    PyObject *r = PyObject_CallNoArgs(check);
                    if (r) Py_DECREF(r);
                    else cancelled = 1;
                    Py_UNBLOCK_THREADS
                    if (cancelled) break;
                }
                const int64_t m = ball(&g, p + 3 * idx, r2, nb, d2);
                int64_t j = 0;
                while (j < m && corresp[nb[j]] >= 0) j++;
                if (j == m) {
                    mindst[idx] = 0.0;
                    heap_pop(&h);
                    continue;
                }
                const int64_t s = ns;
                samples[ns++] = idx;
                for (j = 0; j < m; j++) {
                    const int64_t v = nb[j];
                    const double d = sqrt(d2[j]), old = mindst[v];
                    if (!(isnan(old) || old > d)) continue;
                    if (corresp[v] < 0) unlabelled--;
                    mindst[v] = d;
                    corresp[v] = s;
                    if (d > 0.0 && heap_push(&h, d, v)) { failed = 1; break; }
                }
                if (failed) break;
            }
        }
    }
    if (built == 0) grid_free(&g);
    Py_END_ALLOW_THREADS
    free(mindst); free(d2); free(nb); free(h.e);
    if (cancelled) goto done;
    if (failed) { PyErr_NoMemory(); goto done; }
    out = built ? Py_NewRef(Py_None) : PyLong_FromLongLong((long long)ns);
done:
    PyBuffer_Release(&pb); PyBuffer_Release(&cb); PyBuffer_Release(&sb);
    return out;
}

static PyMethodDef methods[] = {
    {"sample", py_sample, METH_VARARGS, "Farthest-point sampling by spheres, the Python loop's samples and labels."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_farthest",
                                    "Compiled farthest-point sampling by spheres (docs/repair.md \"The repair's cost\").",
                                    -1, methods};

PyMODINIT_FUNC PyInit__farthest(void) { return PyModule_Create(&module); }
