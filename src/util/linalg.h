/*
 * Small dense helpers shared by the VO (motion), evaluation (Umeyama) and tests: a median and
 * the rotation nearest to a correlation matrix (svd_shim.h's SVD). Matrices are 3x3 row-major.
 */
#ifndef MVOD_UTIL_LINALG_H
#define MVOD_UTIL_LINALG_H

#ifdef __cplusplus
extern "C" {
#endif

/* Median of v[0..n) (reorders v); n > 0. */
double mvod_median(double *v, int n);

/*
 * The rotation R maximising trace(R^T C) for a correlation C = sum dst src^T (Kabsch and
 * Umeyama share it), with trace = trace(D S) of the SVD for Umeyama's scale (may be NULL).
 */
int mvod_nearest_rotation(const double C[9], double R[9], double *trace);

#ifdef __cplusplus
}
#endif

#endif
