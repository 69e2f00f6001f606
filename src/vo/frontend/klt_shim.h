/*
 * The OpenCV door of the KLT front end (klt.c): image pyramids (OpenCV's levels, lk.c's Scharr
 * derivatives) built into buffers kept from frame to frame, for lk.c's Lucas-Kanade, and FAST
 * corners.
 * Plain C; every function catches every exception and returns 0 or -errno.
 */
#ifndef MVOD_KLT_SHIM_H
#define MVOD_KLT_SHIM_H

#include <stdint.h>

#include "lk.h"
#include "mvod/image.h"

#ifdef __cplusplus
extern "C" {
#endif

struct mvod_klt_cv;

/*
 * Pyramids of levels + 1 levels for width x height grey frames, with borders of win pixels
 * (BORDER_REFLECT_101; the derivatives' zero); FAST keeps at most fast_cap corners per frame.
 * Every buffer is sized here: a push allocates nothing after the second frame.
 */
int mvod_klt_cv_create(int width, int height, int win, int levels, int fast_cap,
		       struct mvod_klt_cv **out);
void mvod_klt_cv_destroy(struct mvod_klt_cv *k);

/* grey (borrowed for the call) becomes the newest pyramid; the one before becomes the older. */
int mvod_klt_cv_push(struct mvod_klt_cv *k, const struct mvod_image *grey);

/*
 * The older (newest = 0) or newest pyramid's levels, at most max of them, into out (borrowed
 * until the next push), for lk.h's tracker; returns how many levels it has (0: none yet).
 */
int mvod_klt_cv_levels(const struct mvod_klt_cv *k, int newest, struct mvod_lk_level *out,
		       int max);

/*
 * FAST corners (non-maximum suppressed) of grey above threshold grey levels: xy[2 * fast_cap]
 * receives pixel positions, *n their count (the first fast_cap OpenCV found).
 */
int mvod_klt_cv_fast(struct mvod_klt_cv *k, const struct mvod_image *grey, int threshold,
		     float *xy, int *n);

/*
 * The same on level level (at most create's) of the newest pyramid, positions in level 0's
 * pixels (times 2^level).
 */
int mvod_klt_cv_fast_level(struct mvod_klt_cv *k, int level, int threshold, float *xy, int *n);

#ifdef __cplusplus
}
#endif

#endif
