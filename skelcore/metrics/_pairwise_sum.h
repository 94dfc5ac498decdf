/* numpy's pairwise summation of n contiguous doubles (its umath loops' pairwise_sum: blocks of 128, eight
 * running sums each), so a compiled mean gives numpy's bits; shared by _centroids.c and _rings.c.
 * Include after Python.h (Py_ssize_t). */
#ifndef SKELCORE_PAIRWISE_SUM_H
#define SKELCORE_PAIRWISE_SUM_H

#define PW_BLOCKSIZE 128

static double pairwise_sum(const double *a, Py_ssize_t n) {
    if (n < 8) {
        double res = 0.0;
        for (Py_ssize_t i = 0; i < n; i++) res += a[i];
        return res;
    }
    if (n <= PW_BLOCKSIZE) {
        double r[8];
        Py_ssize_t i;
        for (int j = 0; j < 8; j++) r[j] = a[j];
        for (i = 8; i < n - (n % 8); i += 8)
            for (int j = 0; j < 8; j++) r[j] += a[i + j];
        double res = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]));
        for (; i < n; i++) res += a[i];
        return res;
    }
    Py_ssize_t n2 = n / 2;
    n2 -= n2 % 8;
    return pairwise_sum(a, n2) + pairwise_sum(a + n2, n - n2);
}

#endif
