/*
 * Pyramidal Lucas-Kanade on OpenCV's pyramids (klt_shim.cpp builds them): OpenCV's tracker
 * (calcOpticalFlowPyrLK) step for step, in its fixed point (bilinear weights of 14 bits,
 * intensities with 5 fractional bits, the template and its Scharr derivatives interpolated at
 * the point, the same stopping rules and minimum eigenvalue test), but with every window row in
 * whole vectors of 8 pixels (the lanes past the window add zero), where OpenCV's tracker takes
 * the pixels past the last multiple of 4 or 8 one at a time in scalar code: on 9 and 21 pixel
 * windows that was most of its instructions (BENCHMARKS.md, "Own Lucas-Kanade"). Tracks agree
 * with OpenCV's to 1e-4 px; the sums are added in another order.
 *
 * Each point's flow is the same whatever else is passed (points are independent). The SSE2 and
 * AVX2 (x86-64) and NEON (arm64) paths compute the same integers as the plain C and add them as
 * floats in the same order, so results do not depend on the machine's SIMD
 * (tests/unit/test_lk.c compares them; make cross-arm64 runs it on arm64).
 */
#ifndef MVOD_VO_LK_H
#define MVOD_VO_LK_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Widest window: MVOD_LK_MAX_WIN x MVOD_LK_MAX_WIN pixels. */
#define MVOD_LK_MAX_WIN 32

/* One pyramid level as buildOpticalFlowPyramid keeps it (with derivatives). */
struct mvod_lk_level {
	const uint8_t *img;   /* pixel (0, 0); rows readable from -border to w + border - 1 */
	const int16_t *deriv; /* Scharr (d/dx, d/dy) pairs of pixel (0, 0), the same border */
	ptrdiff_t stride;     /* bytes from one row of img to the next */
	ptrdiff_t dstride;    /* int16_t from one row of deriv to the next */
	int w, h, border;
};

/*
 * The tracker's settings: a win x win window (3 .. MVOD_LK_MAX_WIN) on levels levels .. 0, at
 * most iterations steps a level, stopping at a step under eps_px pixels (OpenCV's
 * TermCriteria(COUNT | EPS, iterations, eps_px) and its minimum eigenvalue 1e-4).
 */
struct mvod_lk_params {
	int win, levels, iterations;
	float eps_px;
};

/*
 * Lucas-Kanade for n points from pyramid I (from[2n], pixels of level 0) into pyramid J: to[2n]
 * holds the initial guesses and receives the tracked positions; ok[n] gets 1 where the tracker
 * converged inside the image, else 0. I and J: levels + 1 levels each. Runs the fastest path
 * the machine has.
 */
void mvod_lk_flow(const struct mvod_lk_level *I, const struct mvod_lk_level *J,
		  const struct mvod_lk_params *p, const float *from, float *to, int n, uint8_t *ok);

/*
 * The paths, each giving exactly the plain C's results: PLAIN; VECTOR, SSE2 on x86-64, NEON on
 * arm64 (else the plain C); AVX2, on x86-64 machines that have it (chosen at run time).
 */
enum mvod_lk_path { MVOD_LK_PLAIN, MVOD_LK_VECTOR, MVOD_LK_AVX2 };

/* mvod_lk_flow on one path; -ENOTSUP (nothing done) when this build or machine lacks it. */
int mvod_lk_flow_on(enum mvod_lk_path path, const struct mvod_lk_level *I,
		    const struct mvod_lk_level *J, const struct mvod_lk_params *p,
		    const float *from, float *to, int n, uint8_t *ok);

/*
 * Scharr derivatives of a w x h grey image (img, stride bytes a row) into deriv (dstride
 * int16_t a row) as (d/dx, d/dy) pairs, exactly as OpenCV's buildOpticalFlowPyramid computes
 * them (calcSharrDeriv: rows and columns past the edges reflected about them, 101); tmp holds
 * 2 * (w + 2) int16_t. Runs the fastest path the machine has.
 */
void mvod_lk_scharr(const uint8_t *img, ptrdiff_t stride, int w, int h, int16_t *deriv,
		    ptrdiff_t dstride, int16_t *tmp);
/* The same on one path (as mvod_lk_flow_on). */
int mvod_lk_scharr_on(enum mvod_lk_path path, const uint8_t *img, ptrdiff_t stride, int w, int h,
		      int16_t *deriv, ptrdiff_t dstride, int16_t *tmp);

#ifdef __cplusplus
}
#endif

#endif
