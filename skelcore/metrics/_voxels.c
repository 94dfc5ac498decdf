/* Compiled passes over the voxelized interior's grid (docs/diagnostics.md "Cycles", docs/performance.md 6.7):
 * the lattice rays, the cells of its cubical complex with its 26-connected parts (its Betti numbers), and
 * its holes filled.  Every answer is a count or a voxel: the same as the numpy / scipy.ndimage passes of
 * skelcore.diagnostics.interior they replace, bit for bit.
 *
 * The lattice rays: per voxel, how many of the 26 lattice directions d meet a surface voxel at v + t d
 * for some t >= 1.
 *
 * The same count as the sweeps of skelcore.diagnostics.interior._ray_hits, one direction after the other:
 * hit[v] = surface[v + d] | hit[v + d] (False where v + d leaves the grid), the voxels visited so that
 * v + d is done before v (each axis against d's sign on it).  The rows along the last axis are contiguous:
 * a row of hits reads one other row of the surface and of the hits (vectorized), except along (0, 0, +-1),
 * a running OR along the row.
 *
 * Plain C with the buffer protocol (no numpy headers at build time); the entry point releases the GIL.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "_union_find.h"

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

/* cells(solid (nx, ny, nz) u8 0/1 with an empty border, nx, ny, nz) -> (cubes, faces, edges, vertices) of
 * the union of its closed unit cubes: a face normal to axis a lies between the two cubes beside it along a,
 * an edge along a between the 4 cubes around it, a vertex between 8 (each counted where one of them is
 * solid; the border keeps every cell inside the grid) */
static PyObject *py_cells(PyObject *self, PyObject *args) {
    Py_buffer sb;
    Py_ssize_t nx, ny, nz;
    if (!PyArg_ParseTuple(args, "y*nnn", &sb, &nx, &ny, &nz)) return NULL;
    if (nx < 2 || ny < 2 || nz < 2 || nx * ny * nz != sb.len) {
        PyBuffer_Release(&sb);
        PyErr_SetString(PyExc_ValueError, "cells: the grid's size does not match nx * ny * nz (each at least 2)");
        return NULL;
    }
    const uint8_t *s = (const uint8_t *)sb.buf;
    long long cubes = 0, faces = 0, edges = 0, verts = 0;
    const Py_ssize_t sx = ny * nz, sy = nz;
    Py_BEGIN_ALLOW_THREADS
    for (Py_ssize_t i = 0; i < nx; i++)
        for (Py_ssize_t j = 0; j < ny; j++) {
            const uint8_t *r = s + i * sx + j * sy;
            for (Py_ssize_t k = 0; k < nz; k++) {
                cubes += r[k];
                /* the cells whose cubes are v and its neighbours ahead: at v, v + x, v + y, ... */
                const int ax = i + 1 < nx, ay = j + 1 < ny, az = k + 1 < nz;
                const uint8_t c0 = r[k];
                if (ax) faces += c0 | r[k + sx];
                if (ay) faces += c0 | r[k + sy];
                if (az) faces += c0 | r[k + 1];
                if (ay && az) edges += c0 | r[k + sy] | r[k + 1] | r[k + sy + 1];
                if (ax && az) edges += c0 | r[k + sx] | r[k + 1] | r[k + sx + 1];
                if (ax && ay) edges += c0 | r[k + sx] | r[k + sy] | r[k + sx + sy];
                if (ax && ay && az)
                    verts += c0 | r[k + 1] | r[k + sy] | r[k + sy + 1] | r[k + sx] | r[k + sx + 1] | r[k + sx + sy]
                             | r[k + sx + sy + 1];
            }
        }
    Py_END_ALLOW_THREADS
    PyBuffer_Release(&sb);
    return Py_BuildValue("LLLL", cubes, faces, edges, verts);
}

/* parts(solid (nx, ny, nz) u8 0/1, nx, ny, nz) -> its 26-connected parts (scipy.ndimage.label's count with
 * the 3 x 3 x 3 structure): a union-find of every solid voxel with its 13 solid neighbours behind it */
static PyObject *py_parts(PyObject *self, PyObject *args) {
    Py_buffer sb;
    Py_ssize_t nx, ny, nz;
    if (!PyArg_ParseTuple(args, "y*nnn", &sb, &nx, &ny, &nz)) return NULL;
    const Py_ssize_t n = nx * ny * nz;
    if (nx < 0 || ny < 0 || nz < 0 || n != sb.len || n >= INT32_MAX) {
        PyBuffer_Release(&sb);
        PyErr_SetString(PyExc_ValueError, "parts: the grid's size does not match nx * ny * nz");
        return NULL;
    }
    const uint8_t *s = (const uint8_t *)sb.buf;
    int32_t *parent = (int32_t *)malloc(((size_t)n + 1) * sizeof(int32_t));
    long long count = 0;
    if (parent) {
        Py_BEGIN_ALLOW_THREADS
        for (Py_ssize_t i = 0; i < nx; i++)
            for (Py_ssize_t j = 0; j < ny; j++)
                for (Py_ssize_t k = 0; k < nz; k++) {
                    const Py_ssize_t v = (i * ny + j) * nz + k;
                    if (!s[v]) continue;
                    parent[v] = (int32_t)v;
                    count++;
                    for (int di = -1; di <= 0; di++)
                        for (int dj = -1; dj <= 1; dj++)
                            for (int dk = -1; dk <= 1; dk++) {
                                /* the 13 neighbours before v in C order */
                                if (di == 0 && (dj > 0 || (dj == 0 && dk >= 0))) continue;
                                const Py_ssize_t a = i + di, b = j + dj, c = k + dk;
                                if (a < 0 || b < 0 || b >= ny || c < 0 || c >= nz) continue;
                                const Py_ssize_t w = (a * ny + b) * nz + c;
                                if (!s[w]) continue;
                                int32_t x = root_of(parent, (int32_t)v), y = root_of(parent, (int32_t)w);
                                if (x == y) continue;
                                if (x < y) parent[y] = x;
                                else parent[x] = y;
                                count--;
                            }
                }
        Py_END_ALLOW_THREADS
    }
    free(parent);
    PyBuffer_Release(&sb);
    if (!parent) return PyErr_NoMemory();
    return PyLong_FromLongLong(count);
}

/* fill(mask (nx, ny, nz) u8 0/1, nx, ny, nz, out (nx, ny, nz) u8): out = the mask with its holes filled
 * (scipy.ndimage.binary_fill_holes): 1 except where an empty voxel is face-connected through empty
 * voxels to the grid's border.  The grid is copied inside two layers, an empty one around it and a wall
 * around that, and flooded from the empty layer: no voxel's neighbour leaves the copy, no index is divided */
static PyObject *py_fill(PyObject *self, PyObject *args) {
    Py_buffer mb, ob;
    Py_ssize_t nx, ny, nz;
    if (!PyArg_ParseTuple(args, "y*nnnw*", &mb, &nx, &ny, &nz, &ob)) return NULL;
    const Py_ssize_t n = nx * ny * nz;
    if (nx < 0 || ny < 0 || nz < 0 || n != mb.len || n != ob.len) {
        PyBuffer_Release(&mb); PyBuffer_Release(&ob);
        PyErr_SetString(PyExc_ValueError, "fill: the grids' sizes do not match nx * ny * nz");
        return NULL;
    }
    const Py_ssize_t px = nx + 4, py = ny + 4, pz = nz + 4, pn = px * py * pz;
    const uint8_t *m = (const uint8_t *)mb.buf;
    uint8_t *out = (uint8_t *)ob.buf;
    enum { EMPTY = 0, FULL = 1, WALL = 2, REACHED = 3 };
    uint8_t *b = (uint8_t *)malloc((size_t)pn);
    Py_ssize_t *stack = (Py_ssize_t *)malloc((size_t)pn * sizeof(Py_ssize_t));
    if (b && stack) {
        Py_BEGIN_ALLOW_THREADS
        memset(b, EMPTY, (size_t)pn);
        for (Py_ssize_t i = 0; i < px; i++)
            for (Py_ssize_t j = 0; j < py; j++) {
                uint8_t *r = b + (i * py + j) * pz;
                if (i == 0 || j == 0 || i == px - 1 || j == py - 1) {
                    memset(r, WALL, (size_t)pz);
                    continue;
                }
                r[0] = r[pz - 1] = WALL;
                if (i >= 2 && j >= 2 && i < nx + 2 && j < ny + 2)
                    memcpy(r + 2, m + ((i - 2) * ny + (j - 2)) * nz, (size_t)nz);
            }
        const Py_ssize_t step[6] = {py * pz, -py * pz, pz, -pz, 1, -1};
        Py_ssize_t top = 0;
        const Py_ssize_t start = (1 * py + 1) * pz + 1;  /* a voxel of the empty layer */
        b[start] = REACHED;
        stack[top++] = start;
        while (top > 0) {
            const Py_ssize_t v = stack[--top];
            for (int t = 0; t < 6; t++) {
                const Py_ssize_t w = v + step[t];
                if (b[w] == EMPTY) {
                    b[w] = REACHED;
                    stack[top++] = w;
                }
            }
        }
        for (Py_ssize_t i = 0; i < nx; i++)
            for (Py_ssize_t j = 0; j < ny; j++) {
                const uint8_t *r = b + ((i + 2) * py + (j + 2)) * pz + 2;
                uint8_t *o = out + (i * ny + j) * nz;
                for (Py_ssize_t k = 0; k < nz; k++) o[k] = r[k] != REACHED;
            }
        Py_END_ALLOW_THREADS
    }
    free(b);
    free(stack);
    PyBuffer_Release(&mb); PyBuffer_Release(&ob);
    if (!b || !stack) return PyErr_NoMemory();
    Py_RETURN_NONE;
}

static PyMethodDef methods[] = {
    {"hits", py_hits, METH_VARARGS, "Per voxel, the lattice directions whose ray meets the surface voxels."},
    {"cells", py_cells, METH_VARARGS, "Cubes, faces, edges and vertices of the union of a grid's closed cubes."},
    {"parts", py_parts, METH_VARARGS, "The 26-connected parts of a grid's voxels."},
    {"fill", py_fill, METH_VARARGS, "A grid's voxels with their holes filled."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_voxels",
                                    "Compiled passes over the voxelized interior's grid (docs/performance.md, section 6.7).",
                                    -1, methods};

PyMODINIT_FUNC PyInit__voxels(void) { return PyModule_Create(&module); }
