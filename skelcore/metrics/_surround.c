/* Compiled first pass of the surround test of an opening's fill (docs/metrics.md 6.1; design and numbers:
 * docs/performance.md, "The openings' surround test").
 *
 * A grid point is surrounded by a rim when the largest angle between consecutive directions to the rim's
 * samples is below ``angle`` (skelcore.scan.boundary.largest_angle_gap: arctan2 of every direction, a
 * sort, the gaps).  Here each direction only marks one of NBINS equal angular bins, its angle from a
 * polynomial approximation of atan (error below APPROX_ERR); R, the longest circular run of empty bins,
 * bounds the largest gap G:  R w - 2 e <= G <= (R + 2) w + 2 e  (w the bin width, e = APPROX_ERR).  A point
 * with (R + 2) w + 2 e < angle is surrounded whatever the exact angles, one with R w - 2 e > angle is not,
 * and the few between are left to the exact test (state -1), so the answers are the exact test's.
 *
 * Plain C with the buffer protocol (no numpy headers at build time); the entry point releases the GIL.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#include <stdint.h>
#include <string.h>

#define NBINS 256
/* the error allowed approx_angle: over twice its largest, 0.0015 rad (Rajan et al. 2006; the tests sweep it) */
#define APPROX_ERR 0.004

static const double PI = 3.14159265358979323846;

/* atan2(y, x) within 0.0015 rad: atan(t) ~ pi/4 t - t (t - 1) (0.2447 + 0.0663 t) on [0, 1], by octant;
 * branch-free (the rim's samples come in no angular order); +-pi for y = +-0 and x < 0 are one bin */
static inline double approx_angle(double x, double y) {
    const double ax = fabs(x), ay = fabs(y);
    const double lo = ax < ay ? ax : ay, hi = ax < ay ? ay : ax;
    const double t = lo / hi;
    const double a = 0.25 * PI * t - t * (t - 1.0) * (0.2447 + 0.0663 * t);
    const double steep = (double)(ay > ax), back = (double)(x < 0.0);
    const double b = steep * (0.5 * PI) + (1.0 - 2.0 * steep) * a;
    return copysign(back * PI + (1.0 - 2.0 * back) * b, y);
}

/* surround(ring (R,2) f64, grid (G,2) f64, angle, state out (G,) i8): 1 surrounded, 0 not, -1 undecided */
static PyObject *py_surround(PyObject *self, PyObject *args) {
    Py_buffer rb, gb, sb;
    double angle;
    if (!PyArg_ParseTuple(args, "y*y*dw*", &rb, &gb, &angle, &sb)) return NULL;
    const double *ring = (const double *)rb.buf, *grid = (const double *)gb.buf;
    int8_t *state = (int8_t *)sb.buf;
    const Py_ssize_t nr = rb.len / (Py_ssize_t)(2 * sizeof(double));
    const Py_ssize_t ng = gb.len / (Py_ssize_t)(2 * sizeof(double));
    const int ok = rb.len == nr * (Py_ssize_t)(2 * sizeof(double)) && gb.len == ng * (Py_ssize_t)(2 * sizeof(double))
                   && sb.len == ng;
    if (ok) {
        Py_BEGIN_ALLOW_THREADS
        const double w = 2.0 * PI / NBINS, scale = NBINS / (2.0 * PI);
        unsigned char used[NBINS];
        int finite_ring = 1;
        for (Py_ssize_t j = 0; j < 2 * nr; j++) finite_ring &= isfinite(ring[j]) != 0;
        for (Py_ssize_t i = 0; i < ng; i++) {
            const double gu = grid[2 * i], gv = grid[2 * i + 1];
            if (!(finite_ring && isfinite(gu) && isfinite(gv))) { state[i] = -1; continue; }
            memset(used, 0, sizeof used);
            for (Py_ssize_t j = 0; j < nr; j++) {
                const double x = ring[2 * j] - gu, y = ring[2 * j + 1] - gv;
                if (x == 0.0 && y == 0.0) continue;  /* a sample at the point itself has no direction */
                /* the angle from -pi is in [0, 2 pi] (approx_angle stays in [-pi, pi]): truncation floors it */
                int b = (int)((approx_angle(x, y) + PI) * scale);
                used[b >= NBINS ? b - NBINS : b] = 1;
            }
            int first = -1;
            for (int b = 0; b < NBINS; b++) if (used[b]) { first = b; break; }
            int longest = NBINS, run = 0;
            if (first >= 0) {
                longest = 0;
                for (int s = 1; s <= NBINS; s++) {  /* round the circle from the first used bin back to it */
                    if (used[(first + s) % NBINS]) { if (run > longest) longest = run; run = 0; }
                    else run++;
                }
            }
            if ((longest + 2) * w + 2.0 * APPROX_ERR < angle) state[i] = 1;
            else if (longest * w - 2.0 * APPROX_ERR > angle) state[i] = 0;
            else state[i] = -1;
        }
        Py_END_ALLOW_THREADS
    }
    PyBuffer_Release(&rb); PyBuffer_Release(&gb); PyBuffer_Release(&sb);
    if (!ok) {
        PyErr_SetString(PyExc_ValueError, "surround: ring (R, 2) and grid (G, 2) float64, state (G,) int8");
        return NULL;
    }
    Py_RETURN_NONE;
}

/* approx_angles(x (n,) f64, y (n,) f64, out (n,) f64): the first pass's angles, for its tests */
static PyObject *py_approx_angles(PyObject *self, PyObject *args) {
    Py_buffer xb, yb, ob;
    if (!PyArg_ParseTuple(args, "y*y*w*", &xb, &yb, &ob)) return NULL;
    const Py_ssize_t n = ob.len / (Py_ssize_t)sizeof(double);
    const int ok = xb.len == ob.len && yb.len == ob.len;
    if (ok) {
        const double *x = (const double *)xb.buf, *y = (const double *)yb.buf;
        double *out = (double *)ob.buf;
        for (Py_ssize_t i = 0; i < n; i++) out[i] = approx_angle(x[i], y[i]);
    }
    PyBuffer_Release(&xb); PyBuffer_Release(&yb); PyBuffer_Release(&ob);
    if (!ok) {
        PyErr_SetString(PyExc_ValueError, "approx_angles: x, y and out of one length, float64");
        return NULL;
    }
    Py_RETURN_NONE;
}

static PyMethodDef methods[] = {
    {"surround", py_surround, METH_VARARGS, "Per grid point: surrounded (1), not (0) or undecided (-1)."},
    {"approx_angles", py_approx_angles, METH_VARARGS, "The first pass's approximate atan2(y, x)."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_surround",
                                    "Compiled first pass of the openings' surround test (docs/metrics.md, section 6.1).",
                                    -1, methods};

PyMODINIT_FUNC PyInit__surround(void) { return PyModule_Create(&module); }
