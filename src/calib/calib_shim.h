/* The OpenCV side of mvod calibrate: board detection, calibration, the report. */
#ifndef MVOD_CALIB_SHIM_H
#define MVOD_CALIB_SHIM_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "mvod/board.h"
#include "mvod/calibrate.h"
#include "mvod/calib.h"
#include "mvod/image.h"

#ifdef __cplusplus
extern "C" {
#endif

/* A board detector: the dictionary, board layout and scratch images, made once per run. */
struct mvod_calib_det;

int mvod_calib_det_create(const struct mvod_board *b, struct mvod_calib_det **out);
/* NULL is a no-op. */
void mvod_calib_det_destroy(struct mvod_calib_det *d);

/* What one frame shows; ids and xy are caller-owned, of mvod_board_corner_count capacity. */
struct mvod_calib_found {
	int n;         /* corners found (chessboard: all or none) */
	int *ids;      /* corner indices, mvod_board_corner order */
	float *xy;     /* 2n pixel coordinates */
	int markers;   /* charuco: markers of this board found */
	int stray;     /* charuco: markers of the dictionary whose ids are not on this board */
	int max_id;    /* charuco: largest marker id seen; -1 = none */
	bool mislaid;  /* charuco: corners do not lie on one plane as the layout says (f->n = 0) */
	bool repeat;   /* the frame is the last examined one again (a still camera): not examined */
};

/*
 * Finds the board in img (grey or BGR). No board is not an error: f->n = 0. A frame that
 * differs from the last examined one by less than sensor noise is not examined (f->repeat):
 * its board would be a duplicate view that selection drops anyway.
 */
int mvod_calib_detect(struct mvod_calib_det *d, const struct mvod_image *img,
		      struct mvod_calib_found *f);
/*
 * For a frame where the board was not found: what the image shows instead, e.g. "markers of
 * DICT_4X4_50" or "a chessboard with 7x5 inner corners", or "" when nothing; and in fits the
 * board spec that would match it (the searched board with that size or dictionary), or
 * cols 0 when no spec follows from it. Slow (tries every dictionary): for a few frames only.
 */
int mvod_calib_diagnose(struct mvod_calib_det *d, const struct mvod_image *img,
			struct mvod_board *fits, char *what,
			size_t len);

/* One view for calibration: n corners with their board indices and pixel positions. */
struct mvod_calib_obs {
	int n;
	const int *ids;
	const float *xy;
	int64_t frame; /* the source frame it was found in: not used by the fit, recorded with it */
};

struct mvod_calib_fit {
	struct mvod_camera cam;
	double rms_px;
	double *view_rms_px;   /* caller-owned, n entries */
	double *view_pose;     /* caller-owned, 6n: rvec, tvec */
	bool has_std;
	double std_K[4];
	double std_dist[MVOD_MAX_DIST];
};

/* Calibrates a w x h camera of the given model from n views. fit's arrays are caller-owned. */
int mvod_calib_solve(const struct mvod_board *b, const struct mvod_calib_obs *v, int n, int w, int h,
		   enum mvod_cam_model model, bool rational, struct mvod_calib_fit *fit, char *err,
		   size_t errlen);

/*
 * Board orientation of each view (rvecs, 3n) under a rough pinhole camera estimated from the
 * views themselves: good to a few degrees, enough to tell tilts apart before calibrating.
 */
int mvod_calib_rough_tilts(const struct mvod_board *b, const struct mvod_calib_obs *v, int n,
			   int w, int h, double *rvecs);

/*
 * Every view of the board in o->source (read as mvod calibrate reads it: o's board,
 * min_corners, max_frames and stop), for mvod mount. Fewer than min_views is an error saying
 * what the frames showed instead. Free out with mvod_calib_views_free, also after a failure.
 */
struct mvod_calib_views {
	int n;
	struct mvod_calib_obs *obs; /* n views in source order; corners borrowed from pools */
	int w, h;                   /* the frames' size, pixels */
	int64_t frames;             /* frames read */
	void *pools;                /* owned: the corners of every view */
};
int mvod_calib_read_views(const struct mvod_calib_opts *o, int min_views,
			  struct mvod_calib_views *out, char *err, size_t errlen);
void mvod_calib_views_free(struct mvod_calib_views *v);

/* One view's board-to-camera pose under known intrinsics: X_cam = R(rvec) X_board + tvec. */
struct mvod_calib_pose {
	double rvec[3];  /* rotation vector, radians */
	double tvec[3];  /* metres */
	double cov[36];  /* covariance of (rvec, tvec), row-major 6x6, for corners of sigma_px */
	double rms_px;   /* reprojection RMS through the camera's lens model, pixels */
};

/*
 * The board's pose in view v (at least 4 corners not on one line) under cam's intrinsics and
 * lens: the corners undistorted, IPPE (the planar solver), then Levenberg-Marquardt. The
 * covariance takes the corners' error as sigma_px in each axis. -EDOM when no pose fits.
 */
int mvod_calib_board_pose(const struct mvod_board *b, const struct mvod_calib_obs *v,
			  const struct mvod_camera *cam, double sigma_px,
			  struct mvod_calib_pose *out);

struct mvod_calib_report {
	const struct mvod_camera *cam;
	const struct mvod_calib_obs *views; /* the views used */
	int n;
	const double *view_rms_px;
	double outlier_px;                  /* the drop threshold, drawn on the error chart */
	double coverage;                    /* fraction of image cells covered */
	const struct mvod_image *sample;    /* a frame with the board, or NULL */
	enum mvod_calib_verdict verdict;    /* written in the header, with its advice */
	const char *advice;                 /* borrowed; NULL: none */
};

/* One PNG: corner coverage, per-view error, a sample frame before and after undistortion. */
int mvod_calib_report_write(const char *path, const struct mvod_calib_report *r);

#ifdef __cplusplus
}
#endif

#endif
