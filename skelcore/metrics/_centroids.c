/* Compiled neighbour sums of SkelScope's skeletal centeredness (docs/metrics.md 3, paper Eq. 10; design
 * and numbers: docs/performance.md, section 6.4).
 *
 * Per row i and its k neighbour slots s_ij: m_s = the mean of the skeletal rows, m_o = the mean of the
 * cloud rows, and M = the mean over j of |cloud[s_ij] - m_s|.  The arithmetic is numpy's, step by step,
 * so the values are the same bits as the array code they replace: each mean sums its rows in order and
 * divides by k (m_s from its first row, m_o from 0.0 as numpy's reduce: they differ only for -0.0); |v| = sqrt((v0 v0 + v1 v1) + v2 v2); M sums its k lengths as numpy's pairwise sum of a
 * contiguous row does (eight partial sums), then divides by k.  Built without FMA contraction (the
 * extension's flags), as numpy's loops are.
 *
 * Plain C with the buffer protocol (no numpy headers at build time); the entry point releases the GIL.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include "_pairwise_sum.h"

#define MAX_K 4096

/* neighbour_sums(skeletal (N,3) f64, cloud (N,3) f64, slot (n,k) i64, m_s out (n,3) f64, m_o out (n,3) f64,
 *                spread out (n) f64); every slot in [0, N) (the caller's) */
static PyObject *py_neighbour_sums(PyObject *self, PyObject *args) {
    Py_buffer sk, cl, sl, ms, mo, sp;
    if (!PyArg_ParseTuple(args, "y*y*y*w*w*w*", &sk, &cl, &sl, &ms, &mo, &sp)) return NULL;
    const double *S = (const double *)sk.buf, *C = (const double *)cl.buf;
    const int64_t *slot = (const int64_t *)sl.buf;
    double *out_s = (double *)ms.buf, *out_o = (double *)mo.buf, *out_m = (double *)sp.buf;
    const Py_ssize_t n = sp.len / (Py_ssize_t)sizeof(double);
    const Py_ssize_t k = n > 0 ? sl.len / (Py_ssize_t)sizeof(int64_t) / n : 0;
    const int64_t rows = (int64_t)(sk.len / (Py_ssize_t)(3 * sizeof(double)));
    int ok = k > 0 && k <= MAX_K && ms.len == 3 * n * (Py_ssize_t)sizeof(double)
             && mo.len == ms.len && sl.len == n * k * (Py_ssize_t)sizeof(int64_t) && cl.len == sk.len;
    for (Py_ssize_t t = 0; ok && t < n * k; t++) ok = slot[t] >= 0 && slot[t] < rows;
    if (ok || n == 0) {
        Py_BEGIN_ALLOW_THREADS
        double len[MAX_K];
        const double kd = (double)k;
        for (Py_ssize_t i = 0; i < n; i++) {
            const int64_t *s = slot + i * k;
            double a0 = 0.0, a1 = 0.0, a2 = 0.0, b0 = 0.0, b1 = 0.0, b2 = 0.0;
            for (Py_ssize_t j = 0; j < k; j++) {
                const double *x = S + 3 * s[j], *y = C + 3 * s[j];
                if (j == 0) { a0 = x[0]; a1 = x[1]; a2 = x[2]; }  /* m_s from its first row, m_o from 0.0 */
                else { a0 += x[0]; a1 += x[1]; a2 += x[2]; }
                b0 += y[0]; b1 += y[1]; b2 += y[2];
            }
            const double m0 = a0 / kd, m1 = a1 / kd, m2 = a2 / kd;
            for (Py_ssize_t j = 0; j < k; j++) {
                const double *y = C + 3 * s[j];
                double d0 = y[0] - m0, d1 = y[1] - m1, d2 = y[2] - m2;
                len[j] = sqrt((d0 * d0 + d2 * d2) + d1 * d1);  /* numpy's einsum: two lanes, the third term on the first */
            }
            out_s[3 * i] = m0; out_s[3 * i + 1] = m1; out_s[3 * i + 2] = m2;
            out_o[3 * i] = b0 / kd; out_o[3 * i + 1] = b1 / kd; out_o[3 * i + 2] = b2 / kd;
            out_m[i] = pairwise_sum(len, k) / kd;
        }
        Py_END_ALLOW_THREADS
    }
    PyBuffer_Release(&sk); PyBuffer_Release(&cl); PyBuffer_Release(&sl);
    PyBuffer_Release(&ms); PyBuffer_Release(&mo); PyBuffer_Release(&sp);
    if (!ok && n > 0) {
        PyErr_SetString(PyExc_ValueError, "neighbour_sums: slot must be (n, k) int64 rows of the points, 1 <= k <= 4096");
        return NULL;
    }
    Py_RETURN_NONE;
}

static PyMethodDef methods[] = {
    {"neighbour_sums", py_neighbour_sums, METH_VARARGS, "Per row: the neighbours' two means and mean distance."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_centroids",
                                    "Compiled neighbour sums of skeletal centeredness (docs/metrics.md, section 3).",
                                    -1, methods};

PyMODINIT_FUNC PyInit__centroids(void) { return PyModule_Create(&module); }
