/* The inverse of a 4 x 4 matrix in double (mat4d.h). */
#include "common/mat4d.h"

#include <math.h>

bool mat4d_invert(const double m[16], double out[16])
{
    double a[4][8];
    for (int i = 0; i < 4; i++) {
        for (int j = 0; j < 4; j++) {
            a[i][j] = m[4 * i + j];
            a[i][j + 4] = i == j ? 1.0 : 0.0;
        }
    }
    for (int c = 0; c < 4; c++) {
        int piv = c;
        for (int i = c + 1; i < 4; i++) {
            if (fabs(a[i][c]) > fabs(a[piv][c]))
                piv = i;
        }
        if (a[piv][c] == 0.0)
            return false;
        for (int j = 0; j < 8; j++) {
            double x = a[c][j];
            a[c][j] = a[piv][j];
            a[piv][j] = x;
        }
        double inv = 1.0 / a[c][c];
        for (int j = 0; j < 8; j++)
            a[c][j] *= inv;
        for (int i = 0; i < 4; i++) {
            if (i == c)
                continue;
            double f = a[i][c];
            for (int j = 0; j < 8; j++)
                a[i][j] -= f * a[c][j];
        }
    }
    for (int i = 0; i < 4; i++) {
        for (int j = 0; j < 4; j++)
            out[4 * i + j] = a[i][j + 4];
    }
    return true;
}
