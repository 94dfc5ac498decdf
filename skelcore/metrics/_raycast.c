/* Compiled kernel of the `rays` boundedness estimator (docs/metrics.md 2; design: docs/boundedness.md, section 3).
 *
 * beta(q) = share of the raster's direction samples s from q whose ray meets a ball of radius h around
 * a cloud point p with |p - q| > h.  A ray meets that ball iff s lies in p's cap of angular radius
 * asin(h / |p - q|), so this is the union-of-caps raster of _rays.py, sample for sample.
 *
 * Queries come in clusters (centre c, reach r).  Near points (|p - c| <= r) are rasterised as exact caps
 * from every member query (per-row longitude intervals, law of cosines), nearest shells first, stopping when a
 * raster is full.  Far points (|p - c| > r) are handled once per cluster: one any-hit ray cast from c,
 * through a KD-tree of bounding spheres, per sample that some member left open (cost ~ samples x depth,
 * not ~ points).  A cluster of one query at its own position is exact for any r.
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
#if defined(__AVX__)
#include <immintrin.h>
#elif defined(__SSE2__)
#include <emmintrin.h>
#endif

#define LEAF_SIZE 8

/* The module's name: setup.py also builds this file with -mavx2 as _raycast_avx2 (rays_kernel.py imports
 * it where the CPU has AVX2; docs/boundedness.md 3.11). */
#ifndef MODULE_NAME
#define MODULE_NAME _raycast
#endif
#define STR_(x) #x
#define STR(x) STR_(x)
#define CAT_(a, b) a##b
#define CAT(a, b) CAT_(a, b)

/* Lanes of floats (VF) and doubles (VD): GCC/Clang vector extensions, SSE2 on x86-64 (AVX with -mavx2),
 * NEON on arm64.  Element-wise IEEE operations without contraction (-std=c99 keeps -ffp-contract=off), so a
 * lane rounds exactly as the scalar expression written in the same order: the same bits on every build. */
#ifdef __AVX__
#define VF 8
#define VD 4
#else
#define VF 4
#define VD 2
#endif
typedef float vf __attribute__((vector_size(4 * VF)));
typedef int32_t vfi __attribute__((vector_size(4 * VF)));
typedef double vd __attribute__((vector_size(8 * VD)));
typedef int64_t vdi __attribute__((vector_size(8 * VD)));
typedef int32_t vdw __attribute__((vector_size(4 * VD)));  /* VD lanes of int32 */

static inline unsigned lane_mask(vfi m) {  /* bit l set iff lane l of the comparison holds */
#if defined(__AVX__)
    return (unsigned)_mm256_movemask_ps((__m256)m);
#elif defined(__SSE2__)
    return (unsigned)_mm_movemask_ps((__m128)m);
#else
    unsigned bits = 0;
    for (int l = 0; l < VF; l++) bits |= (unsigned)(m[l] & 1) << l;
    return bits;
#endif
}

static inline vd sqrt_lanes(vd q) {
#if defined(__AVX__)
    return (vd)_mm256_sqrt_pd((__m256d)q);
#elif defined(__SSE2__)
    return (vd)_mm_sqrt_pd((__m128d)q);
#else
    for (int l = 0; l < VD; l++) q[l] = sqrt(q[l]);
    return q;
#endif
}

static inline vd clamp_lanes(vd q) {  /* q clamped to [-1, 1] (q never NaN): max, then min */
#if defined(__AVX__)
    return (vd)_mm256_min_pd(_mm256_max_pd((__m256d)q, _mm256_set1_pd(-1.0)), _mm256_set1_pd(1.0));
#elif defined(__SSE2__)
    return (vd)_mm_min_pd(_mm_max_pd((__m128d)q, _mm_set1_pd(-1.0)), _mm_set1_pd(1.0));
#else
    for (int l = 0; l < VD; l++) q[l] = q[l] > 1.0 ? 1.0 : q[l] < -1.0 ? -1.0 : q[l];
    return q;
#endif
}
#define TWO_PI 6.283185307179586476925286766559

/* ------------------------------------------------------------------------------------------------ */
/* KD-tree of bounding spheres over a permutation of the points                                       */

typedef struct {
    float c[3], r;          /* bounding sphere */
    int32_t kid, lo, hi;    /* first child (second = kid + 1), or -1 - b for leaf b; point range [lo, hi) */
    int32_t par;            /* parent, -1 for the root */
} Node;                     /* 32 bytes: two siblings share a cache line */

typedef struct {
    const float *pts;       /* (n, 3) points in tree order */
    const Node *nodes;
    int32_t n_nodes;
    const float *leaf;      /* (leaves, 3, LEAF_SIZE): leaf b's points as x[8], y[8], z[8] (unused lanes NaN) */
    const struct Wide *wide; /* the same tree with WIDE children a node, for the packets (wide_tree); NULL: none */
} Tree;

static inline void swap_rows(double *key, int32_t *idx, double *wp, int32_t i, int32_t j) {
    double tk = key[i]; key[i] = key[j]; key[j] = tk;
    int32_t ti = idx[i]; idx[i] = idx[j]; idx[j] = ti;
    double *a = wp + 3 * (size_t)i, *b = wp + 3 * (size_t)j;
    for (int k = 0; k < 3; k++) { double t = a[k]; a[k] = b[k]; b[k] = t; }
}

static void select_nth(double *key, int32_t *idx, double *wp, int32_t lo, int32_t hi, int32_t nth) {
    /* quickselect on key[lo:hi] carrying idx and the point rows wp: afterwards key[nth] is the nth smallest */
    while (hi - lo > 1) {
        int32_t mid = lo + (hi - lo) / 2;
        double a = key[lo], b = key[mid], c = key[hi - 1];
        double pivot = (a < b) ? ((b < c) ? b : ((a < c) ? c : a)) : ((a < c) ? a : ((b < c) ? c : b));
        int32_t i = lo, j = hi - 1;
        while (i <= j) {
            while (key[i] < pivot) i++;
            while (key[j] > pivot) j--;
            if (i <= j) {
                swap_rows(key, idx, wp, i, j);
                i++; j--;
            }
        }
        if (nth <= j) hi = j + 1;
        else if (nth >= i) lo = i;
        else return;
    }
}

typedef struct {
    double *wp;              /* (n, 3) the points, permuted along with perm: every pass reads them in order */
    int32_t *perm;
    double *key;
    Node *nodes;
    int32_t n_nodes, cap;
    double pad;              /* absolute radius padding: float32 rounding of centres and points */
    volatile int32_t *stop;  /* set by another thread to abandon the build (a cancel) */
    int split_depth;         /* subtrees this many levels from the root or fewer get a thread of their own */
} Builder;

/* nodes of the subtree over n points (median splits, leaves of at most LEAF_SIZE) */
static int32_t subtree_nodes(int32_t n) {
    if (n <= LEAF_SIZE) return 1;
    return 1 + subtree_nodes(n / 2) + subtree_nodes(n - n / 2);
}

static void build_node(Builder *b, int32_t node, int32_t parent, int32_t lo, int32_t hi, int depth);

typedef struct { Builder b; int32_t node, parent, lo, hi; int depth; } BuildJob;

static void *build_job(void *arg) {
    BuildJob *j = (BuildJob *)arg;
    build_node(&j->b, j->node, j->parent, j->lo, j->hi, j->depth);
    return NULL;
}

static void build_node(Builder *b, int32_t node, int32_t parent, int32_t lo, int32_t hi, int depth) {
    Node *nd = b->nodes + node;
    nd->par = parent;
    nd->lo = lo;
    nd->hi = hi;
    nd->kid = -1;
    if (hi - lo > 4096 && *b->stop) return;
    double mn[3] = {INFINITY, INFINITY, INFINITY}, mx[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int32_t i = lo; i < hi; i++) {
        const double *p = b->wp + 3 * (size_t)i;
        for (int k = 0; k < 3; k++) {
            if (p[k] < mn[k]) mn[k] = p[k];
            if (p[k] > mx[k]) mx[k] = p[k];
        }
    }
    double c[3], r2 = 0.0;
    for (int k = 0; k < 3; k++) c[k] = 0.5 * (mn[k] + mx[k]);
    for (int32_t i = lo; i < hi; i++) {
        const double *p = b->wp + 3 * (size_t)i;
        double dx = p[0] - c[0], dy = p[1] - c[1], dz = p[2] - c[2];
        double d2 = dx * dx + dy * dy + dz * dz;
        if (d2 > r2) r2 = d2;
    }
    for (int k = 0; k < 3; k++) nd->c[k] = (float)c[k];
    nd->r = (float)(sqrt(r2) * (1.0 + 1e-6) + b->pad);
    if (hi - lo <= LEAF_SIZE || b->n_nodes + 2 > b->cap) return;
    int axis = 0;
    double ext = mx[0] - mn[0];
    for (int k = 1; k < 3; k++)
        if (mx[k] - mn[k] > ext) { ext = mx[k] - mn[k]; axis = k; }
    for (int32_t i = lo; i < hi; i++) b->key[i] = b->wp[3 * (size_t)i + axis];
    int32_t mid = lo + (hi - lo) / 2;
    select_nth(b->key, b->perm, b->wp, lo, hi, mid);
    int32_t first = b->n_nodes;
    b->n_nodes += 2;
    nd->kid = first;
    if (depth < b->split_depth && hi - lo > 65536) {
        /* the second subtree on its own thread, numbered as the sequential build numbers it: its nodes
         * follow all of the first subtree's */
        BuildJob job = {*b, first + 1, node, mid, hi, depth + 1};
        job.b.n_nodes = first + 2 + (subtree_nodes(mid - lo) - 1);
        pthread_t th;
        if (pthread_create(&th, NULL, build_job, &job) == 0) {
            build_node(b, first, node, lo, mid, depth + 1);
            pthread_join(th, NULL);
            b->n_nodes = job.b.n_nodes;
            return;
        }
    }
    build_node(b, first, node, lo, mid, depth + 1);
    build_node(b, first + 1, node, mid, hi, depth + 1);
}

/* build_tree(points (n,3) f64, perm (n) i32 out, nodes (cap) Node out, stop (1) i32, threads,
 *            tree_points (n,3) f32 out) -> number of nodes, or -1 if stop was set meanwhile.  perm lists the
 * input rows in tree order, tree_points the points in that order.  The tree does not depend on threads. */
static PyObject *py_build_tree(PyObject *self, PyObject *args) {
    Py_buffer pts, perm, nds, stop, out;
    int threads = 1;
    if (!PyArg_ParseTuple(args, "y*w*w*w*iw*", &pts, &perm, &nds, &stop, &threads, &out)) return NULL;
    int32_t n = (int32_t)(pts.len / (3 * sizeof(double)));
    int32_t cap = (int32_t)(nds.len / (Py_ssize_t)sizeof(Node));
    PyObject *result = NULL;
    double *key = NULL, *wp = NULL;
    if (perm.len / (Py_ssize_t)sizeof(int32_t) < n || cap < 1 || out.len < 3 * (Py_ssize_t)sizeof(float) * n) {
        PyErr_SetString(PyExc_ValueError, "build_tree: output buffers too small");
        goto done;
    }
    key = (double *)malloc(sizeof(double) * (size_t)(n > 0 ? n : 1));
    wp = (double *)malloc(3 * sizeof(double) * (size_t)(n > 0 ? n : 1));
    if (!key || !wp) { PyErr_NoMemory(); goto done; }
    double scale = 1.0;
    for (Py_ssize_t i = 0; i < 3 * (Py_ssize_t)n; i++) {
        double v = fabs(((const double *)pts.buf)[i]);
        if (v > scale) scale = v;
    }
    int split = 0;
    while ((1 << split) < threads && split < 6) split++;
    Builder b = {wp, (int32_t *)perm.buf, key, (Node *)nds.buf, 1, cap, 1e-6 * scale,
                 (volatile int32_t *)stop.buf, split};
    int32_t total = 0;
    Py_BEGIN_ALLOW_THREADS
    memcpy(wp, pts.buf, 3 * sizeof(double) * (size_t)n);
    for (int32_t i = 0; i < n; i++) b.perm[i] = i;
    build_node(&b, 0, -1, 0, n, 0);
    total = b.n_nodes;
    float *tp = (float *)out.buf;
    for (size_t i = 0; i < 3 * (size_t)n; i++) tp[i] = (float)wp[i];
    Py_END_ALLOW_THREADS
    result = PyLong_FromLong(*b.stop ? -1 : total);
done:
    free(key);
    free(wp);
    PyBuffer_Release(&pts); PyBuffer_Release(&perm); PyBuffer_Release(&nds); PyBuffer_Release(&stop);
    PyBuffer_Release(&out);
    return result;
}

/* ------------------------------------------------------------------------------------------------ */
/* The raster: rows of equal height in z, bins of equal longitude; one sample per cell centre         */

typedef struct {
    int rows, bins, words;     /* words per row */
    double *z, *s, *inv_s, *z_over_s, *cos_lon, *sin_lon;
    int32_t *row_start, *row_in, *row_wrap;  /* add_cap's scratch per row: bins [start, in) and [0, wrap) */
    uint64_t last_mask;        /* valid bits of a row's last word */
    uint64_t *below;           /* rows of two words: below[2 x .. 2 x + 1] = bits [0, x), x = 0 .. bins */
} Raster;

static int raster_init(Raster *r, int rows, int bins) {
    r->rows = rows;
    r->bins = bins;
    r->words = (bins + 63) / 64;
    r->last_mask = (bins % 64) ? ((UINT64_C(1) << (bins % 64)) - 1) : ~UINT64_C(0);
    /* every per-row array has VD - 1 padding entries (add_cap reads rows VD at a time) */
    const int pad = rows + VD - 1;
    r->z = (double *)calloc((size_t)(6 * pad + 2 * bins), sizeof(double));
    if (!r->z) return -1;
    r->s = r->z + pad;
    r->inv_s = r->s + pad;
    r->z_over_s = r->inv_s + pad;
    r->row_start = (int32_t *)(r->z_over_s + pad);  /* three int32 arrays in two double arrays' room */
    r->row_in = r->row_start + pad;
    r->row_wrap = r->row_in + pad;
    r->cos_lon = r->z_over_s + 3 * pad;
    r->sin_lon = r->cos_lon + bins;
    for (int j = 0; j < rows; j++) {
        double z = -1.0 + (j + 0.5) * (2.0 / rows);
        r->z[j] = z;
        r->s[j] = sqrt(1.0 - z * z);
        r->inv_s[j] = 1.0 / r->s[j];
        r->z_over_s[j] = z / r->s[j];
    }
    r->below = NULL;
    if (r->words == 2) {  /* add_cap's interval masks by table (bins 65 ... 128, the usual raster) */
        r->below = (uint64_t *)calloc(2 * (size_t)(bins + 1), sizeof(uint64_t));
        if (!r->below) { free(r->z); r->z = NULL; return -1; }
        for (int x = 0; x <= bins; x++) {
            r->below[2 * x] = x >= 64 ? ~UINT64_C(0) : (UINT64_C(1) << x) - 1;
            r->below[2 * x + 1] = x <= 64 ? 0 : x == 128 ? ~UINT64_C(0) : (UINT64_C(1) << (x - 64)) - 1;
        }
    }
    for (int k = 0; k < bins; k++) {
        double lon = (k + 0.5) * (TWO_PI / bins);
        r->cos_lon[k] = cos(lon);
        r->sin_lon[k] = sin(lon);
    }
    return 0;
}

static void raster_free(Raster *r) { free(r->z); free(r->below); }

/* one raster's bits: rows x words, plus the count of full rows */
static inline int row_is_full(const Raster *r, const uint64_t *row) {
    for (int w = 0; w < r->words - 1; w++)
        if (row[w] != ~UINT64_C(0)) return 0;
    return row[r->words - 1] == r->last_mask;
}

static inline void set_bits(uint64_t *row, int a, int b) {
    /* bits [a, b) of a row, 0 <= a <= b: a mask for the first and the last word, whole words between */
    if (a >= b) return;
    int wa = a >> 6, wb = (b - 1) >> 6;
    uint64_t first = ~UINT64_C(0) << (a & 63), last = ~UINT64_C(0) >> (63 - ((b - 1) & 63));
    if (wa == wb) {
        row[wa] |= first & last;
        return;
    }
    row[wa] |= first;
    for (int w = wa + 1; w < wb; w++) row[w] = ~UINT64_C(0);
    row[wb] |= last;
}

/* acos on [-1, 1] to within 6e-12 rad, VD lanes at once: acos(x) = sqrt(1 - x) P11(x) on [0, 1] (the form
 * of Abramowitz & Stegun 4.4.46, coefficients refitted for degree 11 near-minimax absolute error),
 * acos(-x) = pi - acos(x).  It replaces glibc's acos call (12 % of the kernel's CPU on a scanned tree;
 * docs/boundedness.md 3.8); in lanes (3.11: the same bits as the scalar form).  A cap's
 * interval ends are truncated to bins (96 / 2 pi bins per rad), so a sample can change side only within
 * 1e-10 bins of a cap edge. */
static inline vd acos_lanes(vd x) {
    vd a = (vd)((vdi)x & INT64_C(0x7fffffffffffffff));
    vd p = (vd){0} - 1.672209418596159e-04;
    p = p * a + 1.1512229129094958e-03;
    p = p * a - 3.7477159300164384e-03;
    p = p * a + 7.91670454880172e-03;
    p = p * a - 1.2794338604959644e-02;
    p = p * a + 1.7952216644927355e-02;
    p = p * a - 2.420551142654848e-02;
    p = p * a + 3.365570099497326e-02;
    p = p * a - 5.07905022548988e-02;
    p = p * a + 8.904851410439575e-02;
    p = p * a - 2.1460183461102783e-01;
    p = p * a + 1.5707963267888694;
    vd r = sqrt_lanes(1.0 - a) * p;
    vdi neg = x < 0.0;
    return (vd)((neg & (vdi)(3.141592653589793238462643383280 - r)) | (~neg & (vdi)r));
}

/* The cap of (dx, dy, dz) = p - q (|p - q| > h) into the bitmap, rows already full skipped.
 * The same arithmetic as _rays.CapRaster.covered, in double precision.  Returns rows newly full. */
static int add_cap(const Raster *r, uint64_t *bits, uint8_t *full, double dx, double dy, double dz, double d2,
                   double h) {
    const int rows = r->rows, bins = r->bins;
    double inv = 1.0 / sqrt(d2);
    double uz = dz * inv;
    double sina = h * inv;
    if (sina > 1.0) sina = 1.0;
    double cosa = sqrt(1.0 - sina * sina);
    double rho2 = 1.0 - uz * uz;
    double rho = rho2 > 0.0 ? sqrt(rho2) : 0.0;
    double mid = uz * cosa, spread = rho * sina;
    double zhi = mid + spread, zlo = mid - spread;
    if (uz >= cosa) zhi = 1.0;
    if (-uz >= cosa) zlo = -1.0;
    int first = (int)((zlo + 1.0) * (0.5 * rows) + 0.5);
    int end = (int)((zhi + 1.0) * (0.5 * rows) + 0.5);
    if (end > rows) end = rows;
    if (first < 0) first = 0;
    if (end <= first) return 0;
    int open = first;  /* a cap whose rows are all full adds nothing: no atan2 for it */
    while (open < end && full[open]) open++;
    if (open == end) return 0;
    if (rho < 1e-30) rho = 1e-30;
    double a0 = cosa / rho, a1 = uz / rho;
    double centre = atan2(dy, dx) * (bins / TWO_PI) + bins + 0.5;
    /* each row's interval VD rows at a time (the acos chains overlap): its first bin and its length, from
     * the cosine c and the half-width in bins; c <= -1 is a whole row.  Both ends are positive (centre
     * >= bins / 2 + 0.5 >= half), so the conversion truncates as (int) of each end would.  Stored as
     * [start, in) and its wrap [0, wrap) past bins; an empty interval as in = start, wrap = 0. */
    const vd cen = (vd){0} + centre;
    for (int j = open; j < end; j += VD) {
        vd is, zs;
        memcpy(&is, r->inv_s + j, sizeof is);
        memcpy(&zs, r->z_over_s + j, sizeof zs);
        vd c = a0 * is - a1 * zs;
        vd half = acos_lanes(clamp_lanes(c)) * (bins / TWO_PI);
        vdw whole = __builtin_convertvector(c <= -1.0, vdw);
        vdw start = __builtin_convertvector(cen - half, vdw);
        vdw len = __builtin_convertvector(cen + half, vdw) - start;
        vdw over = len > bins;
        len = (over & bins) | (~over & len);
        start -= (start >= bins) & bins;
        start &= ~whole;
        len = (whole & bins) | (~whole & len);
        vdw stop = start + (len & (len > 0));
        vdw past = stop > bins;
        vdw in = (past & bins) | (~past & stop), wrap = past & (stop - bins);
        memcpy(r->row_start + j, &start, sizeof start);
        memcpy(r->row_in + j, &in, sizeof in);
        memcpy(r->row_wrap + j, &wrap, sizeof wrap);
    }
    int newly = 0;
    if (r->below) {  /* two words a row: [start, stop) and its wrap past bins as table masks, no branches */
        const uint64_t *below = r->below;
        for (int j = open; j < end; j++) {
            if (full[j]) continue;
            const uint64_t *in = below + 2 * r->row_in[j], *out = below + 2 * r->row_start[j];
            const uint64_t *wr = below + 2 * r->row_wrap[j];
            uint64_t *row = bits + 2 * (size_t)j;
            const uint64_t w0 = row[0] | (in[0] & ~out[0]) | wr[0];
            const uint64_t w1 = row[1] | (in[1] & ~out[1]) | wr[1];
            row[0] = w0;
            row[1] = w1;
            if ((~w0 | (w1 ^ r->last_mask)) == 0) { full[j] = 1; newly++; }
        }
        return newly;
    }
    for (int j = open; j < end; j++) {
        const int start = r->row_start[j], in = r->row_in[j], wrap = r->row_wrap[j];
        if (full[j] || (in == start && wrap == 0)) continue;
        uint64_t *row = bits + (size_t)j * r->words;
        set_bits(row, start, in);
        set_bits(row, 0, wrap);
        if (row_is_full(r, row)) { full[j] = 1; newly++; }
    }
    return newly;
}

/* ------------------------------------------------------------------------------------------------ */
/* Any-hit ray cast from o along s against the balls of the points with |p - o|^2 > cut2              */

typedef struct {
    int32_t *stack;
    int32_t last_leaf;         /* the leaf of the previous ray's hit */
    int32_t hit_point;         /* the point of the last hit a walk found */
    int64_t visits, hint_tries, hint_hits;
} Walker;

static inline int point_hit(const Tree *t, int32_t i, const float *o, const float *s, float cut2, float h2) {
    const float *p = t->pts + 3 * (size_t)i;
    float wx = p[0] - o[0], wy = p[1] - o[1], wz = p[2] - o[2];
    float d2 = wx * wx + wy * wy + wz * wz;
    if (d2 <= cut2) return 0;
    float tt = wx * s[0] + wy * s[1] + wz * s[2];
    return tt > 0.0f && d2 - tt * tt <= h2;
}

/* the first point of the leaf whose ball the ray meets, or -1: point_hit on its 8 lanes, VF at once (the
 * same operations in the same order, so the same bits; a NaN lane never hits).  A node that is no leaf (a hint
 * from a table the kernel did not make for this tree: seed_cells checks only the ranges) holds no hit. */
static inline int32_t leaf_hit(const Tree *t, int32_t node, const float *o, const float *s, float cut2, float h2) {
    const Node *nd = t->nodes + node;
    const int32_t kid = nd->kid;
    const float *L = t->leaf + 3 * LEAF_SIZE * (size_t)(kid < 0 ? -1 - kid : 0);
    unsigned mask = 0;
    for (int g = 0; g < LEAF_SIZE; g += VF) {
        vf x, y, z;
        memcpy(&x, L + g, sizeof x);
        memcpy(&y, L + LEAF_SIZE + g, sizeof y);
        memcpy(&z, L + 2 * LEAF_SIZE + g, sizeof z);
        vf wx = x - o[0], wy = y - o[1], wz = z - o[2];
        vf d2 = wx * wx + wy * wy + wz * wz;
        vf tt = wx * s[0] + wy * s[1] + wz * s[2];
        vfi hit = (d2 > cut2) & (tt > 0.0f) & (d2 - tt * tt <= h2);
        mask |= lane_mask(hit) << g;
    }
    return mask && kid < 0 ? nd->lo + __builtin_ctz(mask) : -1;
}

/* Can the node hold a counted point whose ball the ray meets?  Not if every point of it lies within the
 * cut, nor if the ray passes farther than its radius + h from its centre. */
static inline int node_passes(const Node *nd, const float *o, const float *s, float cut, float h) {
    float wx = nd->c[0] - o[0], wy = nd->c[1] - o[1], wz = nd->c[2] - o[2];
    float rad = nd->r;
    float d2 = wx * wx + wy * wy + wz * wz;
    float lim = cut - rad;
    if (lim > 0.0f && d2 <= lim * lim) return 0;
    float tt = wx * s[0] + wy * s[1] + wz * s[2];
    float reach = rad + h;
    float off2 = (tt > 0.0f) ? d2 - tt * tt : d2;
    return off2 <= reach * reach;
}

/* Any-hit walk of the subtree at `root` (skipping subtree `skip` and leaves `skip_a`, `skip_b`, already
 * tested): the leaf of a hit, or -1.  Both children are tested before they are pushed (the two tests are
 * independent, so they overlap), the nearer along the ray first. */
static int32_t walk(const Tree *t, Walker *w, int32_t root, int32_t skip, int32_t skip_a, int32_t skip_b,
                    const float *o, const float *s, float cut, float h) {
    const float h2 = h * h, cut2 = cut * cut;
    if (root == skip) return -1;
    w->visits++;
    if (!node_passes(t->nodes + root, o, s, cut, h)) return -1;
    int sp = 0;
    w->stack[sp++] = root;
    while (sp > 0) {
        int32_t node = w->stack[--sp];
        const Node *nd = t->nodes + node;
        int32_t k = nd->kid;
        if (k < 0) {
            if (node != skip_a && node != skip_b && (w->hit_point = leaf_hit(t, node, o, s, cut2, h2)) >= 0)
                return node;
            continue;
        }
        const Node *a = t->nodes + k, *b = a + 1;
        int pa = k != skip && node_passes(a, o, s, cut, h);
        int pb = k + 1 != skip && node_passes(b, o, s, cut, h);
        w->visits += 2;
        /* the child whose centre lies nearer along the ray first: (a - b) . s <= 0 (only the order) */
        float ab = (a->c[0] - b->c[0]) * s[0] + (a->c[1] - b->c[1]) * s[1] + (a->c[2] - b->c[2]) * s[2];
        if (ab <= 0.0f) {
            if (pb) w->stack[sp++] = k + 1;
            if (pa) w->stack[sp++] = k;
        } else {
            if (pa) w->stack[sp++] = k;
            if (pb) w->stack[sp++] = k + 1;
        }
    }
    return -1;
}

/* levels a ray that its hints did not settle walks up from its hinted leaf (each ancestor's other subtree)
 * before it is left to a packet from the root.  2 paid before the tiles and the 32-ray packets (3.10); with
 * them every such ray goes straight to a packet: 3-4 % less CPU on an edit's samples, the hammer and the
 * scans (docs/boundedness.md 3.15) */
#define WALK_UP 0

/* A stream whose hints hit fewer than HINT_MIN per mille of its recent clusters' far rays sends the rays of
 * the next HINT_REST clusters straight to packets, then tries the hints again: where a cluster's move is
 * many leaves wide (the 1M torus: 3 % of hint tries hit; an edit's moved samples at 1M points: 18 % of the
 * rays) a failed try costs a point test and leaf tests for nothing.  Only the hints' own hits count (a
 * point or a leaf tried), not the rays a walk up (WALK_UP) finds, and over the recent clusters (each
 * cluster's counts added to half the previous sums), so one cluster's luck decides nothing
 * (docs/boundedness.md 3.15).  The hints only order the search, so beta is the same either way. */
#define HINT_MIN 250
#define HINT_REST 7

/* The needed samples are cast tile by tile, TILE_ROWS rows x TILE_BINS bins (a power of 2 up to 64, so a
 * tile lies in one word of a row), rows in turn within a tile: the rays a packet collects then point
 * into one compact patch of the sphere (8 x 4 cells, about 19 x 15 degrees at the equator) instead of a
 * strip of one row, and share more nodes (docs/boundedness.md 3.10). */
#define TILE_ROWS 8
#define TILE_BINS 4
#define TILE_MASK ((TILE_BINS) >= 64 ? ~UINT64_C(0) : (UINT64_C(1) << (TILE_BINS)) - 1)

/* Lone queries (clusters of one member) are cast BLOCK at a time, band by band: a band (TILE_ROWS rows x
 * BAND_BINS bins, a multiple of TILE_BINS) of every query of the block, then the next band.  Consecutive
 * queries lie a few h apart, so the rays of one band from them meet the same part of the cloud and its
 * nodes, leaves and points stay in the caches from one query to the next, where one query's whole raster
 * reaches more of the tree than the caches hold (docs/boundedness.md 3.19).  Only the order of the rays
 * changes: every hit is the same exact test, so beta is the same bit for bit. */
#define BLOCK 32
#define BAND_BINS 32
/* ... where the points exceed this many bytes (the `clusters` call's `block` > 1 casts blocks of that many at any
 * size): the hammer's 48 KB stay in the caches anyway, and there its 208 curve samples took 20 % more CPU in
 * blocks (the hints skipped per block, HINT_MIN, rather than per query) */
#define BLOCK_FROM (512 * 1024)

/* The move of the rays' origin since the previous cluster, and the raster's hints (moved_cells) */
typedef struct {
    float d[3];
    int on, rows, bins;
    int32_t *hints;
    const float *lon_scale;  /* per row: bins / 2 pi / s_j^2 (longitude change in bins per unit of x dy - y dx) */
    int band, bands_across;  /* cast band by band (BLOCK): cells of a later band than `band` hold no hint yet */
} Move;

/* The hint of the sample whose ray from the previous origin passed where this ray passes now: the sample's
 * own hint point p (hit from the previous origin o - d at tt along s) has moved with the origin to about
 * o + tt s, which the previous origin saw along v = tt s + d; the cell of v (its row from v's z, its bin
 * from the first-order change of longitude) holds the point that ray hit.  Only a candidate, tested exactly
 * (point_hit, leaf_hit) like every hint: where the origin moves along a wall, as curve samples along a tube's
 * axis, the sample's own hint point misses by the move (docs/boundedness.md 3.14).  The cells of a tile's rays
 * are found together, VF lanes at a time from the offsets w = p - o its own-point test computed (the same
 * float operations in the same order as one ray at a time, floor from a truncation; docs/boundedness.md 3.22):
 * out[l] = the cell of ray l's candidate, or -1 where there is none (no hint point, the origin unmoved, v
 * behind the origin, off the raster, the ray's own cell, or a later band not yet filled).  A lane from n on is
 * NaN (tt fails). */
static inline void moved_cells(const Move *mv, const float *wxs, const float *wys, const float *wzs, const float *sx,
                               const float *sy, const float *sz, const float *ls, const int32_t *rj, const int32_t *rb,
                               int n, int32_t *out) {
    const float rows_f = (float)mv->rows, half_rows = 0.5f * mv->rows;
    const float lon_lo = -0.5f * mv->bins, lon_hi = 0.5f * mv->bins;
    const float d0 = mv->d[0], d1 = mv->d[1], d2 = mv->d[2];
    for (int g = 0; g < n; g += VF) {
        vf wx, wy, wz, s0, s1, s2, sc;
        vfi j, b;
        memcpy(&wx, wxs + g, sizeof wx); memcpy(&wy, wys + g, sizeof wy); memcpy(&wz, wzs + g, sizeof wz);
        memcpy(&s0, sx + g, sizeof s0); memcpy(&s1, sy + g, sizeof s1); memcpy(&s2, sz + g, sizeof s2);
        memcpy(&sc, ls + g, sizeof sc);
        memcpy(&j, rj + g, sizeof j); memcpy(&b, rb + g, sizeof b);
        const vf sd = s0 * d0 + s1 * d1 + s2 * d2;
        const vf tt = wx * s0 + wy * s1 + wz * s2 + sd;
        vfi ok = tt > 0.0f;
        const vf inv = 1.0f / tt;
        const vf z = s2 + (d2 - s2 * sd) * inv;
        const vf lon = (s0 * d1 - s1 * d0) * inv * sc;
        const vf y = (z + 1.0f) * half_rows;
        ok &= (y >= 0.0f) & (y < rows_f) & (lon > lon_lo) & (lon < lon_hi);
        /* (int)y and (int)floorf(lon + 0.5f) where ok (elsewhere 0, never converted out of range) */
        const vf ys = (vf)((vfi)y & ok), u = (vf)((vfi)(lon + 0.5f) & ok);
        const vfi j2 = __builtin_convertvector(ys, vfi);
        vfi fl = __builtin_convertvector(u, vfi);
        fl += (vfi)(__builtin_convertvector(fl, vf) > u);  /* -1 where the truncation rounded up */
        vfi b2 = b + fl;
        ok &= (b2 != b) | (j2 != j);
        b2 += (vfi)(b2 < 0) & mv->bins;
        b2 -= (vfi)(b2 >= mv->bins) & mv->bins;
        ok &= (j2 / TILE_ROWS) * mv->bands_across + b2 / BAND_BINS <= mv->band;
        const vfi cell = ((j2 * mv->bins + b2) & ok) | ~ok;
        memcpy(out + g, &cell, sizeof cell);
    }
}

/* Does the ray from o along s meet a ball around a point with |p - o| > cut?  1 yes, 0 no, -1 not settled:
 * the caller walks it from the root in a packet (walk_packet).  Exact either way; the hints only order the
 * search.  hint[0], hint[1] = the leaf and the point a nearby ray hit (the same sample from the previous
 * cluster): that point first (a centre one cell away usually still sees it; the caller has tested it, in
 * lanes over a tile's rays: cast_band), then the point and the leaf of
 * the sample its hit moved to (the cell `moved`: moved_cells), then its leaf, then (`sibling`: where the points exceed
 * PREFETCH_FROM) that leaf's sibling where it is a leaf, then the previous ray's leaf, then the subtrees of
 * the WALK_UP nearest ancestors of the moved hint's leaf where it was tried, else of the hinted leaf
 * (docs/boundedness.md 3.14, 3.20). */
static int ray_hits(const Tree *t, Walker *w, const float *o, const float *s, float cut, float h,
                    int32_t *hint, const int32_t *hints, int32_t moved, int sibling) {
    const float h2 = h * h, cut2 = cut * cut;
    int32_t a = hint[0], b = w->last_leaf, p, up_from = -1;
    if (hint[1] >= 0 && moved >= 0) {  /* its point missed; the moved hint's cell (moved_cells) */
        const int32_t *cand = hints + 2 * (size_t)moved;
        if (cand[1] >= 0 && cand[1] != hint[1]) {
            w->hint_tries++;
            if (point_hit(t, cand[1], o, s, cut2, h2)) {
                w->hint_hits++;
                hint[0] = cand[0];
                hint[1] = cand[1];
                w->last_leaf = cand[0];
                return 1;
            }
            if (cand[0] != a && cand[0] >= 0) {
                w->hint_tries++;
                if ((p = leaf_hit(t, cand[0], o, s, cut2, h2)) >= 0) {
                    w->hint_hits++; hint[0] = cand[0]; hint[1] = p; w->last_leaf = cand[0]; return 1;
                }
                up_from = cand[0];
            }
        }
    }
    if (a >= 0) {
        w->hint_tries++;
        if ((p = leaf_hit(t, a, o, s, cut2, h2)) >= 0) { w->hint_hits++; w->last_leaf = a; hint[1] = p; return 1; }
        /* its sibling where that is a leaf too (the same cache line of nodes, the next leaf block) */
        const int32_t sib = (a & 1) ? a + 1 : a - 1;
        if (sibling && a > 0 && sib < t->n_nodes && sib != b && t->nodes[sib].kid < 0) {
            w->hint_tries++;
            if ((p = leaf_hit(t, sib, o, s, cut2, h2)) >= 0) {
                w->hint_hits++; hint[0] = sib; hint[1] = p; w->last_leaf = sib; return 1;
            }
        }
    }
    if (b >= 0 && b != a) {
        w->hint_tries++;
        if ((p = leaf_hit(t, b, o, s, cut2, h2)) >= 0) { w->hint_hits++; hint[0] = b; hint[1] = p; return 1; }
    }
    if (a < 0) return -1;
    int32_t leaf = -1;
    const int32_t start = up_from >= 0 ? up_from : a;
    if (t->nodes[start].kid >= 0) return -1;  /* no leaf (a stale seed, seed_cells): nothing below it was tested */
    int32_t prev = start, node = t->nodes[start].par;
    for (int up = 0; up < WALK_UP && node >= 0 && leaf < 0; up++) {
        leaf = walk(t, w, node, prev, a, b, o, s, cut, h);
        prev = node;
        node = t->nodes[node].par;
    }
    if (leaf < 0) return node >= 0 ? -1 : 0;  /* the whole tree walked (a small one): a miss */
    hint[0] = leaf;
    hint[1] = w->hit_point;
    w->last_leaf = leaf;
    return 1;
}

/* What a walk reads after the node: its children's pair (one cache line where the pair is aligned,
 * BallTree) or its leaf block, asked of memory while the walk tests the nodes before it (at 1M points the
 * tree is larger than the caches and a visit waits on memory); no value depends on it. */
static inline void prefetch_below(const Tree *t, const Node *nd) {
    int32_t k = nd->kid;
    if (k >= 0) {
        __builtin_prefetch(t->nodes + k);
    } else {
        const float *L = t->leaf + 3 * LEAF_SIZE * (size_t)(-1 - k);
        __builtin_prefetch(L);
        __builtin_prefetch(L + 3 * LEAF_SIZE - 1);
    }
}

/* Up to PACKET rays from one origin that the hints did not settle (mostly rays that escape: they cost most
 * of the walks), walked from the root together: one traversal, each node tested against every ray still open
 * (the shared part of the test once, the rays' part VF lanes at a time) as its parent is visited, each leaf
 * tested ray by ray (its points' offsets from the origin once).  A
 * node can hold a hit for a ray only if some of its points lie beyond the cut and the ray passes within
 * its radius + h of its centre; a ray meets a point's ball iff point_hit.  Exact per ray, so the hits do
 * not depend on which rays share a packet (docs/boundedness.md 3.10-3.11). */
#define PACKET 32

typedef struct {
    float sx[PACKET], sy[PACKET], sz[PACKET];  /* the rays' directions; lanes from n on are masked out */
    int32_t *hint[PACKET];
    uint64_t *word[PACKET];
    uint64_t bit[PACKET];
    int n;
} Packet;

/* The rays of `m` that the node can hold a hit for: some of its points lie beyond the cut and the ray passes
 * within its radius + h of its centre (node_passes, the rays' part VF lanes at a time). */
static inline unsigned packet_pass(const Node *nd, const float *o, const vf *sx, const vf *sy, const vf *sz,
                                   float cut, float h, unsigned m) {
    float wx = nd->c[0] - o[0], wy = nd->c[1] - o[1], wz = nd->c[2] - o[2];
    float rad = nd->r;
    float d2 = wx * wx + wy * wy + wz * wz;
    float lim = cut - rad;
    if (lim > 0.0f && d2 <= lim * lim) return 0;
    float reach2 = (rad + h) * (rad + h);
    /* the rays' part: off2 = d2 - tt^2 where tt > 0, else d2 (d2 - 0 = d2 exactly) */
    unsigned pass = 0;
    for (int g = 0; g < PACKET / VF; g++) {
        vf tt = wx * sx[g] + wy * sy[g] + wz * sz[g];
        vf sq = (vf)((vfi)(tt * tt) & (tt > 0.0f));
        pass |= lane_mask(d2 - sq <= reach2) << (VF * g);
    }
    return m & pass;
}

/* The packet's directions in lanes and their sum */
static inline void packet_lanes(const Packet *pk, vf *sx, vf *sy, vf *sz, float *sum) {
    float mx = 0.0f, my = 0.0f, mz = 0.0f;
    for (int l = 0; l < pk->n; l++) { mx += pk->sx[l]; my += pk->sy[l]; mz += pk->sz[l]; }
    sum[0] = mx; sum[1] = my; sum[2] = mz;
    for (int g = 0; g < PACKET / VF; g++) {
        memcpy(&sx[g], pk->sx + VF * g, sizeof(vf));
        memcpy(&sy[g], pk->sy + VF * g, sizeof(vf));
        memcpy(&sz[g], pk->sz + VF * g, sizeof(vf));
    }
}

/* leaf_hit for every open ray of `m` against leaf `node` (block `blk`, first point `lo`), the rays' common
 * part (w = p - o, d2 > cut2) once: each ray hit leaves the packet, its hint and far bit set; the rays still
 * open returned */
static inline unsigned packet_leaf(const Tree *t, Walker *w, Packet *pk, int32_t node, int32_t blk, int32_t lo,
                                   unsigned m, unsigned active, const float *o, float cut2, float h2) {
    const float *L = t->leaf + 3 * LEAF_SIZE * (size_t)blk;
    vf lx[LEAF_SIZE / VF], ly[LEAF_SIZE / VF], lz[LEAF_SIZE / VF], ld2[LEAF_SIZE / VF];
    vfi lfar[LEAF_SIZE / VF];
    for (int g = 0; g < LEAF_SIZE / VF; g++) {
        vf x, y, z;
        memcpy(&x, L + VF * g, sizeof x);
        memcpy(&y, L + LEAF_SIZE + VF * g, sizeof y);
        memcpy(&z, L + 2 * LEAF_SIZE + VF * g, sizeof z);
        lx[g] = x - o[0]; ly[g] = y - o[1]; lz[g] = z - o[2];
        ld2[g] = lx[g] * lx[g] + ly[g] * ly[g] + lz[g] * lz[g];
        lfar[g] = ld2[g] > cut2;
    }
    for (unsigned open = m; open; open &= open - 1) {
        const int l = __builtin_ctz(open);
        const float s0 = pk->sx[l], s1 = pk->sy[l], s2 = pk->sz[l];
        unsigned mask = 0;
        for (int g = 0; g < LEAF_SIZE / VF; g++) {
            vf tt = lx[g] * s0 + ly[g] * s1 + lz[g] * s2;
            vfi hit = lfar[g] & (tt > 0.0f) & (ld2[g] - tt * tt <= h2);
            mask |= lane_mask(hit) << (VF * g);
        }
        if (!mask) continue;
        active &= ~(1u << l);
        pk->hint[l][0] = node;
        pk->hint[l][1] = lo + __builtin_ctz(mask);
        *pk->word[l] |= pk->bit[l];
        w->last_leaf = node;
    }
    return active;
}

static void walk_packet_wide(const Tree *t, Walker *w, Packet *pk, const float *o, float cut, float h);
static void walk_packet(const Tree *t, Walker *w, Packet *pk, const float *o, float cut, float h) {
    if (t->wide) { walk_packet_wide(t, w, pk, o, cut, h); return; }
    const float h2 = h * h, cut2 = cut * cut;
    unsigned active = pk->n >= 32 ? ~0u : (1u << pk->n) - 1u;
    uint32_t masks[256];
    float m3[3];  /* the rays' summed direction: children in its order */
    vf sx[PACKET / VF], sy[PACKET / VF], sz[PACKET / VF];
    packet_lanes(pk, sx, sy, sz, m3);
    const float mx = m3[0], my = m3[1], mz = m3[2];
    int sp = 0;
    w->visits++;
    unsigned m0 = packet_pass(t->nodes, o, sx, sy, sz, cut, h, active);
    if (m0) { w->stack[sp] = 0; masks[sp] = m0; sp++; }
    while (sp > 0 && active) {
        sp--;
        int32_t node = w->stack[sp];
        unsigned m = masks[sp] & active;
        if (!m) continue;
        const Node *nd = t->nodes + node;
        int32_t k = nd->kid;
        if (k < 0) {
            active = packet_leaf(t, w, pk, node, -1 - k, nd->lo, m, active, o, cut2, h2);
            continue;
        }
        /* both children tested here (their pair shares a cache line), only those with an open ray pushed (fewer
         * mispredicted branches); what lies below both is asked of memory before the tests, as early as it can
         * be (after the tests: 1M points 4-11 % slower; docs/boundedness.md 3.16) */
        const Node *a = t->nodes + k, *b = a + 1;
        prefetch_below(t, a);
        prefetch_below(t, b);
        const unsigned ma = packet_pass(a, o, sx, sy, sz, cut, h, m), mb = packet_pass(b, o, sx, sy, sz, cut, h, m);
        w->visits += 2;
        float ab = (a->c[0] - b->c[0]) * mx + (a->c[1] - b->c[1]) * my + (a->c[2] - b->c[2]) * mz;
        /* the nearer along the rays popped first */
        if (ab <= 0.0f) {
            if (mb) { w->stack[sp] = k + 1; masks[sp] = mb; sp++; }
            if (ma) { w->stack[sp] = k; masks[sp] = ma; sp++; }
        } else {
            if (ma) { w->stack[sp] = k; masks[sp] = ma; sp++; }
            if (mb) { w->stack[sp] = k + 1; masks[sp] = mb; sp++; }
        }
    }
    pk->n = 0;
}

/* The same tree with up to WIDE children a node, for the packets: a wide node holds the spheres of a binary
 * node's descendants three levels down (AVX2: 8 slots; two levels, 4 slots, in the build for any x86-64 CPU:
 * as many as a set of float lanes holds), or of those above that are leaves, side by side, so a packet's walk
 * tests them at one pop, one ray against all of them in one set of lanes, and pops a third as often (a leaf
 * lies about 5 wide levels below the root at 100k points instead of 14).  The spheres are the binary tree's
 * own, tested as packet_pass tests them, so every subtree pruned is one whose sphere no ray of it passes; a
 * ray is still hit only by a leaf's exact ball test and missed only by an exhaustive walk (docs/boundedness.md
 * 3.21: with AVX2 8 slots beat 4 at 1M points and tie at 100k; without it 8 slots cost 5-10 % more CPU).
 * Empty slots have NaN spheres, which no ray passes.  Each build makes its own (wide_tree, WIDE_BYTES). */
#define WIDE VF
typedef struct Wide {
    float cx[WIDE], cy[WIDE], cz[WIDE], r[WIDE];  /* the slots' spheres */
    int32_t ref[WIDE];   /* a wide node, or -1 - n for the binary tree's leaf n */
    int32_t blk[WIDE];   /* a leaf slot's block (-1 - its kid) */
    int32_t lo[WIDE];    /* a leaf slot's first point */
    int32_t pad[WIDE];
} Wide;                  /* 32 x WIDE bytes: four cache lines with AVX2, two without */

/* the binary node's descendants as the slots of wide node `at` (the next free one is *next) */
static void wide_fill(const Node *nodes, Wide *wd, int32_t at, int32_t node, int32_t *next) {
    /* the children, then each slot that is not a leaf replaced by its two children while there is room,
     * level by level (8 slots: the descendants three levels down; 4: two levels) */
    int32_t slot[WIDE], n = 2;
    slot[0] = nodes[node].kid;
    slot[1] = nodes[node].kid + 1;
    for (int grew = 1; grew;) {
        grew = 0;
        int32_t next_slot[WIDE], m = 0;
        for (int i = 0; i < n; i++) {
            const int32_t k = nodes[slot[i]].kid;
            if (k >= 0 && m + (n - i) + 1 <= WIDE) { next_slot[m++] = k; next_slot[m++] = k + 1; grew = 1; }
            else next_slot[m++] = slot[i];
        }
        memcpy(slot, next_slot, sizeof(int32_t) * (size_t)m);
        n = m;
    }
    Wide *w = wd + at;
    for (int i = 0; i < WIDE; i++) {
        w->cx[i] = w->cy[i] = w->cz[i] = w->r[i] = NAN;
        w->ref[i] = w->blk[i] = w->lo[i] = w->pad[i] = 0;
    }
    for (int i = 0; i < n; i++) {
        const Node *c = nodes + slot[i];
        w->cx[i] = c->c[0]; w->cy[i] = c->c[1]; w->cz[i] = c->c[2]; w->r[i] = c->r;
        if (c->kid < 0) {
            w->ref[i] = -1 - slot[i];
            w->blk[i] = -1 - c->kid;
            w->lo[i] = c->lo;
        } else {
            w->ref[i] = (*next)++;
        }
    }
    for (int i = 0; i < n; i++)
        if (w->ref[i] >= 0) wide_fill(nodes, wd, w->ref[i], slot[i], next);
}

/* wide_tree(nodes, out) -> count: the wide tree of a binary tree of at least 3 nodes (wide node 0 below the
 * root) into `out` (bytes for n_nodes / 2 + 1 wide nodes; a wide node per binary node with a child that is not
 * a leaf), 0 for a smaller tree.  Built once per tree (BallTree.wide): at 1M points about 4 ms, which every
 * kernel call would pay again. */
static PyObject *py_wide_tree(PyObject *self, PyObject *args) {
    Py_buffer nds, out;
    if (!PyArg_ParseTuple(args, "y*w*", &nds, &out)) return NULL;
    const int32_t n_nodes = (int32_t)(nds.len / (Py_ssize_t)sizeof(Node));
    int32_t next = 0;
    if (out.len < (Py_ssize_t)sizeof(Wide) * (n_nodes / 2 + 1)) {
        PyErr_SetString(PyExc_ValueError, "wide_tree: out needs n_nodes / 2 + 1 wide nodes");
    } else if (n_nodes >= 3) {
        Py_BEGIN_ALLOW_THREADS
        next = 1;
        wide_fill((const Node *)nds.buf, (Wide *)out.buf, 0, 0, &next);
        Py_END_ALLOW_THREADS
    }
    PyBuffer_Release(&nds);
    PyBuffer_Release(&out);
    if (PyErr_Occurred()) return NULL;
    return PyLong_FromLong(next);
}

/* Is `wd` (n_wide nodes) a wide tree the walk can follow over these nodes?  Every wide child numbered after
 * its parent (no cycle), every leaf slot a leaf of this tree with its own block and first point; a tree
 * smaller than 3 nodes has none.  Only what keeps the walk in bounds: the spheres are BallTree's. */
static int wide_ok(const Wide *wd, int64_t n_wide, const Tree *t) {
    if (t->n_nodes < 3 || n_wide < 1) return 0;
    for (int64_t a = 0; a < n_wide; a++)
        for (int i = 0; i < WIDE; i++) {
            const int32_t r = wd[a].ref[i];
            if (!(wd[a].r[i] == wd[a].r[i])) continue;  /* an empty slot */
            if (r >= 0) {
                if (r <= a || r >= n_wide) return 0;
            } else {
                const int64_t node = -1 - (int64_t)r;
                if (node >= t->n_nodes || t->nodes[node].kid >= 0 || wd[a].blk[i] != -1 - t->nodes[node].kid ||
                    wd[a].lo[i] != t->nodes[node].lo)
                    return 0;
            }
        }
    return 1;
}

typedef float vw __attribute__((vector_size(4 * WIDE)));     /* a wide node's slots, one a lane */
typedef int32_t vwi __attribute__((vector_size(4 * WIDE)));

/* The rays of `m` that each slot of the wide node can hold a hit for: packet_pass's test per slot and ray, in
 * its operations and order.  Where few rays are open (about half the pops hold one) ray by ray, the WIDE slots
 * in one set of lanes; else slot by slot, the rays VF lanes at a time (the switch at 4, 8, 16 or 32 open rays:
 * the same CPU within the noise, docs/boundedness.md 3.21). */
#define WIDE_RAYWISE 8
static inline void wide_pass(const Wide *wn, const float *o, const float *px, const float *py, const float *pz,
                             const vf *sx, const vf *sy, const vf *sz, float cut, float h, unsigned m, unsigned *out) {
    vw cx, cy, cz, rad;
    memcpy(&cx, wn->cx, sizeof cx); memcpy(&cy, wn->cy, sizeof cy);
    memcpy(&cz, wn->cz, sizeof cz); memcpy(&rad, wn->r, sizeof rad);
    const vw wx = cx - o[0], wy = cy - o[1], wz = cz - o[2];
    const vw d2 = wx * wx + wy * wy + wz * wz;
    const vw lim = cut - rad;
    const vwi inside = (lim > 0.0f) & (d2 <= lim * lim);
    const vw reach = rad + h;
    const vw reach2 = reach * reach;
    /* a slot some ray may pass: not wholly within the cut, not empty (NaN never compares) */
    const vwi live = ~inside & (rad == rad);
    if (__builtin_popcount(m) <= WIDE_RAYWISE) {
        vwi acc = {0};
        for (unsigned open = m; open; open &= open - 1) {
            const int l = __builtin_ctz(open);
            const vw tt = wx * px[l] + wy * py[l] + wz * pz[l];
            const vw sq = (vw)((vwi)(tt * tt) & (tt > 0.0f));
            acc |= (d2 - sq <= reach2) & (int32_t)(1u << l);
        }
        acc &= live;
        for (int i = 0; i < WIDE; i++) out[i] = (unsigned)acc[i];
        return;
    }
    for (int i = 0; i < WIDE; i++) {
        out[i] = 0;
        if (!live[i]) continue;
        const float d2i = d2[i], r2i = reach2[i], xi = wx[i], yi = wy[i], zi = wz[i];
        unsigned pass = 0;
        for (int g = 0; g < PACKET / VF; g++) {
            vf tt = xi * sx[g] + yi * sy[g] + zi * sz[g];
            vf sq = (vf)((vfi)(tt * tt) & (tt > 0.0f));
            pass |= lane_mask(d2i - sq <= r2i) << (VF * g);
        }
        out[i] = m & pass;
    }
}

/* walk_packet on the wide tree: the root tested as there, then each popped wide node's slots tested together,
 * those with an open ray pushed, the nearest along the rays' summed direction popped first; a leaf slot
 * tested ray by ray as walk_packet tests its leaves */
static void walk_packet_wide(const Tree *t, Walker *w, Packet *pk, const float *o, float cut, float h) {
    const float h2 = h * h, cut2 = cut * cut;
    unsigned active = pk->n >= 32 ? ~0u : (1u << pk->n) - 1u;
    int32_t stack[256], blks[256], los[256];  /* a wide node, or a leaf slot's binary node, block, first point */
    uint32_t masks[256];
    float m3[3];  /* the rays' summed direction: children in its order */
    vf sx[PACKET / VF], sy[PACKET / VF], sz[PACKET / VF];
    packet_lanes(pk, sx, sy, sz, m3);
    const float mx = m3[0], my = m3[1], mz = m3[2];
    const Wide *wd = t->wide;
    int sp = 0;
    w->visits++;
    unsigned m0 = packet_pass(t->nodes, o, sx, sy, sz, cut, h, active);
    if (m0) { stack[sp] = 0; masks[sp] = m0; sp++; }
    while (sp > 0 && active) {
        sp--;
        const int32_t ref = stack[sp];
        const unsigned m = masks[sp] & active;
        if (!m) continue;
        if (ref < 0) {  /* a leaf slot: its binary node, block and first point */
            active = packet_leaf(t, w, pk, -1 - ref, blks[sp], los[sp], m, active, o, cut2, h2);
            continue;
        }
        const Wide *wn = wd + ref;
        unsigned ms[WIDE];
        wide_pass(wn, o, pk->sx, pk->sy, pk->sz, sx, sy, sz, cut, h, m, ms);
        w->visits += WIDE;
        /* the passing slots by their centres' distance along the summed direction, the nearest pushed last:
         * each slot's place is the number of passing slots before it in that order, counted in lanes (an
         * insertion sort's branches mispredicted: a fifth of the walk's samples) */
        vw cx, cy, cz;
        memcpy(&cx, wn->cx, sizeof cx); memcpy(&cy, wn->cy, sizeof cy); memcpy(&cz, wn->cz, sizeof cz);
        const vw key = cx * mx + cy * my + cz * mz;
        unsigned live = 0;
        for (int i = 0; i < WIDE; i++) live |= (unsigned)(ms[i] != 0) << i;
        static const vwi lane = {0, 1, 2, 3
#if WIDE == 8
                                 , 4, 5, 6, 7
#endif
        };
        const int n = __builtin_popcount(live);
        for (unsigned todo = live; todo; todo &= todo - 1) {
            const int i = __builtin_ctz(todo);
            const vwi before = (key > key[i]) | ((key == key[i]) & (lane < i));
            const int at = sp + __builtin_popcount(lane_mask((vfi)before) & live);
            const int32_t r = wn->ref[i];
            if (r >= 0) {
                for (size_t b = 0; b < sizeof(Wide); b += 64) __builtin_prefetch((const char *)(wd + r) + b);
            } else {
                const float *L = t->leaf + 3 * LEAF_SIZE * (size_t)wn->blk[i];
                __builtin_prefetch(L);
                __builtin_prefetch(L + 3 * LEAF_SIZE - 1);
                blks[at] = wn->blk[i];
                los[at] = wn->lo[i];
            }
            stack[at] = r; masks[at] = ms[i];
        }
        sp += n;
    }
    pk->n = 0;
}

/* The hints of a tile's needed samples asked of memory before its rays are cast: each sample's hint point
 * and its leaf's node (at 100k points the tree and its points, about 3 MB, outgrow a core's L2, and a ray's
 * first tests wait on them one after the other); only for points beyond PREFETCH_FROM bytes (the hammer's
 * 48 KB stay in the caches, and the extra pass over the tile costs 5 %).  No value depends on it
 * (docs/boundedness.md 3.17). */
#define PREFETCH_FROM (512 * 1024)
static inline void prefetch_hints(const Tree *t, const Raster *r, const uint64_t *need, const int32_t *hints,
                                  int j0, int j1, int b0, int x, int bins) {
    for (int j = j0; j < j1; j++) {
        uint64_t todo = (need[(size_t)j * r->words + x] >> (b0 & 63)) & TILE_MASK;
        while (todo) {
            const int b = b0 + __builtin_ctzll(todo);
            todo &= todo - 1;
            const int32_t *hint = hints + 2 * ((size_t)j * bins + b);
            if (hint[1] >= 0) __builtin_prefetch(t->pts + 3 * (size_t)hint[1]);
            if (hint[0] >= 0) __builtin_prefetch(t->nodes + hint[0]);
        }
    }
}

/* The far rays of the needed samples of rows [j0, j1) x bins [b0, b1) (whole tiles) from cf, tile by tile:
 * each tries its hints (ray_hits) when use_hints, the rest go to packets (the last one left for the caller
 * to walk); hits set in `far`.  A tile's rays first test their own hint points together, VF lanes at a
 * time (point_hit's operations in its order, so the same bits; a ray with no hint point gets NaN lanes,
 * which never hit): the hit or miss of each, about even, is then a bit of a mask instead of a branch that
 * mispredicts half the time.  Then the rays in the order they had, each hit as before or on to its other
 * hints (ray_hits), so every ray meets the same tests with the same hints as one by one
 * (docs/boundedness.md 3.20).  Returns the rays whose hints were tried. */
#define TILE_RAYS (TILE_ROWS * TILE_BINS)
static int64_t cast_band(const Tree *t, Walker *w, Packet *pk, const Raster *r, const uint64_t *need, uint64_t *far,
                         int32_t *hints, const Move *mv, const float *cf, float cut, float h, int use_hints, int big,
                         int j0, int j1, int b0, int b1, int64_t *rays) {
    int64_t tried = 0;
    const int bins = r->bins;
    const float cut2 = cut * cut, h2 = h * h;
    float sx[TILE_RAYS], sy[TILE_RAYS], sz[TILE_RAYS], px[TILE_RAYS], py[TILE_RAYS], pz[TILE_RAYS];
    float ls[TILE_RAYS];  /* the rays' rows' lon_scale (moved_cells) */
    int32_t cell[TILE_RAYS], rj[TILE_RAYS], rb[TILE_RAYS], moved[TILE_RAYS];
    uint8_t row[TILE_RAYS];
    const int moving = use_hints && mv->on;
    for (int b = b0; b < b1; b += TILE_BINS) {
        const int x = b >> 6;
        if (use_hints && big) prefetch_hints(t, r, need, hints, j0, j1, b, x, bins);
        int nr = 0;
        uint32_t with_point = 0;  /* the rays with a hint point */
        for (int j = j0; j < j1; j++) {
            uint64_t todo = (need[(size_t)j * r->words + x] >> (b & 63)) & TILE_MASK;
            while (todo) {
                const int bb = b + __builtin_ctzll(todo);
                todo &= todo - 1;
                sx[nr] = (float)(r->s[j] * r->cos_lon[bb]);
                sy[nr] = (float)(r->s[j] * r->sin_lon[bb]);
                sz[nr] = (float)r->z[j];
                cell[nr] = j * bins + bb;
                row[nr] = (uint8_t)(j - j0);
                rj[nr] = j;
                rb[nr] = bb;
                ls[nr] = mv->lon_scale[j];
                const int32_t pt = hints[2 * (size_t)cell[nr] + 1];
                if (use_hints && pt >= 0) {
                    const float *p = t->pts + 3 * (size_t)pt;
                    px[nr] = p[0]; py[nr] = p[1]; pz[nr] = p[2];
                    with_point |= 1u << nr;
                } else {
                    px[nr] = py[nr] = pz[nr] = NAN;
                }
                nr++;
            }
        }
        if (!nr) continue;
        *rays += nr;
        for (int l = nr; l < TILE_RAYS && (l & (VF - 1)); l++) {
            px[l] = py[l] = pz[l] = sx[l] = sy[l] = sz[l] = ls[l] = NAN;
            rj[l] = rb[l] = 0;
        }
        uint32_t own = 0;  /* the rays whose own hint point they hit */
        const uint32_t all = nr == TILE_RAYS ? ~0u : (1u << nr) - 1u;
        if (use_hints) {
            for (int g = 0; g < nr; g += VF) {
                vf X, Y, Z, S0, S1, S2;
                memcpy(&X, px + g, sizeof X); memcpy(&Y, py + g, sizeof Y); memcpy(&Z, pz + g, sizeof Z);
                memcpy(&S0, sx + g, sizeof S0); memcpy(&S1, sy + g, sizeof S1); memcpy(&S2, sz + g, sizeof S2);
                vf wx = X - cf[0], wy = Y - cf[1], wz = Z - cf[2];
                vf d2 = wx * wx + wy * wy + wz * wz;
                vf tt = wx * S0 + wy * S1 + wz * S2;
                vfi hit = (d2 > cut2) & (tt > 0.0f) & (d2 - tt * tt <= h2);
                own |= (uint32_t)lane_mask(hit) << g;
                /* the offsets w = p - o kept for moved_cells (over px, py, pz) */
                memcpy(px + g, &wx, sizeof wx); memcpy(py + g, &wy, sizeof wy); memcpy(pz + g, &wz, sizeof wz);
            }
            if (moving) moved_cells(mv, px, py, pz, sx, sy, sz, ls, rj, rb, nr, moved);
            own &= all;
            tried += nr;
            w->hint_tries += __builtin_popcount(with_point);
            w->hint_hits += __builtin_popcount(own);
            for (uint32_t m = own; m; m &= m - 1) {
                const int l = __builtin_ctz(m), j = j0 + row[l];
                far[(size_t)j * r->words + x] |= UINT64_C(1) << ((cell[l] - j * bins) & 63);
            }
        }
        if (use_hints && big)  /* the misses' hinted leaf blocks (their nodes were asked of memory with the points) */
            for (uint32_t m = all & ~own; m; m &= m - 1) {
                const int32_t leaf = hints[2 * (size_t)cell[__builtin_ctz(m)]];
                const int32_t kid = leaf >= 0 ? t->nodes[leaf].kid : 0;
                if (kid < 0) {
                    const float *L = t->leaf + 3 * LEAF_SIZE * (size_t)(-1 - kid);
                    __builtin_prefetch(L);
                    __builtin_prefetch(L + 3 * LEAF_SIZE - 1);
                }
            }
        /* the others in order; the previous ray's leaf (a hint) as one by one: the leaf of the last own hit
         * since the ray before, if any */
        uint64_t seen = 0;  /* rays [0, seen) done */
        for (uint32_t m = all & ~own; ; m &= m - 1) {
            const int l = m ? __builtin_ctz(m) : nr;
            const uint32_t since = own & (uint32_t)(((UINT64_C(1) << l) - 1) & ~((UINT64_C(1) << seen) - 1));
            if (since) w->last_leaf = hints[2 * (size_t)cell[31 - __builtin_clz(since)]];
            if (!m) break;
            seen = (uint64_t)l + 1;
            const int j = j0 + row[l], bb = cell[l] - j * bins;
            int32_t *hint = hints + 2 * (size_t)cell[l];
            uint64_t *word = far + (size_t)j * r->words + x, bit = UINT64_C(1) << (bb & 63);
            int hit = -1;
            if (use_hints) {
                const float s[3] = {sx[l], sy[l], sz[l]};
                hit = ray_hits(t, w, cf, s, cut, h, hint, hints, moving ? moved[l] : -1, big);
            }
            if (hit > 0) *word |= bit;
            if (hit < 0) {
                pk->sx[pk->n] = sx[l]; pk->sy[pk->n] = sy[l]; pk->sz[pk->n] = sz[l];
                pk->hint[pk->n] = hint; pk->word[pk->n] = word; pk->bit[pk->n] = bit;
                if (++pk->n == PACKET) walk_packet(t, w, pk, cf, cut, h);
            }
        }
    }
    return tried;
}

/* A seed table's cells (leaf, point; `len` int32 in all) copied as hints: a node of this tree and one of its
 * points, else none (a seed is only an index into arrays the kernel reads, docs/boundedness.md 3.18).  Only the
 * ranges, with no branch (the compiler's lanes): a node that is no leaf holds no hit (leaf_hit), so a stale
 * seed only misorders the search.  Checking each cell's node for a leaf (a bit per node) took 6 % of the
 * kernel on an edit's update at 100k points, and making the bits a pass over all the nodes every call
 * (docs/boundedness.md 3.22). */
static inline void seed_cells(int32_t n_nodes, int32_t n, const int32_t *restrict from, int32_t *restrict to,
                              size_t len) {
    for (size_t x = 0; x < len; x += 2) {
        const int32_t leaf = from[x], pt = from[x + 1];
        const int32_t ok = -(int32_t)(((uint32_t)leaf < (uint32_t)n_nodes) & ((uint32_t)pt < (uint32_t)n));
        to[x] = (leaf & ok) | ~ok;
        to[x + 1] = (pt & ok) | ~ok;
    }
}

/* A lone query of a block (BLOCK): its origin, cut, move, the table its band's hints come from and its hint counts */
typedef struct {
    Move mv;
    const int32_t *src;      /* NULL: no hints */
    float cf[3], cut;
    int use, seeded;
    int64_t tried, hits;
} Lone;

/* Points with |p - c| <= reach, nearest shell first (shell_order), into out; returns their number */
typedef struct { double d2; int32_t i; } Near;

/* Near points in shells of equal width in d2 (SHELLS of them over the reach), nearest shell first, each in
 * the tree's order: a counting sort in two passes through `tmp`.  Only the order in which the caps are drawn
 * (the biggest first, so that rows fill early) depends on it, not the union of the caps: the same beta. */
#define SHELLS 128
static void shell_order(Near *v, Near *tmp, int32_t n, double r2) {
    int32_t first[SHELLS + 1];
    memset(first, 0, sizeof first);
    const double scale = r2 > 0.0 ? SHELLS / r2 : 0.0;
    for (int32_t i = 0; i < n; i++) {
        int b = (int)(v[i].d2 * scale);
        first[(b < SHELLS - 1 ? b : SHELLS - 1) + 1]++;
    }
    for (int b = 0; b < SHELLS; b++) first[b + 1] += first[b];
    for (int32_t i = 0; i < n; i++) {
        int b = (int)(v[i].d2 * scale);
        tmp[first[b < SHELLS - 1 ? b : SHELLS - 1]++] = v[i];
    }
    memcpy(v, tmp, sizeof(Near) * (size_t)n);
}

static int32_t collect_near(const Tree *t, int32_t *stack, const double *c, double reach, Near *out) {
    int32_t m = 0;
    int sp = 0;
    double r2 = reach * reach;
    stack[sp++] = 0;
    while (sp > 0) {
        const Node *nd = t->nodes + stack[--sp];
        double wx = nd->c[0] - c[0], wy = nd->c[1] - c[1], wz = nd->c[2] - c[2];
        double d = sqrt(wx * wx + wy * wy + wz * wz);
        if (d - nd->r > reach) continue;
        if (nd->kid >= 0) {
            stack[sp++] = nd->kid;
            stack[sp++] = nd->kid + 1;
            continue;
        }
        for (int32_t i = nd->lo; i < nd->hi; i++) {
            const float *p = t->pts + 3 * (size_t)i;
            double dx = p[0] - c[0], dy = p[1] - c[1], dz = p[2] - c[2];
            double d2 = dx * dx + dy * dy + dz * dz;
            if (d2 <= r2) { out[m].d2 = d2; out[m].i = i; m++; }
        }
    }
    shell_order(out, out + m, m, r2);
    return m;
}

/* One query's near caps (points nearest shell first, |p - q| > h) into a cleared bitmap; returns caps drawn */
#define MEMBER_CHUNK 1024
static int64_t near_raster(const Raster *r, const Tree *t, const Near *near, int32_t m, const double *qi,
                           double h, double h2, uint64_t *bits, uint8_t *full) {
    memset(bits, 0, (size_t)r->rows * r->words * sizeof(uint64_t));
    memset(full, 0, (size_t)r->rows);
    int nf = 0;
    int64_t caps = 0;
    for (int32_t a = 0; a < m && nf < r->rows; a++) {
        const float *p = t->pts + 3 * (size_t)near[a].i;
        double dx = p[0] - qi[0], dy = p[1] - qi[1], dz = p[2] - qi[2];
        double d2 = dx * dx + dy * dy + dz * dz;
        if (d2 <= h2) continue;
        caps++;
        nf += add_cap(r, bits, full, dx, dy, dz, d2, h);
    }
    return caps;
}

/* clusters(points (n,3) f32 tree order, nodes (m) Node, leaves ((m + 1) / 2, 3, 8) f32 (Tree.leaf),
 *          queries (q,3) f64 grouped by cluster,
 *          starts (k1 - k0 + 1) i64 into queries, centres (k,3) f64, reach (k) f64 (all clusters),
 *          cluster range [k0, k1), h, rows, bins, beta out (q) f64,
 *          stats out (6) i64: node visits, near caps, far rays, near points, hint tries, hint hits,
 *          stop (1) i32, done out (1) i64[, hint_min, hint_rest: HINT_MIN, HINT_REST[, prefetch_from:
 *          PREFETCH_FROM bytes[, seeds, seed origins, seed_of, kept, keep_of (3.18)[, block: lone queries
 *          cast together, BLOCK where the points exceed BLOCK_FROM bytes (< 0), 0 or 1 one by one]]]])
 * beta of the queries of clusters k0..k1-1 (queries holds just theirs, grouped by cluster), one cluster
 * after the other (lone queries a block at a time, band by band), so that each far ray can start from the
 * leaf its sample hit from the previous cluster.  `done` counts the clusters finished (read by another
 * thread for progress); once another thread sets `stop`, the call returns after the cluster (or the band
 * of a block) it is in.  Returns the number of clusters finished. */
static PyObject *py_clusters(PyObject *self, PyObject *args) {
    Py_buffer pts, nds, lvs, qs, starts, cen, rch, beta, stats, stop_buf, done_buf;
    /* optional: seed tables, their origins, each cluster's seed row (or -1); the tables kept after each
     * cluster and each cluster's row there (or -1): seeded hints (docs/boundedness.md 3.18) */
    Py_buffer sd = {0}, sd_at = {0}, sd_of = {0}, kp = {0}, kp_of = {0};
    Py_buffer wdb = {0};  /* optional, last: the wide tree (BallTree.wide) the packets walk; empty: the binary one */
    int k0, k1, rows, bins;
    double h;
    int hint_min = HINT_MIN, hint_rest = HINT_REST, prefetch_from = PREFETCH_FROM, block = -1;
    if (!PyArg_ParseTuple(args, "y*y*y*y*y*y*y*iidiiw*w*w*w*|iiiy*y*y*w*y*iy*", &pts, &nds, &lvs, &qs, &starts, &cen,
                          &rch, &k0, &k1, &h, &rows, &bins, &beta, &stats, &stop_buf, &done_buf, &hint_min, &hint_rest,
                          &prefetch_from, &sd, &sd_at, &sd_of, &kp, &kp_of, &block, &wdb))
        return NULL;
    if (block < 0) block = (int64_t)(pts.len) > (int64_t)BLOCK_FROM ? BLOCK : 0;
    if (hint_min < 0) hint_min = HINT_MIN;  /* < 0: the default (the seeds come after these three) */
    if (hint_rest < 0) hint_rest = HINT_REST;
    if (prefetch_from < 0) prefetch_from = PREFETCH_FROM;
    volatile const int32_t *stop = (volatile const int32_t *)stop_buf.buf;
    volatile int64_t *done_count = (volatile int64_t *)done_buf.buf;
    int64_t finished = 0;
    PyObject *result = NULL;
    Raster r = {0};
    int32_t n = (int32_t)(pts.len / (3 * sizeof(float)));
    Tree t = {(const float *)pts.buf, (const Node *)nds.buf, (int32_t)(nds.len / (Py_ssize_t)sizeof(Node)),
              (const float *)lvs.buf};
    const int64_t *st = (const int64_t *)starts.buf;
    const double *q = (const double *)qs.buf, *cc = (const double *)cen.buf, *rr = (const double *)rch.buf;
    double *out = (double *)beta.buf;
    int64_t *stat = (int64_t *)stats.buf;
    uint64_t *far = NULL, *need = NULL, *bits = NULL;
    uint8_t *full = NULL, *lone_full = NULL;
    int32_t *stack = NULL, *hints = NULL, *tabs = NULL;
    uint64_t *lone_far = NULL;
    Lone *lones = NULL;
    float *lon_scale = NULL;
    Near *near = NULL;
    if (stop_buf.len < (Py_ssize_t)sizeof(int32_t) || done_buf.len < (Py_ssize_t)sizeof(int64_t)) {
        PyErr_SetString(PyExc_ValueError, "clusters: stop needs one int32, done one int64");
        goto done;
    }
    if (lvs.len < (Py_ssize_t)sizeof(float) * 3 * LEAF_SIZE * ((t.n_nodes + 1) / 2)) {  /* a full binary tree */
        PyErr_SetString(PyExc_ValueError, "clusters: the leaves' block is too small for the nodes");
        goto done;
    }
    if (rows < 1 || bins < 1 || raster_init(&r, rows, bins) != 0) {
        PyErr_SetString(PyExc_ValueError, "clusters: bad raster");
        goto done;
    }
    if (wdb.len > 0) {
        if (((uintptr_t)wdb.buf & 63) || !wide_ok((const Wide *)wdb.buf, (int64_t)(wdb.len / (Py_ssize_t)sizeof(Wide)), &t)) {
            PyErr_SetString(PyExc_ValueError, "clusters: the wide tree is not one of these nodes (or not on a 64-byte line)");
            goto done;
        }
        t.wide = (const Wide *)wdb.buf;
    }
    const size_t table = 2 * (size_t)rows * bins;  /* one hint table: leaf, point per sample */
    const int32_t *seeds = (const int32_t *)sd.buf, *seed_of = sd_of.len > 0 ? (const int32_t *)sd_of.buf : NULL;
    const double *seed_at = (const double *)sd_at.buf;
    int32_t *kept = (int32_t *)kp.buf;
    const int32_t *keep_of = kp_of.len > 0 ? (const int32_t *)kp_of.buf : NULL;
    const int64_t n_seeds = (int64_t)(sd.len / (Py_ssize_t)(sizeof(int32_t) * table));
    const int64_t n_kept = (int64_t)(kp.len / (Py_ssize_t)(sizeof(int32_t) * table));
    if ((seed_of && (sd_of.len < (Py_ssize_t)sizeof(int32_t) * (k1 - k0) ||
                     sd_at.len < (Py_ssize_t)sizeof(double) * 3 * n_seeds)) ||
        (keep_of && kp_of.len < (Py_ssize_t)sizeof(int32_t) * (k1 - k0))) {
        PyErr_SetString(PyExc_ValueError, "clusters: seed_of and keep_of need one row per cluster, seed_at 3 per seed");
        goto done;
    }
    for (int k = 0; seed_of && k < k1 - k0; k++)
        if (seed_of[k] >= n_seeds) { PyErr_SetString(PyExc_ValueError, "clusters: seed row out of range"); goto done; }
    for (int k = 0; keep_of && k < k1 - k0; k++)
        if (keep_of[k] >= n_kept) { PyErr_SetString(PyExc_ValueError, "clusters: kept row out of range"); goto done; }
    size_t nw = (size_t)rows * r.words;
    /* member rasters for the largest cluster of the stream, at most MEMBER_CHUNK (fresh pages cost) */
    int64_t slots = 1;
    for (int k = k0; k < k1; k++) {
        int64_t n_mem = st[k - k0 + 1] - st[k - k0];
        if (n_mem > slots) slots = n_mem < MEMBER_CHUNK ? n_mem : MEMBER_CHUNK;
    }
    far = (uint64_t *)calloc((2 + (size_t)slots) * nw, sizeof(uint64_t));
    full = (uint8_t *)calloc((size_t)rows * slots, 1);
    hints = (int32_t *)malloc(sizeof(int32_t) * 2 * (size_t)rows * bins);  /* leaf, point per sample */
    stack = (int32_t *)malloc(sizeof(int32_t) * 256);
    near = (Near *)malloc(2 * sizeof(Near) * (size_t)(n > 0 ? n : 1));  /* and shell_order's scratch */
    lon_scale = (float *)malloc(sizeof(float) * (size_t)rows);
    if (!far || !full || !stack || !near || !hints || !lon_scale) { PyErr_NoMemory(); goto done; }
    /* lone queries only: cast BLOCK at a time, band by band, each with its own hint table (BLOCK) */
    int lone = block > 1 && k1 - k0 > 1;
    for (int k = k0; lone && k < k1; k++) lone = st[k - k0 + 1] - st[k - k0] == 1;
    if (lone) {
        tabs = (int32_t *)malloc(sizeof(int32_t) * (1 + (size_t)block) * table);
        lone_far = (uint64_t *)calloc(3 * (size_t)block * nw, sizeof(uint64_t));
        lone_full = (uint8_t *)calloc((size_t)block * rows, 1);
        lones = (Lone *)calloc((size_t)block, sizeof(Lone));
        if (!tabs || !lone_far || !lone_full || !lones) { PyErr_NoMemory(); goto done; }
    }
    for (int i = 0; i < 2 * rows * bins; i++) hints[i] = -1;
    for (int j = 0; j < rows; j++) lon_scale[j] = (float)(bins / TWO_PI / (r.s[j] * r.s[j]));
    need = far + nw;
    bits = need + nw;
    Py_BEGIN_ALLOW_THREADS
    Walker w = {stack, -1, -1, 0, 0, 0};
    Packet pk;
    pk.n = 0;
    for (int l = 0; l < PACKET; l++) pk.sx[l] = pk.sy[l] = pk.sz[l] = NAN;  /* never uninitialised lanes */
    int64_t caps = 0, rays = 0, nears = 0;
    const double h2 = h * h;
    const int big = (int64_t)n * 3 * (int64_t)sizeof(float) > (int64_t)prefetch_from;  /* prefetch_hints */
    const double total = (double)rows * bins;
    double prev[3] = {0.0, 0.0, 0.0};
    int64_t recent_tried = 0, recent_hits = 0;  /* the hints' recent rays and hits (HINT_MIN) */
    int rest = 0;  /* clusters left whose far rays skip their hints (HINT_MIN) */
    const int bands_across = (bins + BAND_BINS - 1) / BAND_BINS;
    if (lone) for (size_t i = 0; i < table; i++) tabs[i] = -1;  /* the table before the block: none yet */
    for (int kb = k0; lone && kb < k1 && !*stop; kb += block) {
        const int kn = k1 - kb < block ? k1 - kb : block;
        /* each query's near caps, needed samples, hint table (a seed's, none, or its band's cells copied from
         * the query before it as the bands go: src) and move */
        for (int i = 0; i < kn; i++) {
            const int k = kb + i;
            Lone *L = lones + i;
            int32_t *tab = tabs + (size_t)(i + 1) * table;
            const double *c = cc + 3 * (size_t)k;
            L->use = rest == 0;
            if (rest > 0) rest--;
            L->tried = L->hits = 0;
            for (int a = 0; a < 3; a++) L->cf[a] = (float)c[a];
            const double reach = rr[k];
            L->cut = (float)(reach > h ? reach : h);
            const int32_t seed = seed_of ? seed_of[k - k0] : -1;
            if (seed >= 0) memcpy(prev, seed_at + 3 * (size_t)seed, sizeof prev);
            double jx = c[0] - prev[0], jy = c[1] - prev[1], jz = c[2] - prev[2];
            const int reset = (k == k0 && seed < 0) || jx * jx + jy * jy + jz * jz > 4.0 * reach * reach;
            L->src = reset ? NULL : seed >= 0 ? seeds + (size_t)seed * table : tabs + (size_t)i * table;
            L->seeded = !reset && seed >= 0;
            Move mv = {{(float)jx, (float)jy, (float)jz}, !reset && (jx != 0.0 || jy != 0.0 || jz != 0.0), rows, bins,
                       tab, lon_scale, 0, bands_across};
            L->mv = mv;
            memcpy(prev, c, sizeof prev);
            int32_t m = n > 0 ? collect_near(&t, stack, c, reach, near) : 0;
            nears += m;
            uint64_t *mb = lone_far + (size_t)(3 * i) * nw, *nd = mb + nw, *fa = nd + nw;
            uint8_t *mf = lone_full + (size_t)i * rows;
            caps += near_raster(&r, &t, near, m, q + 3 * (size_t)(st[k - k0]), h, h2, mb, mf);
            memset(nd, 0, nw * sizeof(uint64_t));
            memset(fa, 0, nw * sizeof(uint64_t));
            for (int j = 0; j < rows; j++) {
                if (mf[j]) continue;
                for (int x = 0; x < r.words; x++) {
                    uint64_t valid = (x == r.words - 1) ? r.last_mask : ~UINT64_C(0);
                    nd[(size_t)j * r.words + x] = ~mb[(size_t)j * r.words + x] & valid;
                }
            }
        }
        /* the far rays, band by band, each band from every query in turn */
        int band = 0;
        for (int j0 = 0; n > 0 && j0 < rows && !*stop; j0 += TILE_ROWS) {
            const int j1 = j0 + TILE_ROWS < rows ? j0 + TILE_ROWS : rows;
            for (int b0 = 0; b0 < bins; b0 += BAND_BINS, band++) {
                const int b1 = b0 + BAND_BINS < bins ? b0 + BAND_BINS : bins;
                for (int i = 0; i < kn; i++) {
                    Lone *L = lones + i;
                    int32_t *tab = tabs + (size_t)(i + 1) * table;
                    for (int j = j0; j < j1; j++) {  /* the band's hints: none, a seed's (checked) or the query before's */
                        int32_t *to = tab + 2 * ((size_t)j * bins + b0);
                        const size_t cells = 2 * (size_t)(b1 - b0);
                        if (!L->src) {
                            for (size_t x = 0; x < cells; x++) to[x] = -1;
                        } else if (L->seeded) {
                            seed_cells(t.n_nodes, n, L->src + 2 * ((size_t)j * bins + b0), to, cells);
                        } else {
                            memcpy(to, L->src + 2 * ((size_t)j * bins + b0), sizeof(int32_t) * cells);
                        }
                    }
                    L->mv.band = band;
                    const int64_t hits_before = w.hint_hits;
                    uint64_t *nd = lone_far + (size_t)(3 * i + 1) * nw;
                    L->tried += cast_band(&t, &w, &pk, &r, nd, nd + nw, tab, &L->mv, L->cf, L->cut, (float)h, L->use,
                                          big, j0, j1, b0, b1, &rays);
                    if (pk.n) walk_packet(&t, &w, &pk, L->cf, L->cut, (float)h);
                    L->hits += w.hint_hits - hits_before;
                }
            }
        }
        if (*stop) break;  /* a cancel: the block's queries unfinished, as a cluster's after it */
        for (int i = 0; i < kn; i++) {
            const int k = kb + i;
            Lone *L = lones + i;
            if (L->use && L->tried > 0) {
                recent_tried = recent_tried / 2 + L->tried;
                recent_hits = recent_hits / 2 + L->hits;
                /* the next hint_rest blocks skip them: the rule decides once a block, so per block */
                if (1000 * recent_hits < (int64_t)hint_min * recent_tried) rest = hint_rest * block;
            }
            const uint64_t *mb = lone_far + (size_t)(3 * i) * nw, *fa = mb + 2 * nw;
            int64_t count = 0;
            for (size_t x = 0; x < nw; x++) count += __builtin_popcountll(mb[x] | fa[x]);
            out[st[k - k0]] = (double)count / total;
            if (keep_of && keep_of[k - k0] >= 0)
                memcpy(kept + (size_t)keep_of[k - k0] * table, tabs + (size_t)(i + 1) * table, sizeof(int32_t) * table);
        }
        memcpy(tabs, tabs + (size_t)kn * table, sizeof(int32_t) * table);
        finished += kn;
        *done_count = finished;
    }
    for (int k = lone ? k1 : k0; k < k1 && !*stop; k++) {
        const double *c = cc + 3 * (size_t)k;
        const int use_hints = rest == 0;
        if (rest > 0) rest--;
        int64_t tried = 0;
        const int64_t hits_before = w.hint_hits;
        const float cf[3] = {(float)c[0], (float)c[1], (float)c[2]};
        const double reach = rr[k];
        const double cut = reach > h ? reach : h;
        const int64_t q0 = st[k - k0], q1 = st[k - k0 + 1];
        const int64_t n_mem = q1 - q0;
        /* a seed: the hints a lone query nearby left (its table and origin), instead of the previous cluster's */
        const int32_t seed = seed_of ? seed_of[k - k0] : -1;
        if (seed >= 0) {
            seed_cells(t.n_nodes, n, seeds + (size_t)seed * table, hints, table);
            memcpy(prev, seed_at + 3 * (size_t)seed, sizeof prev);
        }
        /* hints from a cluster far away would only lengthen the walks */
        double jx = c[0] - prev[0], jy = c[1] - prev[1], jz = c[2] - prev[2];
        const int reset = (k == k0 && seed < 0) || jx * jx + jy * jy + jz * jz > 4.0 * reach * reach;
        if (reset)
            for (int i = 0; i < 2 * rows * bins; i++) hints[i] = -1;
        Move mv = {{(float)jx, (float)jy, (float)jz}, !reset && (jx != 0.0 || jy != 0.0 || jz != 0.0), rows, bins,
                   hints, lon_scale, INT32_MAX, 0};
        memcpy(prev, c, sizeof prev);
        int32_t m = n > 0 ? collect_near(&t, stack, c, reach, near) : 0;
        nears += m;
        /* pass 1: every member's near caps; `need` = samples left uncovered by some member */
        memset(need, 0, nw * sizeof(uint64_t));
        for (int64_t i = q0; i < q1; i++) {
            int64_t slot = (i - q0) % slots;
            uint64_t *mb = bits + (size_t)slot * nw;
            uint8_t *mf = full + (size_t)slot * rows;
            caps += near_raster(&r, &t, near, m, q + 3 * (size_t)i, h, h2, mb, mf);
            for (int j = 0; j < rows; j++) {
                if (mf[j]) continue;
                for (int x = 0; x < r.words; x++) {
                    uint64_t valid = (x == r.words - 1) ? r.last_mask : ~UINT64_C(0);
                    need[(size_t)j * r.words + x] |= ~mb[(size_t)j * r.words + x] & valid;
                }
            }
        }
        /* the far field from the centre: one ray per needed sample */
        memset(far, 0, nw * sizeof(uint64_t));
        w.last_leaf = -1;
        if (n > 0) {
            for (int j0 = 0; j0 < rows; j0 += TILE_ROWS)
                tried += cast_band(&t, &w, &pk, &r, need, far, hints, &mv, cf, (float)cut, (float)h, use_hints, big, j0,
                                   j0 + TILE_ROWS < rows ? j0 + TILE_ROWS : rows, 0, bins, &rays);
            if (pk.n) walk_packet(&t, &w, &pk, cf, (float)cut, (float)h);
        }
        /* hints that hit under hint_min per mille of the recent rays tried: the next hint_rest clusters go
         * straight to packets (their hits still refresh the hints) */
        if (use_hints && tried > 0) {
            recent_tried = recent_tried / 2 + tried;
            recent_hits = recent_hits / 2 + (w.hint_hits - hits_before);
            if (1000 * recent_hits < (int64_t)hint_min * recent_tried) rest = hint_rest;
        }
        /* pass 2: member raster | far field (members beyond the first chunk are rasterised again) */
        for (int64_t i = q0; i < q1; i++) {
            int64_t slot = (i - q0) % slots;
            uint64_t *mb = bits + (size_t)slot * nw;
            uint8_t *mf = full + (size_t)slot * rows;
            if (n_mem > slots) caps += near_raster(&r, &t, near, m, q + 3 * (size_t)i, h, h2, mb, mf);
            int64_t count = 0;
            for (size_t x = 0; x < nw; x++) count += __builtin_popcountll(mb[x] | far[x]);
            out[i] = (double)count / total;
        }
        if (keep_of && keep_of[k - k0] >= 0)
            memcpy(kept + (size_t)keep_of[k - k0] * table, hints, sizeof(int32_t) * table);
        *done_count = ++finished;
    }
    stat[0] += w.visits;
    stat[1] += caps;
    stat[2] += rays;
    stat[3] += nears;
    stat[4] += w.hint_tries;
    stat[5] += w.hint_hits;
    Py_END_ALLOW_THREADS
    result = PyLong_FromLongLong((long long)finished);
done:
    raster_free(&r);
    free(far); free(full); free(stack); free(near); free(hints); free(lon_scale);
    free(tabs); free(lone_far); free(lone_full); free(lones);
    PyBuffer_Release(&pts); PyBuffer_Release(&nds); PyBuffer_Release(&lvs); PyBuffer_Release(&qs); PyBuffer_Release(&starts);
    PyBuffer_Release(&cen); PyBuffer_Release(&rch);
    PyBuffer_Release(&beta); PyBuffer_Release(&stats); PyBuffer_Release(&stop_buf); PyBuffer_Release(&done_buf);
    PyBuffer_Release(&sd); PyBuffer_Release(&sd_at); PyBuffer_Release(&sd_of); PyBuffer_Release(&kp); PyBuffer_Release(&kp_of);
    PyBuffer_Release(&wdb);
    return result;
}

/* Distance from each point of [i0, i1) (tree order) to its nearest other point: its own leaf first, then
 * up the tree, each ancestor's other subtree pruned by the best distance so far.  Exact (as a KD-tree
 * kNN query), in double precision from the float32 points. */
static double nn_subtree(const Tree *t, int32_t *stack, int32_t root, int32_t self, const float *p, double best2) {
    int sp = 0;
    stack[sp++] = root;
    double best = sqrt(best2);
    while (sp > 0) {
        const Node *nd = t->nodes + stack[--sp];
        double wx = nd->c[0] - p[0], wy = nd->c[1] - p[1], wz = nd->c[2] - p[2];
        double lim = best + nd->r;  /* |p - c| - r > best, without a square root */
        if (wx * wx + wy * wy + wz * wz > lim * lim) continue;
        if (nd->kid >= 0) {
            stack[sp++] = nd->kid;
            stack[sp++] = nd->kid + 1;
            continue;
        }
        for (int32_t i = nd->lo; i < nd->hi; i++) {
            if (i == self) continue;
            const float *o = t->pts + 3 * (size_t)i;
            double dx = (double)o[0] - p[0], dy = (double)o[1] - p[1], dz = (double)o[2] - p[2];
            double d2 = dx * dx + dy * dy + dz * dz;
            if (d2 < best2) { best2 = d2; best = sqrt(d2); }
        }
    }
    return best2;
}

/* nn_dist(points (n,3) f32 tree order, nodes, leaf_of (n) i32, i0, i1, out (i1 - i0) f64) */
static PyObject *py_nn_dist(PyObject *self, PyObject *args) {
    Py_buffer pts, nds, leaf_of, out;
    Py_ssize_t i0, i1;
    if (!PyArg_ParseTuple(args, "y*y*y*nnw*", &pts, &nds, &leaf_of, &i0, &i1, &out)) return NULL;
    Tree t = {(const float *)pts.buf, (const Node *)nds.buf, (int32_t)(nds.len / (Py_ssize_t)sizeof(Node))};
    const int32_t *lf = (const int32_t *)leaf_of.buf;
    double *o = (double *)out.buf;
    Py_BEGIN_ALLOW_THREADS
    int32_t stack[256];
    for (Py_ssize_t i = i0; i < i1; i++) {
        const float *p = t.pts + 3 * (size_t)i;
        int32_t leaf = lf[i];
        double best2 = nn_subtree(&t, stack, leaf, (int32_t)i, p, INFINITY);
        int32_t prev = leaf, node = t.nodes[leaf].par;
        while (node >= 0) {  /* each ancestor's other subtree; far ones cost one sphere test */
            const Node *nd = t.nodes + node;
            int32_t other = (nd->kid == prev) ? prev + 1 : prev - 1;
            best2 = nn_subtree(&t, stack, other, (int32_t)i, p, best2);
            prev = node;
            node = nd->par;
        }
        o[i - i0] = sqrt(best2);
    }
    Py_END_ALLOW_THREADS
    PyBuffer_Release(&pts); PyBuffer_Release(&nds); PyBuffer_Release(&leaf_of); PyBuffer_Release(&out);
    Py_RETURN_NONE;
}

/* near_stats(points (n,3) f32 tree order, nodes, queries (q,3) f64, radius, bound, counts out (q) i64,
 *            clearance out (q) f64): per query, the number of points within `radius`, and the distance
 * to the nearest point if it is below `bound` (else inf).  For the cluster plan's cost estimate and its
 * near-surface test.  The node tests compare squares (no square root per node): the padded radii (BallTree)
 * keep every point of a node well inside its sphere, so a test that rounding tips either way changes which
 * nodes are opened, never a count or a distance. */
static PyObject *py_near_stats(PyObject *self, PyObject *args) {
    Py_buffer pts, nds, qs, counts, clear;
    double radius, bound;
    if (!PyArg_ParseTuple(args, "y*y*y*ddw*w*", &pts, &nds, &qs, &radius, &bound, &counts, &clear)) return NULL;
    Tree t = {(const float *)pts.buf, (const Node *)nds.buf, (int32_t)(nds.len / (Py_ssize_t)sizeof(Node))};
    Py_ssize_t nq = qs.len / (Py_ssize_t)(3 * sizeof(double));
    const double *q = (const double *)qs.buf;
    int64_t *cnt = (int64_t *)counts.buf;
    double *cl = (double *)clear.buf;
    const int want_count = counts.len > 0, want_clear = clear.len > 0;
    Py_BEGIN_ALLOW_THREADS
    int32_t stack[256];
    const double r2 = radius * radius;
    for (Py_ssize_t i = 0; i < nq; i++) {
        const double *p = q + 3 * (size_t)i;
        if (want_count) {  /* points within radius: whole nodes inside the ball counted at once */
            int64_t c = 0;
            int sp = 0;
            stack[sp++] = 0;
            while (sp > 0) {
                const Node *nd = t.nodes + stack[--sp];
                double wx = nd->c[0] - p[0], wy = nd->c[1] - p[1], wz = nd->c[2] - p[2];
                double d2 = wx * wx + wy * wy + wz * wz, out = radius + nd->r, in = radius - nd->r;
                if (d2 > out * out) continue;
                if (in >= 0.0 && d2 <= in * in) { c += nd->hi - nd->lo; continue; }
                if (nd->kid >= 0) { stack[sp++] = nd->kid; stack[sp++] = nd->kid + 1; continue; }
                for (int32_t k = nd->lo; k < nd->hi; k++) {
                    const float *o = t.pts + 3 * (size_t)k;
                    double dx = o[0] - p[0], dy = o[1] - p[1], dz = o[2] - p[2];
                    if (dx * dx + dy * dy + dz * dz <= r2) c++;
                }
            }
            cnt[i] = c;
        }
        if (want_clear) {  /* nearest point below the bound, nearer child first */
            double best = bound, best2 = bound * bound;
            int sp = 0;
            stack[sp++] = 0;
            while (sp > 0) {
                const Node *nd = t.nodes + stack[--sp];
                double wx = nd->c[0] - p[0], wy = nd->c[1] - p[1], wz = nd->c[2] - p[2];
                const double lim = best + nd->r;  /* |p - c| - r > best, without a square root */
                if (wx * wx + wy * wy + wz * wz > lim * lim) continue;
                if (nd->kid >= 0) {
                    const Node *a = t.nodes + nd->kid, *b = a + 1;
                    double da = (a->c[0] - p[0]) * (a->c[0] - p[0]) + (a->c[1] - p[1]) * (a->c[1] - p[1]) +
                                (a->c[2] - p[2]) * (a->c[2] - p[2]);
                    double db = (b->c[0] - p[0]) * (b->c[0] - p[0]) + (b->c[1] - p[1]) * (b->c[1] - p[1]) +
                                (b->c[2] - p[2]) * (b->c[2] - p[2]);
                    if (da <= db) { stack[sp++] = nd->kid + 1; stack[sp++] = nd->kid; }
                    else { stack[sp++] = nd->kid; stack[sp++] = nd->kid + 1; }
                    continue;
                }
                for (int32_t k = nd->lo; k < nd->hi; k++) {
                    const float *o = t.pts + 3 * (size_t)k;
                    double dx = o[0] - p[0], dy = o[1] - p[1], dz = o[2] - p[2];
                    double d2 = dx * dx + dy * dy + dz * dz;
                    if (d2 < best2) { best2 = d2; best = sqrt(d2); }
                }
            }
            cl[i] = best2 < bound * bound ? best : INFINITY;
        }
    }
    Py_END_ALLOW_THREADS
    PyBuffer_Release(&pts); PyBuffer_Release(&nds); PyBuffer_Release(&qs);
    PyBuffer_Release(&counts); PyBuffer_Release(&clear);
    Py_RETURN_NONE;
}

/* cpu_has_avx2() -> bool: can this CPU (and OS) run the _raycast_avx2 build? */
static PyObject *py_cpu_has_avx2(PyObject *self, PyObject *noargs) {
#if defined(__x86_64__) && defined(__GNUC__)
    __builtin_cpu_init();
    return PyBool_FromLong(__builtin_cpu_supports("avx2") && __builtin_cpu_supports("popcnt"));
#else
    Py_RETURN_FALSE;
#endif
}

static PyMethodDef methods[] = {
    {"cpu_has_avx2", py_cpu_has_avx2, METH_NOARGS, "Can this CPU run the AVX2 build of the kernel?"},
    {"build_tree", py_build_tree, METH_VARARGS, "KD-tree of bounding spheres (boundedness rays kernel)."},
    {"near_stats", py_near_stats, METH_VARARGS, "Points within a radius and bounded clearance per query."},
    {"nn_dist", py_nn_dist, METH_VARARGS, "Distance of each point to its nearest other point (tree order)."},
    {"wide_tree", py_wide_tree, METH_VARARGS, "The tree with WIDE_BYTES / 32 children a node (the rays kernel's packets)."},
    {"clusters", py_clusters, METH_VARARGS, "beta of the queries of a range of clusters (rays kernel)."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, STR(MODULE_NAME),
                                    "Compiled kernel of the rays boundedness estimator (docs/boundedness.md).",
                                    -1, methods};

PyMODINIT_FUNC CAT(PyInit_, MODULE_NAME)(void) {
    PyObject *m = PyModule_Create(&module);
    if (m && PyModule_AddIntConstant(m, "LEAF_SIZE", LEAF_SIZE) < 0) Py_CLEAR(m);  /* rays_kernel's leaf blocks */
    if (m && PyModule_AddIntConstant(m, "WIDE_BYTES", (long)sizeof(Wide)) < 0) Py_CLEAR(m);  /* BallTree.wide */
    return m;
}
