/* Compiled passes over a set of points against a few shapes, each one loop over the coordinates instead
 * of numpy's chains of temporaries (design and numbers: docs/performance.md, section 6.10, "The non-ray
 * stages of a pruned branch, compiled"):
 *
 *   near_box        the points within a per-point bound of a box (an edited curve's coverage asks again
 *                   only the cloud points near its removed and added balls, skelcore/edit/coverage_update.py);
 *   nearest_squared each point's squared distance to the nearest of a few centres (the bounds of a missing
 *                   region's depth quantile and its distances to a small border, skelcore/diagnostics/missing_parts.py);
 *   nearest_two     each point's two nearest of some hundreds of centres, their blocks' boxes skipped when
 *                   farther than the second nearest found (the noise sample's points whose nearest element
 *                   an edit removed, skelcore/edit/coverage_update.py).
 *
 * Each computes numpy's expressions in numpy's order, so the same bits: (dx^2 + dy^2) + dz^2 with no fused
 * multiply-add (built with -ffp-contract=off), numpy's maximum and minimum (a NaN wins), libm's sqrt; that is
 * also scipy's cKDTree's squared distance (summed over the coordinates in order, the root taken last).
 * Plain C with the buffer protocol (no numpy headers at build time); the entry points release the GIL.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>

/* np.maximum and np.minimum of two doubles: a NaN on either side is the answer */
static inline double np_max(double a, double b) { return (a >= b || a != a) ? a : b; }
static inline double np_min(double a, double b) { return (a <= b || a != a) ? a : b; }

/* near_box(points (n, 3) f64, lo (3,) f64, hi (3,) f64, reach (n,) f64, cover f64, out (n,) u8):
 * bound = max(reach, cover) * (1 + 1e-9) + 1e-12 and loose = bound * (1 + 1e-9) per point; a point is
 * near when each coordinate lies within loose of the box and its distance to the box,
 * sqrt((tx^2 + ty^2) + tz^2) with t = max(max(lo - x, x - hi), 0), is at most bound */
static PyObject *py_near_box(PyObject *self, PyObject *args) {
    Py_buffer pb, lb, hb, rb, ob;
    double cover;
    if (!PyArg_ParseTuple(args, "y*y*y*y*dw*", &pb, &lb, &hb, &rb, &cover, &ob)) return NULL;
    const Py_ssize_t n = rb.len / (Py_ssize_t)sizeof(double);
    int ok = pb.len == 3 * n * (Py_ssize_t)sizeof(double) && rb.len == n * (Py_ssize_t)sizeof(double)
             && lb.len == 3 * (Py_ssize_t)sizeof(double) && hb.len == 3 * (Py_ssize_t)sizeof(double) && ob.len == n;
    if (ok) {
        const double *p = (const double *)pb.buf, *lo = (const double *)lb.buf, *hi = (const double *)hb.buf;
        const double *reach = (const double *)rb.buf;
        uint8_t *out = (uint8_t *)ob.buf;
        Py_BEGIN_ALLOW_THREADS
        for (Py_ssize_t i = 0; i < n; i++) {
            const double *x = p + 3 * i;
            const double bound = np_max(reach[i], cover) * (1 + 1e-9) + 1e-12;
            const double loose = bound * (1 + 1e-9);
            int in = 1;
            for (int k = 0; k < 3; k++) in &= (x[k] >= lo[k] - loose) & (x[k] <= hi[k] + loose);
            if (!in) {
                out[i] = 0;
                continue;
            }
            double total = 0.0;
            for (int k = 0; k < 3; k++) {
                const double t = np_max(np_max(lo[k] - x[k], x[k] - hi[k]), 0.0);
                total += t * t;
            }
            out[i] = sqrt(total) <= bound;
        }
        Py_END_ALLOW_THREADS
    }
    PyBuffer_Release(&pb); PyBuffer_Release(&lb); PyBuffer_Release(&hb); PyBuffer_Release(&rb); PyBuffer_Release(&ob);
    if (!ok) {
        PyErr_SetString(PyExc_ValueError, "near_box: inconsistent array sizes");
        return NULL;
    }
    Py_RETURN_NONE;
}

/* nearest_squared(points (n, 3) f64, centres (m, 3) f64, out (n,) f64): out = min over the centres, in
 * order, of (dx * dx + dy * dy) + dz * dz, from inf */
static PyObject *py_nearest_squared(PyObject *self, PyObject *args) {
    Py_buffer pb, cb, ob;
    if (!PyArg_ParseTuple(args, "y*y*w*", &pb, &cb, &ob)) return NULL;
    const Py_ssize_t n = ob.len / (Py_ssize_t)sizeof(double), m = cb.len / (3 * (Py_ssize_t)sizeof(double));
    int ok = pb.len == 3 * n * (Py_ssize_t)sizeof(double) && cb.len == 3 * m * (Py_ssize_t)sizeof(double)
             && ob.len == n * (Py_ssize_t)sizeof(double);
    if (ok) {
        const double *p = (const double *)pb.buf, *c = (const double *)cb.buf;
        double *out = (double *)ob.buf;
        Py_BEGIN_ALLOW_THREADS
        /* a block of points against every centre (the block's minima stay in registers); a NaN distance,
         * which a plain minimum would skip, is caught by the sum of the block's coordinates and
         * the block done again with numpy's minimum */
        enum { BLOCK = 8 };
        double cs = 0.0;
        for (Py_ssize_t j = 0; j < 3 * m; j++) cs += c[j];
        for (Py_ssize_t i0 = 0; i0 < n; i0 += BLOCK) {
            const Py_ssize_t nb = n - i0 < BLOCK ? n - i0 : BLOCK;
            double best[BLOCK], x[BLOCK], y[BLOCK], z[BLOCK];
            double ps = cs;
            for (Py_ssize_t b = 0; b < BLOCK; b++) {
                const Py_ssize_t i = i0 + (b < nb ? b : 0);
                x[b] = p[3 * i]; y[b] = p[3 * i + 1]; z[b] = p[3 * i + 2];
                best[b] = INFINITY;
                ps += x[b] + y[b] + z[b];
            }
            if (ps - ps == 0.0) {  /* every coordinate finite */
                for (Py_ssize_t j = 0; j < m; j++) {
                    const double cx = c[3 * j], cy = c[3 * j + 1], cz = c[3 * j + 2];
                    for (int b = 0; b < BLOCK; b++) {
                        const double dx = x[b] - cx, dy = y[b] - cy, dz = z[b] - cz;
                        double d = dx * dx;
                        d += dy * dy;
                        d += dz * dz;
                        best[b] = d < best[b] ? d : best[b];
                    }
                }
            } else {
                for (int b = 0; b < BLOCK; b++) {
                    for (Py_ssize_t j = 0; j < m; j++) {
                        const double dx = x[b] - c[3 * j], dy = y[b] - c[3 * j + 1], dz = z[b] - c[3 * j + 2];
                        double d = dx * dx;
                        d += dy * dy;
                        d += dz * dz;
                        best[b] = np_min(best[b], d);
                    }
                }
            }
            for (Py_ssize_t b = 0; b < nb; b++) out[i0 + b] = best[b];
        }
        Py_END_ALLOW_THREADS
    }
    PyBuffer_Release(&pb); PyBuffer_Release(&cb); PyBuffer_Release(&ob);
    if (!ok) {
        PyErr_SetString(PyExc_ValueError, "nearest_squared: inconsistent array sizes");
        return NULL;
    }
    Py_RETURN_NONE;
}

/* nearest_two(points (n, 3) f64, centres (m, 3) f64, d0 (n,) f64, i0 (n,) i64, d1 (n,) f64), m >= 2, every
 * coordinate finite: d0 and d1 the square roots of each point's two least squared distances (a repeat
 * counts twice), i0 a centre at d0.  The centres in blocks of NT_BLOCK in their order (a tree's order keeps
 * a block's box small); the box nearest the point first, then every block whose box's squared distance is
 * below the second least found.  The box's squared distance, rounded as the points' ((t0^2 + t1^2) + t2^2,
 * each t no larger than that coordinate's |dx|), is at most each of its centres' computed one (rounding
 * is monotone), so a block skipped holds nothing under the second least: the two least are exact. */
#define NT_BLOCK 16
static PyObject *py_nearest_two(PyObject *self, PyObject *args) {
    Py_buffer pb, cb, d0b, i0b, d1b;
    if (!PyArg_ParseTuple(args, "y*y*w*w*w*", &pb, &cb, &d0b, &i0b, &d1b)) return NULL;
    const Py_ssize_t n = d0b.len / (Py_ssize_t)sizeof(double), m = cb.len / (3 * (Py_ssize_t)sizeof(double));
    int ok = m >= 2 && pb.len == 3 * n * (Py_ssize_t)sizeof(double) && cb.len == 3 * m * (Py_ssize_t)sizeof(double)
             && d1b.len == d0b.len && i0b.len == n * (Py_ssize_t)sizeof(int64_t);
    const Py_ssize_t nb = (m + NT_BLOCK - 1) / NT_BLOCK;
    double *box = ok ? (double *)malloc((size_t)nb * 7 * sizeof(double)) : NULL;  /* lo, hi, then a lower bound */
    if (ok && box) {
        const double *p = (const double *)pb.buf, *c = (const double *)cb.buf;
        double *d0 = (double *)d0b.buf, *d1 = (double *)d1b.buf;
        int64_t *i0 = (int64_t *)i0b.buf;
        Py_BEGIN_ALLOW_THREADS
        for (Py_ssize_t b = 0; b < nb; b++) {
            double *lo = box + 7 * b, *hi = lo + 3;
            const Py_ssize_t end = (b + 1) * NT_BLOCK < m ? (b + 1) * NT_BLOCK : m;
            for (int k = 0; k < 3; k++) lo[k] = hi[k] = c[3 * b * NT_BLOCK + k];
            for (Py_ssize_t j = b * NT_BLOCK; j < end; j++)
                for (int k = 0; k < 3; k++) {
                    if (c[3 * j + k] < lo[k]) lo[k] = c[3 * j + k];
                    if (c[3 * j + k] > hi[k]) hi[k] = c[3 * j + k];
                }
        }
        for (Py_ssize_t i = 0; i < n; i++) {
            const double *x = p + 3 * i;
            Py_ssize_t first = 0;
            for (Py_ssize_t b = 0; b < nb; b++) {
                const double *lo = box + 7 * b, *hi = lo + 3;
                double lb = 0.0;
                for (int k = 0; k < 3; k++) {
                    double t = lo[k] - x[k], u = x[k] - hi[k];
                    t = t > u ? t : u;
                    t = t > 0.0 ? t : 0.0;
                    lb += t * t;
                }
                box[7 * b + 6] = lb;
                if (lb < box[7 * first + 6]) first = b;
            }
            double s0 = INFINITY, s1 = INFINITY;
            Py_ssize_t at = 0;
            for (Py_ssize_t step = -1; step < nb; step++) {
                const Py_ssize_t b = step < 0 ? first : step;
                if ((step >= 0 && b == first) || !(box[7 * b + 6] < s1)) continue;
                const Py_ssize_t end = (b + 1) * NT_BLOCK < m ? (b + 1) * NT_BLOCK : m;
                for (Py_ssize_t j = b * NT_BLOCK; j < end; j++) {
                    const double dx = x[0] - c[3 * j], dy = x[1] - c[3 * j + 1], dz = x[2] - c[3 * j + 2];
                    double d = dx * dx;
                    d += dy * dy;
                    d += dz * dz;
                    if (d < s0) {
                        s1 = s0;
                        s0 = d;
                        at = j;
                    } else if (d < s1) {
                        s1 = d;
                    }
                }
            }
            d0[i] = sqrt(s0);
            d1[i] = sqrt(s1);
            i0[i] = at;
        }
        Py_END_ALLOW_THREADS
    }
    free(box);
    PyBuffer_Release(&pb); PyBuffer_Release(&cb); PyBuffer_Release(&d0b); PyBuffer_Release(&i0b); PyBuffer_Release(&d1b);
    if (!ok) {
        PyErr_SetString(PyExc_ValueError, "nearest_two: inconsistent array sizes or fewer than two centres");
        return NULL;
    }
    if (!box) return PyErr_NoMemory();
    Py_RETURN_NONE;
}

static PyMethodDef methods[] = {
    {"near_box", py_near_box, METH_VARARGS, "The points within a per-point bound of a box, as numpy computes it."},
    {"nearest_squared", py_nearest_squared, METH_VARARGS, "Each point's squared distance to its nearest centre."},
    {"nearest_two", py_nearest_two, METH_VARARGS, "Each point's two nearest centres' distances, and the nearest."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_point_passes",
                                    "Compiled passes over points against a box or a few centres (docs/performance.md, section 6.10).",
                                    -1, methods};

PyMODINIT_FUNC PyInit__point_passes(void) { return PyModule_Create(&module); }
