/* PNG plots of trajectories. */
#ifndef MVOD_PLOT_H
#define MVOD_PLOT_H

#include "mvod/geom.h"
#include "mvod/image.h"

#ifdef __cplusplus
extern "C" {
#endif

/*
 * Top-down view (x right, z forward: the ground plane of a camera frame) of an estimated path
 * against ground truth: metric axes with ticks, equal aspect, start and end markers, a heading
 * arrow at the end of the estimate (from heading, the last camera-to-world rotation; may be
 * NULL), a legend and a title. gt may be NULL / n_gt 0. Written through a temporary file and
 * rename(). Returns 0 or -errno.
 */
int mvod_plot_topdown(const char *path, const char *title, const double *est_xyz, int n_est,
		      const double heading[9], const double *gt_xyz, int n_gt);

/* The size of that picture, in pixels. */
#define MVOD_PLOT_WIDTH 1000
#define MVOD_PLOT_HEIGHT 800

/*
 * The same picture drawn into out (MVOD_PIX_BGR, MVOD_PLOT_WIDTH x MVOD_PLOT_HEIGHT, borrowed
 * for the call) instead of a file, for a caller that draws more around it (mvod view).
 */
int mvod_plot_topdown_draw(struct mvod_image *out, const char *title, const double *est_xyz,
			   int n_est, const double heading[9], const double *gt_xyz, int n_gt);

#ifdef __cplusplus
}
#endif

#endif
