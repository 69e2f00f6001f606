/* The 3x3 singular value decomposition, through OpenCV. Plain C; exceptions become -errno. */
#ifndef MVOD_UTIL_SVD_SHIM_H
#define MVOD_UTIL_SVD_SHIM_H

#ifdef __cplusplus
extern "C" {
#endif

/* A = U diag(S) Vt (3x3 row-major), S descending (OpenCV's SVD). 0 or -errno. */
int mvod_svd3(const double A[9], double U[9], double S[3], double Vt[9]);

#ifdef __cplusplus
}
#endif

#endif
