/* Compiled Euclidean minimum spanning tree of SkelScope's topology stage (docs/metrics.md 1: the H0 barcode of a
 * Vietoris-Rips filtration is the EMST's edge lengths; design and numbers: docs/performance.md, section 6.1).
 *
 * Boruvka's algorithm over a KD-tree of the (distinct) points.  Each round, every component takes its
 * shortest outgoing edge.  A point's candidate is its nearest point in another component, found by a
 * nearest-first search that skips nodes wholly inside the point's own component (a label per node, set
 * each round) and nodes farther than its component's best candidate so far.  Candidates carry over:
 * components only grow, so a candidate whose far end is still in another component is still that point's
 * nearest, and one that fell inside leaves a lower bound (its length) that spares the search while the
 * component already has a shorter candidate.  Ties only ever form cycles of equal-length edges, which the
 * union-find merge drops, so the multiset of lengths is exact.  The first round keeps each point's KNN
 * nearest others (sorted; nothing left out is closer than the last): a later round takes a point's
 * candidate from that list, the first entry outside its component, and searches only for points whose
 * whole list lies inside.  The caller may hand those lists in, from another search of the same
 * points (centeredness' k nearest positions, docs/performance.md 6.1): each is checked to be KNN other
 * points in non-decreasing distance, and searched here if not.  Lengths are sqrt of the sum of squared coordinate differences in double
 * precision, in that order (as scipy's cKDTree computes them).
 *
 * The searches of a round run on `threads` threads in blocks of BLOCK points (a shared counter hands out
 * the blocks); the stop flag is read before every block and at every node of the build with more than
 * 65,536 points.  The candidates are per point, the bound per component is lowered with a compare-and-swap
 * (non-negative doubles order as their bit patterns), and each component's edge is picked afterwards, in
 * point order, from the candidates: the lengths do not depend on the threads.
 *
 * The same tree (leaves of KNN_LEAF points) also answers k-nearest queries (knn_tree, knn_query): the
 * skeletal set's distinct positions of skeletal centeredness and smoothness (docs/performance.md 6.4).
 *
 * Plain C with the buffer protocol (no numpy headers at build time); the entry points release the GIL.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define LEAF 8
#define STACK 256
#define BLOCK 1024
#define MAX_THREADS 64
#define KNN 6              /* neighbours each point keeps from the first round (docs/performance.md 6.1) */

typedef struct {
    double lo[3], hi[3];   /* bounding box of the node's points */
    int32_t kid;           /* first child (second = kid + 1), -1 for a leaf */
    int32_t a, b;          /* point range [a, b) in tree order */
    int32_t label;         /* the component holding every point of the node, -1 if several */
} Node;                    /* 64 bytes */

typedef struct {
    double *P;             /* points in tree order, n x 3 */
    int32_t *perm;         /* tree order -> input row */
    Node *nodes;
    int32_t n_nodes, n;
    int32_t leaf;          /* most points in a leaf (LEAF for the EMST) */
    volatile int32_t *stop;
} Tree;

/* ---- build: median split of the widest axis, preorder numbering (children after their parent) ---- */
static void swap_rows(double *P, int32_t *perm, int32_t i, int32_t j) {
    double t0 = P[3 * i], t1 = P[3 * i + 1], t2 = P[3 * i + 2];
    P[3 * i] = P[3 * j]; P[3 * i + 1] = P[3 * j + 1]; P[3 * i + 2] = P[3 * j + 2];
    P[3 * j] = t0; P[3 * j + 1] = t1; P[3 * j + 2] = t2;
    int32_t tp = perm[i]; perm[i] = perm[j]; perm[j] = tp;
}

/* rows [a, b) rearranged so that row k holds the k-th smallest coordinate `ax` (Hoare quickselect) */
static void select_rows(double *P, int32_t *perm, int32_t a, int32_t b, int32_t k, int ax) {
    int32_t lo = a, hi = b - 1;
    while (hi > lo) {
        int32_t mid = lo + (hi - lo) / 2;
        /* median of three as pivot */
        double x = P[3 * lo + ax], y = P[3 * mid + ax], z = P[3 * hi + ax];
        double pivot = (x < y) ? ((y < z) ? y : ((x < z) ? z : x)) : ((x < z) ? x : ((y < z) ? z : y));
        int32_t i = lo, j = hi;
        while (i <= j) {
            while (P[3 * i + ax] < pivot) i++;
            while (P[3 * j + ax] > pivot) j--;
            if (i <= j) { swap_rows(P, perm, i, j); i++; j--; }
        }
        if (k <= j) hi = j;
        else if (k >= i) lo = i;
        else return;
    }
}

static void node_box(const double *P, Node *nd) {
    for (int d = 0; d < 3; d++) { nd->lo[d] = INFINITY; nd->hi[d] = -INFINITY; }
    for (int32_t i = nd->a; i < nd->b; i++)
        for (int d = 0; d < 3; d++) {
            double v = P[3 * i + d];
            if (v < nd->lo[d]) nd->lo[d] = v;
            if (v > nd->hi[d]) nd->hi[d] = v;
        }
}

static int build(Tree *t) {
    /* explicit work list in preorder: node k's children get the next two free slots */
    int32_t *todo = malloc(sizeof(int32_t) * (size_t)(t->n_nodes + 1));
    if (!todo) return -1;
    int32_t top = 0, used = 1;
    t->nodes[0].a = 0; t->nodes[0].b = t->n;
    todo[top++] = 0;
    while (top) {
        int32_t k = todo[--top];
        Node *nd = &t->nodes[k];
        if (nd->b - nd->a > 65536 && *t->stop) { free(todo); return 1; }
        node_box(t->P, nd);
        if (nd->b - nd->a <= t->leaf) { nd->kid = -1; continue; }
        int ax = 0;
        double w = nd->hi[0] - nd->lo[0];
        for (int d = 1; d < 3; d++) if (nd->hi[d] - nd->lo[d] > w) { w = nd->hi[d] - nd->lo[d]; ax = d; }
        int32_t m = nd->a + (nd->b - nd->a) / 2;
        select_rows(t->P, t->perm, nd->a, nd->b, m, ax);
        nd->kid = used;
        Node *l = &t->nodes[used], *r = &t->nodes[used + 1];
        l->a = nd->a; l->b = m; r->a = m; r->b = nd->b;
        used += 2;
        todo[top++] = nd->kid + 1;
        todo[top++] = nd->kid;
    }
    t->n_nodes = used;
    free(todo);
    return 0;
}

/* ---- Boruvka state ---- */
typedef struct {
    Tree *t;
    int32_t *comp;         /* component (root point) of every point, tree order */
    double *cand_d;        /* each point's candidate: its length ... */
    int32_t *cand_j;       /* ... and its far end (-1: none) */
    double *lower;         /* nothing of another component is closer than this */
    int64_t *bound_bits;   /* per component (root point): best candidate length so far, as bits */
    int32_t *knn;          /* each point's KNN nearest others (first round), nearest first, -1 past the end */
    double *kth;           /* nothing outside that list is closer than this (inf: it holds every other point) */
    uint8_t *cursor;       /* list entries before it are known to lie in the point's component */
    const int32_t *given;  /* the caller's first-round lists (tree order), n x KNN, or NULL */
    int first;             /* the first round: every point's KNN nearest others */
    int64_t next_block;    /* shared block counter of the current round */
    int64_t n_blocks;
    int stopped;
} State;

static inline double box_d2(const Node *nd, const double *x) {
    double s = 0.0;
    for (int d = 0; d < 3; d++) {
        double g = 0.0;
        if (x[d] < nd->lo[d]) g = nd->lo[d] - x[d];
        else if (x[d] > nd->hi[d]) g = x[d] - nd->hi[d];
        s += g * g;
    }
    return s;
}

static inline double bits_to_d(int64_t b) { double d; memcpy(&d, &b, 8); return d; }
static inline int64_t d_to_bits(double d) { int64_t b; memcpy(&b, &d, 8); return b; }

static void lower_bound(int64_t *slot, double d) {
    int64_t want = d_to_bits(d);
    int64_t cur = __atomic_load_n(slot, __ATOMIC_RELAXED);
    while (want < cur && !__atomic_compare_exchange_n(slot, &cur, want, 1, __ATOMIC_RELAXED, __ATOMIC_RELAXED)) {
    }
}

/* nearest point of another component than c to point i, strictly closer than sqrt(bound2) */
static int32_t search(const Tree *t, const int32_t *comp, int32_t i, int32_t c, double bound2, double *out2) {
    const double *x = &t->P[3 * i];
    int32_t stack[STACK];
    double sd[STACK];
    int top = 0;
    double best2 = bound2;
    int32_t bestj = -1;
    const Node *N = t->nodes;
    if (N[0].label == c) return -1;
    stack[top] = 0; sd[top] = box_d2(&N[0], x); top++;
    while (top) {
        top--;
        int32_t k = stack[top];
        if (!(sd[top] < best2)) continue;
        const Node *nd = &N[k];
        if (nd->kid < 0) {
            for (int32_t j = nd->a; j < nd->b; j++) {
                if (comp[j] == c) continue;
                const double *y = &t->P[3 * j];
                double dx = x[0] - y[0], dy = x[1] - y[1], dz = x[2] - y[2];
                double d2 = dx * dx + dy * dy + dz * dz;
                if (d2 < best2) { best2 = d2; bestj = j; }
            }
            continue;
        }
        const Node *l = &N[nd->kid], *r = &N[nd->kid + 1];
        double dl = (l->label == c) ? INFINITY : box_d2(l, x);
        double dr = (r->label == c) ? INFINITY : box_d2(r, x);
        if (top + 2 > STACK) continue;  /* cannot happen: depth <= log2(n / LEAF) + 1 */
        if (dl <= dr) {
            if (dr < best2) { stack[top] = nd->kid + 1; sd[top] = dr; top++; }
            if (dl < best2) { stack[top] = nd->kid; sd[top] = dl; top++; }
        } else {
            if (dl < best2) { stack[top] = nd->kid; sd[top] = dl; top++; }
            if (dr < best2) { stack[top] = nd->kid + 1; sd[top] = dr; top++; }
        }
    }
    *out2 = best2;
    return bestj;
}

/* KNN nearest other points of point i into list (nearest first; -1 past the end), their squared
 * distances into d2s; returns how many.  Every point left out is at least d2s[KNN - 1] away. */
static int search_knn(const Tree *t, int32_t i, int32_t *list, double *d2s) {
    const double *x = &t->P[3 * i];
    int32_t stack[STACK];
    double sd[STACK];
    int top = 0, m = 0;
    const Node *N = t->nodes;
    stack[top] = 0; sd[top] = box_d2(&N[0], x); top++;
    while (top) {
        top--;
        int32_t k = stack[top];
        double worst = (m == KNN) ? d2s[KNN - 1] : INFINITY;
        if (!(sd[top] < worst)) continue;
        const Node *nd = &N[k];
        if (nd->kid < 0) {
            for (int32_t j = nd->a; j < nd->b; j++) {
                if (j == i) continue;
                const double *y = &t->P[3 * j];
                double dx = x[0] - y[0], dy = x[1] - y[1], dz = x[2] - y[2];
                double d2 = dx * dx + dy * dy + dz * dz;
                if (m == KNN && !(d2 < d2s[KNN - 1])) continue;
                int p = (m < KNN) ? m++ : KNN - 1;  /* sorted insert, ascending */
                while (p > 0 && d2s[p - 1] > d2) {
                    d2s[p] = d2s[p - 1]; list[p] = list[p - 1]; p--;
                }
                d2s[p] = d2; list[p] = j;
            }
            continue;
        }
        double worst2 = (m == KNN) ? d2s[KNN - 1] : INFINITY;
        double dl = box_d2(&N[nd->kid], x), dr = box_d2(&N[nd->kid + 1], x);
        if (top + 2 > STACK) continue;  /* cannot happen: depth <= log2(n / LEAF) + 1 */
        if (dl <= dr) {
            if (dr < worst2) { stack[top] = nd->kid + 1; sd[top] = dr; top++; }
            if (dl < worst2) { stack[top] = nd->kid; sd[top] = dl; top++; }
        } else {
            if (dl < worst2) { stack[top] = nd->kid; sd[top] = dl; top++; }
            if (dr < worst2) { stack[top] = nd->kid + 1; sd[top] = dr; top++; }
        }
    }
    for (int p = m; p < KNN; p++) list[p] = -1;
    return m;
}

/* point i's KNN nearest others from the caller's list (another search's answer, nearest first: nothing
 * left out is closer than its last), their squared distances in this kernel's arithmetic; 0 (search
 * instead) unless they are KNN other points in non-decreasing order of those distances */
static int take_given(const Tree *t, const int32_t *given, int32_t i, int32_t *list, double *d2s) {
    const double *x = &t->P[3 * i];
    for (int p = 0; p < KNN; p++) {
        int32_t j = given[(size_t)i * KNN + p];
        if (j < 0 || j >= t->n || j == i) return 0;
        const double *y = &t->P[3 * j];
        double dx = x[0] - y[0], dy = x[1] - y[1], dz = x[2] - y[2];
        d2s[p] = dx * dx + dy * dy + dz * dz;
        if (p > 0 && d2s[p] < d2s[p - 1]) return 0;
        list[p] = j;
    }
    return 1;
}

/* the first entry of point i's list outside component c (its nearest point of another component:
 * nothing closer lies outside the list), or -1 with lower[i] raised to the list's reach */
static int32_t from_list(State *s, int32_t i, int32_t c) {
    const int32_t *list = &s->knn[(size_t)i * KNN];
    int p = s->cursor[i];
    while (p < KNN && list[p] >= 0 && s->comp[list[p]] == c) p++;
    s->cursor[i] = (uint8_t)p;
    if (p < KNN && list[p] >= 0) return list[p];
    if (s->kth[i] > s->lower[i]) s->lower[i] = s->kth[i];
    return -1;
}

static void *search_blocks(void *arg) {
    State *s = (State *)arg;
    const Tree *t = s->t;
    for (;;) {
        if (*t->stop) { s->stopped = 1; return NULL; }
        int64_t blk = __atomic_fetch_add(&s->next_block, 1, __ATOMIC_RELAXED);
        if (blk >= s->n_blocks) return NULL;
        int32_t i0 = (int32_t)(blk * BLOCK), i1 = i0 + BLOCK < t->n ? i0 + BLOCK : t->n;
        if (s->first) {
            for (int32_t i = i0; i < i1; i++) {
                int32_t *list = &s->knn[(size_t)i * KNN];
                double d2s[KNN];
                int m = (s->given && take_given(t, s->given, i, list, d2s)) ? KNN : search_knn(t, i, list, d2s);
                s->kth[i] = (m == KNN) ? sqrt(d2s[KNN - 1]) : INFINITY;
                s->cursor[i] = 0;
                if (m == 0) continue;  /* cannot happen: n >= 2 */
                s->cand_d[i] = sqrt(d2s[0]);
                s->cand_j[i] = list[0];
                s->cursor[i] = 1;
                lower_bound(&s->bound_bits[s->comp[i]], s->cand_d[i]);
            }
            continue;
        }
        for (int32_t i = i0; i < i1; i++) {
            if (s->cand_j[i] >= 0) continue;
            int32_t c = s->comp[i];
            int32_t near = from_list(s, i, c);
            if (near >= 0) {  /* the same arithmetic as search() */
                const double *x = &t->P[3 * i], *y = &t->P[3 * near];
                double dx = x[0] - y[0], dy = x[1] - y[1], dz = x[2] - y[2];
                double d = sqrt(dx * dx + dy * dy + dz * dz);
                s->cand_d[i] = d;
                s->cand_j[i] = near;
                lower_bound(&s->bound_bits[c], d);
                continue;
            }
            double bound = bits_to_d(__atomic_load_n(&s->bound_bits[c], __ATOMIC_RELAXED));
            if (s->lower[i] >= bound) continue;
            double d2;
            int32_t j = search(t, s->comp, i, c, bound * bound, &d2);
            if (j >= 0) {
                double d = sqrt(d2);
                s->cand_d[i] = d;
                s->cand_j[i] = j;
                lower_bound(&s->bound_bits[c], d);
            } else if (bound > s->lower[i]) {
                s->lower[i] = bound;  /* nothing of another component closer than the bound */
            }
        }
    }
}

static int32_t find(int32_t *parent, int32_t i) {
    int32_t r = i;
    while (parent[r] != r) r = parent[r];
    while (parent[i] != r) { int32_t nx = parent[i]; parent[i] = r; i = nx; }
    return r;
}

static void set_labels(Tree *t, const int32_t *comp) {
    for (int32_t k = t->n_nodes - 1; k >= 0; k--) {  /* children come after their parent */
        Node *nd = &t->nodes[k];
        if (nd->kid < 0) {
            int32_t c = comp[nd->a];
            for (int32_t j = nd->a + 1; j < nd->b; j++) if (comp[j] != c) { c = -1; break; }
            nd->label = c;
        } else {
            int32_t c = t->nodes[nd->kid].label;
            nd->label = (c >= 0 && t->nodes[nd->kid + 1].label == c) ? c : -1;
        }
    }
}

/* The whole EMST; returns the number of edges (n - 1), -1 on a stop, -2 out of memory. */
static int64_t emst(const double *pts, int32_t n, double *lengths, double *nn, volatile int32_t *stop,
                    int64_t *components, int threads, const int32_t *given) {
    Tree t = {0};
    State s = {0};
    int64_t m = 0, status = 0;
    int32_t *parent = NULL, *pick = NULL, *given_t = NULL;
    t.n = n;
    t.leaf = LEAF;
    t.stop = stop;
    t.n_nodes = 2 * ((n + LEAF - 1) / LEAF) * 2 + 2;  /* generous: median splits give < 2 n / (LEAF / 2) */
    t.P = malloc(sizeof(double) * 3 * (size_t)n);
    t.perm = malloc(sizeof(int32_t) * (size_t)n);
    t.nodes = malloc(sizeof(Node) * (size_t)t.n_nodes);
    s.comp = malloc(sizeof(int32_t) * (size_t)n);
    s.cand_d = malloc(sizeof(double) * (size_t)n);
    s.cand_j = malloc(sizeof(int32_t) * (size_t)n);
    s.lower = malloc(sizeof(double) * (size_t)n);
    s.bound_bits = malloc(sizeof(int64_t) * (size_t)n);
    parent = malloc(sizeof(int32_t) * (size_t)n);
    pick = malloc(sizeof(int32_t) * (size_t)n);
    s.knn = malloc(sizeof(int32_t) * KNN * (size_t)n);
    s.kth = malloc(sizeof(double) * (size_t)n);
    s.cursor = malloc((size_t)n);
    if (!s.knn || !s.kth || !s.cursor || !pick || !t.P || !t.perm || !t.nodes || !s.comp || !s.cand_d || !s.cand_j || !s.lower || !s.bound_bits || !parent) {
        status = -2;
        goto done;
    }
    memcpy(t.P, pts, sizeof(double) * 3 * (size_t)n);
    for (int32_t i = 0; i < n; i++) t.perm[i] = i;
    {
        int r = build(&t);
        if (r < 0) { status = -2; goto done; }
        if (r > 0) { status = -1; goto done; }
    }
    s.t = &t;
    if (given) {  /* the caller's lists, rows and entries in tree order (pick: input row -> tree order) */
        given_t = malloc(sizeof(int32_t) * KNN * (size_t)n);
        if (!given_t) { status = -2; goto done; }
        for (int32_t i = 0; i < n; i++) pick[t.perm[i]] = i;
        for (int32_t i = 0; i < n; i++)
            for (int p = 0; p < KNN; p++) {
                int32_t j = given[(size_t)t.perm[i] * KNN + p];
                given_t[(size_t)i * KNN + p] = (j >= 0 && j < n) ? pick[j] : -1;
            }
        s.given = given_t;
    }
    for (int32_t i = 0; i < n; i++) {
        parent[i] = i; s.comp[i] = i; s.cand_j[i] = -1; s.lower[i] = 0.0;
    }
    int64_t n_comp = n;
    int first = 1;
    s.first = 1;
    if (threads < 1) threads = 1;
    if (threads > MAX_THREADS) threads = MAX_THREADS;
    while (n_comp > 1) {
        *components = n_comp;
        set_labels(&t, s.comp);
        /* candidates still leaving their component stand; the others leave a lower bound */
        for (int32_t i = 0; i < n; i++) if (s.comp[i] == i) s.bound_bits[i] = d_to_bits(INFINITY);
        for (int32_t i = 0; i < n; i++) {
            int32_t j = s.cand_j[i];
            if (j < 0) continue;
            if (s.comp[j] != s.comp[i]) {
                if (d_to_bits(s.cand_d[i]) < s.bound_bits[s.comp[i]]) s.bound_bits[s.comp[i]] = d_to_bits(s.cand_d[i]);
            } else {
                s.cand_j[i] = -1;
                if (s.cand_d[i] > s.lower[i]) s.lower[i] = s.cand_d[i];
            }
        }
        s.next_block = 0;
        s.n_blocks = ((int64_t)n + BLOCK - 1) / BLOCK;
        int use = (n >= 16 * BLOCK) ? threads : 1;
        if (use > 1) {
            pthread_t tid[MAX_THREADS];
            int started = 0;
            for (int k = 1; k < use; k++) {
                if (pthread_create(&tid[k], NULL, search_blocks, &s) != 0) break;
                started = k;
            }
            search_blocks(&s);
            for (int k = 1; k <= started; k++) pthread_join(tid[k], NULL);
        } else {
            search_blocks(&s);
        }
        if (s.stopped) { status = -1; goto done; }
        if (first) {  /* every point searched with no bound: its nearest other point */
            for (int32_t i = 0; i < n; i++) nn[t.perm[i]] = s.cand_d[i];
            first = 0;
            s.first = 0;
        }
        /* each component's shortest candidate, the first in point order among equals */
        for (int32_t i = 0; i < n; i++) if (s.comp[i] == i) pick[i] = -1;
        for (int32_t i = 0; i < n; i++) {
            if (s.cand_j[i] < 0) continue;
            int32_t c = s.comp[i];
            int32_t p = pick[c];
            if (p < 0 || s.cand_d[i] < s.cand_d[p]) pick[c] = i;
        }
        int64_t merged = 0;
        for (int32_t c = 0; c < n; c++) {
            if (s.comp[c] != c) continue;
            int32_t p = pick[c];
            if (p < 0) continue;  /* cannot happen while there are two components */
            int32_t ra = find(parent, p), rb = find(parent, s.cand_j[p]);
            if (ra == rb) continue;  /* the other side took the same (or an equal) edge */
            if (ra < rb) parent[rb] = ra; else parent[ra] = rb;
            lengths[m++] = s.cand_d[p];
            merged++;
        }
        if (merged == 0) { status = -3; goto done; }
        n_comp -= merged;
        for (int32_t i = 0; i < n; i++) s.comp[i] = find(parent, i);
    }
    *components = 1;
    status = m;
done:
    free(t.P); free(t.perm); free(t.nodes); free(s.comp); free(s.cand_d); free(s.cand_j); free(s.lower);
    free(s.bound_bits); free(parent); free(pick); free(s.knn); free(s.kth); free(s.cursor); free(given_t);
    return status;
}

/* ---- k nearest neighbours of query points, the order scipy's cKDTree gives where distances fix it ----
 * (the skeletal set's distinct positions of skeletal centeredness and smoothness, docs/performance.md 6.4)
 * A tree of the points (the EMST's build) kept in a capsule; a query walks it nearest child first and keeps
 * the kq nearest by squared distance, summed as cKDTree sums them (dx^2, then + dy^2, then + dz^2), in a
 * sorted list.  A row whose kq squared distances are not strictly increasing is flagged: its order (or,
 * at the kq-th, its set) is scipy's search's own, and the caller asks scipy for that row. */
#define KNN_MAX 256
#define KNN_LEAF 32        /* points per leaf: k = 31 queries at 1M, about 20 % less CPU than leaves of 8 */

static void knn_free(PyObject *cap) {
    Tree *t = (Tree *)PyCapsule_GetPointer(cap, "skelcore.knn_tree");
    if (!t) return;
    free(t->P); free(t->perm); free(t->nodes); free(t);
}

static int knn_one(const Tree *t, const double *x, int kq, int32_t *list, double *d2s) {
    int32_t stack[STACK];
    double sd[STACK];
    int top = 0, m = 0;
    const Node *N = t->nodes;
    const double *P = t->P;
    stack[top] = 0; sd[top] = box_d2(&N[0], x); top++;
    double worst = INFINITY;
    while (top) {
        top--;
        if (!(sd[top] < worst)) continue;
        const Node *nd = &N[stack[top]];
        if (nd->kid < 0) {
            for (int32_t j = nd->a; j < nd->b; j++) {
                const double *y = &P[3 * j];
                double dx = x[0] - y[0], dy = x[1] - y[1], dz = x[2] - y[2];
                double d2 = dx * dx + dy * dy + dz * dz;
                if (!(d2 < worst)) continue;
                int p = (m < kq) ? m++ : kq - 1;  /* sorted insert, ascending */
                while (p > 0 && d2s[p - 1] > d2) { d2s[p] = d2s[p - 1]; list[p] = list[p - 1]; p--; }
                d2s[p] = d2; list[p] = j;
                if (m == kq) worst = d2s[kq - 1];
            }
            continue;
        }
        const Node *l = &N[nd->kid], *r = &N[nd->kid + 1];
        __builtin_prefetch(l); __builtin_prefetch(r);
        double dl = box_d2(l, x), dr = box_d2(r, x);
        if (top + 2 > STACK) continue;  /* cannot happen: depth <= log2(n / LEAF) + 1 */
        if (dl <= dr) {
            if (dr < worst) { stack[top] = nd->kid + 1; sd[top] = dr; top++; }
            if (dl < worst) { stack[top] = nd->kid; sd[top] = dl; top++; }
        } else {
            if (dl < worst) { stack[top] = nd->kid; sd[top] = dl; top++; }
            if (dr < worst) { stack[top] = nd->kid + 1; sd[top] = dr; top++; }
        }
    }
    return m;
}


/* knn_tree(points float64 (n, 3), stop int32[1]) -> capsule, or None when stopped (the stop flag is read
 * at every node of the build with more than 65,536 points) */
static PyObject *py_knn_tree(PyObject *self, PyObject *args) {
    Py_buffer pts, stop;
    if (!PyArg_ParseTuple(args, "y*w*", &pts, &stop)) return NULL;
    int64_t n = pts.len / (Py_ssize_t)(3 * sizeof(double));
    if (n < 1 || n > INT32_MAX / 4 || stop.len < 4) {
        PyBuffer_Release(&pts); PyBuffer_Release(&stop);
        PyErr_SetString(PyExc_ValueError, "knn_tree: between 1 and 2^29 points and a stop flag");
        return NULL;
    }
    Tree *t = calloc(1, sizeof(Tree));
    int r = -1;
    if (t) {
        t->n = (int32_t)n;
        t->leaf = KNN_LEAF;
        t->n_nodes = 2 * ((t->n + KNN_LEAF - 1) / KNN_LEAF) * 2 + 2;
        t->P = malloc(sizeof(double) * 3 * (size_t)n);
        t->perm = malloc(sizeof(int32_t) * (size_t)n);
        t->nodes = malloc(sizeof(Node) * (size_t)t->n_nodes);
        t->stop = (volatile int32_t *)stop.buf;
        if (t->P && t->perm && t->nodes) {
            Py_BEGIN_ALLOW_THREADS
            memcpy(t->P, pts.buf, sizeof(double) * 3 * (size_t)n);
            for (int32_t i = 0; i < t->n; i++) t->perm[i] = i;
            r = build(t);
            Py_END_ALLOW_THREADS
        }
        t->stop = NULL;  /* read by the build only */
    }
    PyBuffer_Release(&pts); PyBuffer_Release(&stop);
    if (r != 0) {
        if (t) { free(t->P); free(t->perm); free(t->nodes); free(t); }
        if (r > 0) Py_RETURN_NONE;
        return PyErr_NoMemory();
    }
    PyObject *cap = PyCapsule_New(t, "skelcore.knn_tree", knn_free);
    if (!cap) { free(t->P); free(t->perm); free(t->nodes); free(t); }
    return cap;
}

/* knn_order(tree, out int64 (n)): the points' rows in the tree's leaf order (spatial neighbours together) */
static PyObject *py_knn_order(PyObject *self, PyObject *args) {
    PyObject *cap;
    Py_buffer out;
    if (!PyArg_ParseTuple(args, "Ow*", &cap, &out)) return NULL;
    Tree *t = (Tree *)PyCapsule_GetPointer(cap, "skelcore.knn_tree");
    int ok = t && out.len == (Py_ssize_t)(sizeof(int64_t) * t->n);
    if (ok) for (int32_t i = 0; i < t->n; i++) ((int64_t *)out.buf)[i] = t->perm[i];
    else if (t) PyErr_SetString(PyExc_ValueError, "knn_order: one int64 per point");
    PyBuffer_Release(&out);
    if (!ok) return NULL;
    Py_RETURN_NONE;
}

/* knn_query(tree, queries float64 (q, 3), kq, dist float64 (q, kq) out, idx int64 (q, kq) out,
 *           unsure uint8 (q) out) -> rows flagged unsure (kq squared distances not strictly increasing) */
static PyObject *py_knn_query(PyObject *self, PyObject *args) {
    PyObject *cap;
    Py_buffer qs, dist, idx, unsure;
    int kq;
    if (!PyArg_ParseTuple(args, "Oy*iw*w*w*", &cap, &qs, &kq, &dist, &idx, &unsure)) return NULL;
    Tree *t = (Tree *)PyCapsule_GetPointer(cap, "skelcore.knn_tree");
    int64_t q = qs.len / (Py_ssize_t)(3 * sizeof(double));
    int64_t flagged = -1;
    if (!t) {
        /* error set by PyCapsule_GetPointer */
    } else if (kq < 1 || kq > KNN_MAX || kq > t->n || dist.len != (Py_ssize_t)(sizeof(double) * kq * q) ||
               idx.len != (Py_ssize_t)(sizeof(int64_t) * kq * q) || unsure.len != q) {
        PyErr_SetString(PyExc_ValueError, "knn_query: buffer sizes do not match the queries");
    } else {
        flagged = 0;
        Py_BEGIN_ALLOW_THREADS
        const double *Q = (const double *)qs.buf;
        double *D = (double *)dist.buf;
        int64_t *I = (int64_t *)idx.buf;
        uint8_t *U = (uint8_t *)unsure.buf;
        int32_t list[KNN_MAX];
        double d2s[KNN_MAX];
        for (int64_t i = 0; i < q; i++) {
            knn_one(t, &Q[3 * i], kq, list, d2s);
            int bad = 0;
            for (int p = 0; p < kq; p++) {
                D[i * kq + p] = sqrt(d2s[p]);
                I[i * kq + p] = t->perm[list[p]];
                if (p > 0 && !(d2s[p - 1] < d2s[p])) bad = 1;
            }
            U[i] = (uint8_t)bad;
            flagged += bad;
        }
        Py_END_ALLOW_THREADS
    }
    PyBuffer_Release(&qs); PyBuffer_Release(&dist); PyBuffer_Release(&idx); PyBuffer_Release(&unsure);
    if (flagged < 0) return NULL;
    return PyLong_FromLongLong(flagged);
}

/* emst(points float64 (n, 3), lengths float64 (n - 1) out, nn float64 (n) out, stop int32[1],
 *      components int64[1] out (progress), threads, first int32 (n, 6) or None) -> edges written;
 * `first`: each point's 6 nearest other points (input rows, nearest first) from another search, taken
 * as the first round's lists (a list that is not checks out is searched) */
static PyObject *py_emst(PyObject *self, PyObject *args) {
    Py_buffer pts, len, nn, stop, comps, first = {0};
    int threads = 1;
    PyObject *first_obj = Py_None;
    if (!PyArg_ParseTuple(args, "y*w*w*w*w*|iO", &pts, &len, &nn, &stop, &comps, &threads, &first_obj)) return NULL;
    if (first_obj != Py_None && PyObject_GetBuffer(first_obj, &first, PyBUF_SIMPLE) < 0) {
        PyBuffer_Release(&pts); PyBuffer_Release(&len); PyBuffer_Release(&nn); PyBuffer_Release(&stop);
        PyBuffer_Release(&comps);
        return NULL;
    }
    int64_t n = pts.len / (Py_ssize_t)(3 * sizeof(double));
    int64_t r = 0;
    if (n > INT32_MAX / 4 || len.len < (Py_ssize_t)(sizeof(double) * (n > 0 ? n - 1 : 0)) ||
        nn.len < (Py_ssize_t)(sizeof(double) * n) || stop.len < 4 || comps.len < 8 ||
        (first.buf && first.len != (Py_ssize_t)(sizeof(int32_t) * KNN * n))) {
        PyErr_SetString(PyExc_ValueError, "emst: buffer sizes do not match the points");
        r = -4;
    } else if (n >= 2) {
        Py_BEGIN_ALLOW_THREADS
        r = emst((const double *)pts.buf, (int32_t)n, (double *)len.buf, (double *)nn.buf,
                 (volatile int32_t *)stop.buf, (int64_t *)comps.buf, threads, (const int32_t *)first.buf);
        Py_END_ALLOW_THREADS
        if (r == -2) PyErr_NoMemory();
        if (r == -3) PyErr_SetString(PyExc_RuntimeError, "emst: a Boruvka round made no progress");
    }
    PyBuffer_Release(&pts); PyBuffer_Release(&len); PyBuffer_Release(&nn); PyBuffer_Release(&stop);
    PyBuffer_Release(&comps);
    if (first.buf) PyBuffer_Release(&first);
    if (r < -1) return NULL;
    return PyLong_FromLongLong(r);
}

static PyMethodDef methods[] = {
    {"emst", py_emst, METH_VARARGS, "Edge lengths of the Euclidean minimum spanning tree (Boruvka, exact)."},
    {"knn_tree", py_knn_tree, METH_VARARGS, "A KD-tree of points (float64 (n, 3)) for knn_query, in a capsule."},
    {"knn_order", py_knn_order, METH_VARARGS, "The points' rows in the kNN tree's leaf order."},
    {"knn_query", py_knn_query, METH_VARARGS, "The kq nearest points of each query by squared distance; rows with equal ones flagged."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_emst", NULL, -1, methods};

PyMODINIT_FUNC PyInit__emst(void) { return PyModule_Create(&module); }
