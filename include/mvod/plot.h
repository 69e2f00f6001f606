/* PNG plots of trajectories. */
#ifndef MVOD_PLOT_H
#define MVOD_PLOT_H

#include <stdbool.h>
#include <stddef.h>

#include "mvod/geom.h"
#include "mvod/image.h"

#ifdef __cplusplus
extern "C" {
#endif

/*
 * Axis ticks as every chart of mvod draws them: the step is the smallest 1, 2 or 5 x 10^k at
 * least raw (> 0), and a tick's label has the decimals the step needs (0.05 -> "0.15").
 */
double mvod_plot_nice_step(double raw);
void mvod_plot_tick_label(double value, double step, char *buf, size_t len);

/* The axes' unit: "m" once ground truth set the scale, "units, free scale" otherwise. */
const char *mvod_plot_unit(bool metric);

/*
 * Top-down view (x right, z forward: the ground plane of a camera frame) of an estimated path
 * against ground truth: axes in unit (mvod_plot_unit) with ticks, equal aspect, start and end
 * markers, a heading arrow at the end of the estimate (from heading, the last camera-to-world
 * rotation; may be NULL), a legend and a title. gt may be NULL / n_gt 0. Written through a
 * temporary file and rename(). Returns 0 or -errno.
 */
int mvod_plot_topdown(const char *path, const char *title, const double *est_xyz, int n_est,
		      const double heading[9], const double *gt_xyz, int n_gt, const char *unit);

/*
 * Whether path names an image format OpenCV writes (.png, .jpg, .bmp, .tif, .ppm ...) by its
 * extension, as mvod_plot_topdown and mvod_plot_chart need, before any work: 0, or -EINVAL
 * with "what path: ..." in err (no extension, /dev/null, or one no encoder takes).
 */
int mvod_plot_check(const char *what, const char *path, char *err, size_t errlen);

/* The size of that picture, in pixels. */
#define MVOD_PLOT_WIDTH 1000
#define MVOD_PLOT_HEIGHT 800

/*
 * The same picture drawn into out (MVOD_PIX_BGR, MVOD_PLOT_WIDTH x MVOD_PLOT_HEIGHT, borrowed
 * for the call) instead of a file, for a caller that draws more around it (mvod view), with
 * the axes in unit (mvod_plot_unit).
 */
int mvod_plot_topdown_draw(struct mvod_image *out, const char *title, const double *est_xyz,
			   int n_est, const double heading[9], const double *gt_xyz, int n_gt,
			   const char *unit);

enum mvod_plot_style {
	MVOD_PLOT_LINE = 0,
	MVOD_PLOT_DASHED = 1,
	MVOD_PLOT_POINTS = 2, /* markers; with point_labels numbered, and named in a key beside */
};

/* One data series; borrowed for the call. Non-finite values are left out. */
struct mvod_plot_series {
	const char *label; /* legend text */
	const double *x, *y;
	int n;
	enum mvod_plot_style style;
	const char *const *point_labels; /* POINTS: n texts beside the markers, or NULL */
};

/* One chart: axis titles with units, and its series (colours in order: blue, grey, red, ...). */
struct mvod_plot_panel {
	const char *x_label, *y_label;
	const struct mvod_plot_series *series;
	int n_series;
	bool log_x; /* logarithmic x axis; points with x <= 0 are left out */
};

/*
 * Panels stacked top to bottom under one title, each with its own axes, ticks, grid and
 * legend; axes fit the data (y from 0 when no value is negative). Written through a temporary
 * file and rename(). Returns 0 or -errno.
 */
int mvod_plot_chart(const char *path, const char *title, const struct mvod_plot_panel *panels,
		    int n_panels);

#ifdef __cplusplus
}
#endif

#endif
