/*
 * common/mat4d: the inverse of a 4 x 4 matrix in double, for the places where a float inverse
 * loses too much (a perspective projection with far / near ~1e5 and the rays made from it).
 * Must not know: anything above common/.
 */
#ifndef ANVIL_COMMON_MAT4D_H
#define ANVIL_COMMON_MAT4D_H

#include <stdbool.h>

/* OUT = M^-1 by Gauss-Jordan elimination with partial pivoting.  M and OUT have the same
 * layout, row- or column-major alike (the inverse of the transpose is the transpose of the
 * inverse).  False, OUT untouched, when M is singular. */
bool mat4d_invert(const double m[16], double out[16]);

#endif
