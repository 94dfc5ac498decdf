/* The root of a node in a union-find forest (``parent[v] == v`` at a root), halving the path on the way;
 * shared by _components.c and _voxels.c. Include after <stdint.h>. */
#ifndef SKELCORE_UNION_FIND_H
#define SKELCORE_UNION_FIND_H

static inline int32_t root_of(int32_t *parent, int32_t v) {
    while (parent[v] != v) {
        parent[v] = parent[parent[v]];  /* path halving */
        v = parent[v];
    }
    return v;
}

#endif
