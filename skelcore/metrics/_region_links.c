/* The missing parts' region graph and border from the cloud's kept neighbour answers, in one compiled pass
 * over the unexplained points (design and numbers: docs/performance.md, section 6.10, "The non-ray stages
 * of a pruned branch, compiled"; the rules: skelcore/diagnostics/missing_parts.py, _regions).
 *
 * For each unexplained point (its row of the neighbour table: the distances and cloud rows of its K nearest
 * cloud points within the link, inf and n where fewer), from its first k answers: whether they settle its
 * k nearest unexplained points (the only k nearest, every one found unexplained, none but itself first at
 * distance 0) and then its links to them; from its first kk answers: whether they are the only kk nearest
 * and whether one of them is explained (the point is on its region's border).  What numpy did in a dozen
 * passes with their temporaries (the gathered rows, isfinite, the masks, the edge list); the rows not
 * settled are left to the searches of missing_parts.py as before.
 *
 * Plain C with the buffer protocol (no numpy headers at build time); the entry point releases the GIL.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#include <stdint.h>

/* the first c answers are the only c nearest: fewer found, or the next strictly farther */
static inline int unique_first(const double *d, Py_ssize_t K, Py_ssize_t c) {
    return K <= c || !isfinite(d[c - 1]) || d[c] > d[c - 1];
}

/* links(dist (N, K) f64, cloud (N, K) i32, K, sel (m,) i64, at (n + 1,) i32, covered (n,) u8, k, kk,
 *       heads (m * (k - 1),) i64, tails (same) i64, unsettled (m,) u8, border (m,) u8, unsure (m,) u8)
 * -> the number of links written.  Unexplained point i reads table row sel[i]; at[c] is cloud row c's
 * unexplained row (-1 when explained; at[n] = -1 for "none found").  unsettled[i]: its k nearest
 * unexplained points are not settled by its answers (no link written for it); border[i]: one of its first
 * kk answers found is explained; unsure[i]: those kk are not the only kk nearest. */
static PyObject *py_links(PyObject *self, PyObject *args) {
    Py_buffer db, jb, sb, ab, cb, hb, tb, ub, bb, qb;
    Py_ssize_t K, k, kk;
    if (!PyArg_ParseTuple(args, "y*y*ny*y*y*nnw*w*w*w*w*", &db, &jb, &K, &sb, &ab, &cb, &k, &kk, &hb, &tb, &ub,
                          &bb, &qb))
        return NULL;
    const Py_ssize_t m = sb.len / (Py_ssize_t)sizeof(int64_t), n = cb.len;
    const Py_ssize_t N = K > 0 ? db.len / (K * (Py_ssize_t)sizeof(double)) : 0;
    int ok = K > 0 && k >= 2 && k <= K && kk >= 1 && kk <= K && db.len == N * K * (Py_ssize_t)sizeof(double)
             && jb.len == N * K * (Py_ssize_t)sizeof(int32_t) && sb.len == m * (Py_ssize_t)sizeof(int64_t)
             && ab.len == (n + 1) * (Py_ssize_t)sizeof(int32_t) && ub.len == m && bb.len == m && qb.len == m
             && hb.len == tb.len && hb.len >= m * (k - 1) * (Py_ssize_t)sizeof(int64_t);
    const double *dist = (const double *)db.buf;
    const int32_t *cloud = (const int32_t *)jb.buf;
    const int64_t *sel = (const int64_t *)sb.buf;
    const int32_t *at = (const int32_t *)ab.buf;
    const uint8_t *covered = (const uint8_t *)cb.buf;
    int64_t *heads = (int64_t *)hb.buf, *tails = (int64_t *)tb.buf;
    uint8_t *unsettled = (uint8_t *)ub.buf, *border = (uint8_t *)bb.buf, *unsure = (uint8_t *)qb.buf;
    for (Py_ssize_t i = 0; ok && i < m; i++) ok = sel[i] >= 0 && sel[i] < N;
    Py_ssize_t count = 0;
    if (ok) {
        Py_BEGIN_ALLOW_THREADS
        for (Py_ssize_t i = 0; i < m; i++) {
            const double *d = dist + sel[i] * K;
            const int32_t *j = cloud + sel[i] * K;
            for (Py_ssize_t c = 0; c < K; c++) ok &= j[c] >= 0 && j[c] <= n;  /* the rows read: n is "none" */
            if (!ok) break;
            int settled = unique_first(d, K, k) && d[1] > 0;
            /* unexplained: not covered (the row n, none found, is not finite) */
            for (Py_ssize_t c = 0; settled && c < k; c++) settled = !isfinite(d[c]) || (j[c] < n && !covered[j[c]]);
            unsettled[i] = !settled;
            if (settled) {
                for (Py_ssize_t c = 1; c < k; c++) {
                    if (isfinite(d[c])) {
                        heads[count] = i;
                        tails[count] = at[j[c]];
                        count++;
                    }
                }
            }
            int touches = 0;
            for (Py_ssize_t c = 0; c < kk; c++) touches |= isfinite(d[c]) && j[c] < n && covered[j[c]];
            border[i] = (uint8_t)touches;
            unsure[i] = !unique_first(d, K, kk);
        }
        Py_END_ALLOW_THREADS
    }
    PyBuffer_Release(&db); PyBuffer_Release(&jb); PyBuffer_Release(&sb); PyBuffer_Release(&ab); PyBuffer_Release(&cb);
    PyBuffer_Release(&hb); PyBuffer_Release(&tb); PyBuffer_Release(&ub); PyBuffer_Release(&bb); PyBuffer_Release(&qb);
    if (!ok) {  /* the arrays' sizes, or a table row out of range */
        PyErr_SetString(PyExc_ValueError, "links: inconsistent arrays or a row out of range");
        return NULL;
    }
    return PyLong_FromSsize_t(count);
}

static PyMethodDef methods[] = {
    {"links", py_links, METH_VARARGS, "The missing regions' links and border from the kept neighbour answers."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_region_links",
                                    "The missing parts' region graph and border in one pass (docs/performance.md, section 6.10).",
                                    -1, methods};

PyMODINIT_FUNC PyInit__region_links(void) { return PyModule_Create(&module); }
