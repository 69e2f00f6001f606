/*
 * The OpenCV door of the KLT front end (klt.c): image pyramids built into buffers kept from
 * frame to frame, pyramidal Lucas-Kanade between the last two of them, and FAST corners.
 * Plain C; every function catches every exception and returns 0 or -errno.
 */
#ifndef MVOD_KLT_SHIM_H
#define MVOD_KLT_SHIM_H

#include <stdint.h>

#include "mvod/image.h"

#ifdef __cplusplus
extern "C" {
#endif

struct mvod_klt_cv;

/*
 * Pyramids of levels + 1 levels for width x height grey frames, bordered for Lucas-Kanade
 * windows of up to win x win pixels, tracked with at most iterations steps per level, stopping
 * at a step under eps_px; FAST keeps at most fast_cap corners per frame.
 */
int mvod_klt_cv_create(int width, int height, int win, int levels, int iterations, double eps_px,
		       int fast_cap, struct mvod_klt_cv **out);
void mvod_klt_cv_destroy(struct mvod_klt_cv *k);

/* grey (borrowed for the call) becomes the newest pyramid; the one before becomes the older. */
int mvod_klt_cv_push(struct mvod_klt_cv *k, const struct mvod_image *grey);

/*
 * Lucas-Kanade for n points (x, y pairs, pixels) from the older pyramid to the newest one
 * (backward = 0) or back (backward = 1), with a win x win pixel window (at most create's) on
 * pyramid levels levels down to 0 (at most create's). to[2n] holds the initial guesses and
 * receives the tracked positions; ok[n] gets 1 where the tracker converged.
 */
int mvod_klt_cv_flow(struct mvod_klt_cv *k, int backward, int win, int levels, const float *from,
		     float *to, int n, uint8_t *ok);

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
