/* ref_bases.h - the Bezier control points of a segment given in another
   basis (hairobb_basis), from the bases' matrices in double: the tests'
   reference for hairobb.h's conversion (tests/test_bases.c, and the moving
   segments of tests/test_motion.c). Include after hairobb.h. */
#ifndef REF_BASES_H
#define REF_BASES_H

/* Bezier control points of one segment, in double from the basis matrix
   (rows: Bezier points; columns: the basis' points), then rounded. */
static inline void ref_bezier_from_basis(hairobb_basis basis, const float *p, const float *t, float out[16])
{
    static const double bspline[4][4] = {{1 / 6.0, 4 / 6.0, 1 / 6.0, 0}, {0, 4 / 6.0, 2 / 6.0, 0}, {0, 2 / 6.0, 4 / 6.0, 0},
                                         {0, 1 / 6.0, 4 / 6.0, 1 / 6.0}};
    static const double catmull_rom[4][4] = {{0, 1, 0, 0}, {-1 / 6.0, 1, 1 / 6.0, 0}, {0, 1 / 6.0, 1, -1 / 6.0}, {0, 0, 1, 0}};
    static const double linear[4][2] = {{1, 0}, {2 / 3.0, 1 / 3.0}, {1 / 3.0, 2 / 3.0}, {0, 1}};
    int row, col, c;
    for (row = 0; row < 4; ++row) {
        for (c = 0; c < 4; ++c) {
            double v = 0.0;
            if (basis == HAIROBB_BASIS_BSPLINE || basis == HAIROBB_BASIS_CATMULL_ROM) {
                for (col = 0; col < 4; ++col)
                    v += (basis == HAIROBB_BASIS_BSPLINE ? bspline : catmull_rom)[row][col] * (double)p[4 * col + c];
            } else if (basis == HAIROBB_BASIS_LINEAR) {
                v = linear[row][0] * (double)p[c] + linear[row][1] * (double)p[4 + c];
            } else { /* Hermite: P0, P0 + T0/3, P1 - T1/3, P1 */
                v = row == 0 ? p[c] : row == 1 ? (double)p[c] + t[c] / 3.0 : row == 2 ? (double)p[4 + c] - t[4 + c] / 3.0 : p[4 + c];
            }
            out[4 * row + c] = (float)(c == 3 && v < 0.0 ? 0.0 : v);
        }
    }
}

#endif
