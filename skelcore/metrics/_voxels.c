/* Compiled lattice rays of the voxelized interior (docs/diagnostics.md "Cycles", docs/performance.md 6.7):
 * per voxel, how many of the 26 lattice directions d meet a surface voxel at v + t d for some t >= 1.
 *
 * The same count as the sweeps of skelcore.diagnostics.interior._ray_hits, one direction after the other:
 * hit[v] = surface[v + d] | hit[v + d] (False where v + d leaves the grid), the voxels visited so that
 * v + d is done before v (each axis against d's sign on it).  The rows along the last axis are contiguous:
 * a row of hits reads one other row of the surface and of the hits (vectorized), except along (0, 0, +-1),
 * a running OR along the row.  Integer counts: the same values bit for bit.
 *
 * Plain C with the buffer protocol (no numpy headers at build time); the entry point releases the GIL.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* one direction (di, dj, dk): hit per voxel, added to count */
static void sweep(const uint8_t *restrict g, uint8_t *restrict hit, uint8_t *restrict count,
                  Py_ssize_t nx, Py_ssize_t ny, Py_ssize_t nz, int di, int dj, int dk) {
    for (Py_ssize_t ii = 0; ii < nx; ii++) {
        const Py_ssize_t i = di > 0 ? nx - 1 - ii : ii;
        for (Py_ssize_t jj = 0; jj < ny; jj++) {
            const Py_ssize_t j = dj > 0 ? ny - 1 - jj : jj;
            uint8_t *h = hit + (i * ny + j) * nz;
            uint8_t *c = count + (i * ny + j) * nz;
            const Py_ssize_t i2 = i + di, j2 = j + dj;
            if (i2 < 0 || i2 >= nx || j2 < 0 || j2 >= ny) {
                memset(h, 0, (size_t)nz);
                continue;
            }
            const uint8_t *gs = g + (i2 * ny + j2) * nz;
            if (di == 0 && dj == 0) {  /* along the row: each voxel reads the next one's answer */
                if (dk > 0) {
                    h[nz - 1] = 0;
                    for (Py_ssize_t k = nz - 2; k >= 0; k--) h[k] = gs[k + 1] | h[k + 1];
                } else {
                    h[0] = 0;
                    for (Py_ssize_t k = 1; k < nz; k++) h[k] = gs[k - 1] | h[k - 1];
                }
            } else {  /* another row, done before this one */
                const uint8_t *restrict hs = hit + (i2 * ny + j2) * nz;
                const Py_ssize_t lo = dk < 0 ? 1 : 0, hi = dk > 0 ? nz - 1 : nz;
                if (lo > 0) h[0] = 0;
                if (hi < nz) h[nz - 1] = 0;
                for (Py_ssize_t k = lo; k < hi; k++) {
                    const uint8_t v = gs[k + dk] | hs[k + dk];
                    h[k] = v;
                    c[k] += v;
                }
                continue;
            }
            for (Py_ssize_t k = 0; k < nz; k++) c[k] += h[k];
        }
    }
}

/* hits(surface (nx, ny, nz) u8 0/1 C order, nx, ny, nz, count out (nx, ny, nz) u8): count[v] += the
 * directions whose ray from v meets the surface; surface voxels hold 0 or 1 */
static PyObject *py_hits(PyObject *self, PyObject *args) {
    Py_buffer gb, cb;
    Py_ssize_t nx, ny, nz;
    if (!PyArg_ParseTuple(args, "y*nnnw*", &gb, &nx, &ny, &nz, &cb)) return NULL;
    const Py_ssize_t n = nx * ny * nz;
    if (nx < 0 || ny < 0 || nz < 0 || (nx && ny && nz && n / nx / ny != nz) || gb.len != n || cb.len != n) {
        PyBuffer_Release(&gb); PyBuffer_Release(&cb);
        PyErr_SetString(PyExc_ValueError, "hits: the grids' sizes do not match nx * ny * nz");
        return NULL;
    }
    uint8_t *hit = (uint8_t *)malloc((size_t)n + 1);
    if (hit && n > 0) {
        Py_BEGIN_ALLOW_THREADS
        for (int a = -1; a <= 1; a++)
            for (int b = -1; b <= 1; b++)
                for (int d = -1; d <= 1; d++)
                    if (a || b || d)
                        sweep((const uint8_t *)gb.buf, hit, (uint8_t *)cb.buf, nx, ny, nz, a, b, d);
        Py_END_ALLOW_THREADS
    }
    free(hit);
    PyBuffer_Release(&gb); PyBuffer_Release(&cb);
    if (!hit) return PyErr_NoMemory();
    Py_RETURN_NONE;
}

static PyMethodDef methods[] = {
    {"hits", py_hits, METH_VARARGS, "Per voxel, the lattice directions whose ray meets the surface voxels."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_lattice_rays",
                                    "Compiled lattice rays of the voxelized interior (docs/performance.md, section 6.7).",
                                    -1, methods};

PyMODINIT_FUNC PyInit__lattice_rays(void) { return PyModule_Create(&module); }
