/*
 * OpenCV's own pyramidal Lucas-Kanade (calcOpticalFlowPyrLK), the reference tests/unit/test_lk.c
 * compares src/vo/frontend/lk.c with. Built into unit/lk by meson (which defines
 * MVOD_HAVE_OPENCV_LK then); make cross-arm64 builds test_lk.c alone, without it.
 */
#ifndef MVOD_TESTS_LK_OPENCV_H
#define MVOD_TESTS_LK_OPENCV_H

#include <stddef.h>
#include <stdint.h>

#include "vo/frontend/lk.h"

#ifdef __cplusplus
extern "C" {
#endif

/*
 * calcOpticalFlowPyrLK of n points from the w x h grey image I into J (stride bytes a row):
 * p's window, levels and TermCriteria(COUNT | EPS, iterations, eps_px), the initial flow in to
 * (OPTFLOW_USE_INITIAL_FLOW), the minimum eigenvalue 1e-4 (its default); to receives the
 * tracked positions, status its status. 0, or -EIO when OpenCV throws.
 */
int lk_opencv_flow(const uint8_t *I, const uint8_t *J, int w, int h, ptrdiff_t stride,
		   const struct mvod_lk_params *p, const float *from, float *to, int n,
		   uint8_t *status);

#ifdef __cplusplus
}
#endif

#endif
