/*
 * mvod calibrate: board views from any source, the views worth calibrating with, the
 * calibration, and a verdict a user can act on.
 */
#ifndef MVOD_CALIBRATE_H
#define MVOD_CALIBRATE_H

#include <signal.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "mvod/board.h"
#include "mvod/calib.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Fewer views than this cannot constrain 4 intrinsics and the distortion: no calibration. */
#define MVOD_CALIB_MIN_VIEWS 3
/* Image cells for coverage: 8 across, 6 down, one bit each in a uint64_t. */
#define MVOD_CALIB_CELLS_X 8
#define MVOD_CALIB_CELLS_Y 6

struct mvod_calib_opts {
	const char *source;        /* source URI (required) */
	struct mvod_board board;   /* the target */
	enum mvod_cam_model model; /* pinhole-radtan (default) or fisheye-kb4 */
	bool rational;             /* pinhole: 8 coefficients (k1..k6, p1, p2) instead of 5 */
	int max_views;             /* views to calibrate with, 10..500 (default 80) */
	int min_corners;           /* corners a view needs; 0 = all of a chessboard, 6 of ChArUco */
	int64_t max_frames;        /* stop reading after this many frames; 0 = the whole source */
	const char *report;        /* PNG to write (coverage, errors, undistortion), or NULL */
	/*
	 * Reading stops when *stop becomes non-zero (Ctrl-C on a live camera, which never ends)
	 * and the frames read so far are calibrated. May be NULL. Borrowed.
	 */
	volatile sig_atomic_t *stop;
	/* The subcommand reading the views, naming its progress lines: "calibrate" (default), "mount". */
	const char *command;
	/*
	 * Called once the source is open, so its files are noted as inputs, and before a frame is
	 * read: the caller checks its outputs by the output policy (an --out naming a frame is
	 * refused before the work, not after it). 0 to go on, or -errno with the reason in err,
	 * which ends the reading. May be NULL; check_ctx is the caller's.
	 */
	int (*check_outputs)(void *check_ctx, char *err, size_t errlen);
	void *check_ctx;
};

/* Fills the defaults above; source and board are left for the caller. */
void mvod_calib_opts_default(struct mvod_calib_opts *o);

enum mvod_calib_verdict {
	MVOD_VERDICT_GOOD = 0,
	MVOD_VERDICT_POOR_COVERAGE, /* corners miss much of the image, or the tilts are too alike */
	MVOD_VERDICT_FEW_VIEWS,     /* usable, but too few views to trust the distortion */
	MVOD_VERDICT_HIGH_ERROR,    /* reprojection error too large: blur, a bent board, wrong spec */
	/*
	 * The views cannot all be one camera: frames of another image size, or the two halves of
	 * the views (in source order) calibrated apart disagree beyond their uncertainty (a
	 * folder with a stereo pair's left and right images). The fit is a blend of cameras.
	 */
	MVOD_VERDICT_MIXED,
};
const char *mvod_calib_verdict_name(enum mvod_calib_verdict v);

struct mvod_calib_result {
	struct mvod_camera cam;
	double rms_px;                /* over the views used */
	int64_t frames_read;
	int64_t frames_with_board;    /* frames with at least min_corners corners */
	int64_t frames_repeated;      /* not examined: the same picture as the frame before */
	int views_selected;           /* picked for calibration */
	int views_used;               /* after dropping outliers */
	double outlier_px;            /* per-view RMS above which a view was dropped */
	double *view_rms_px;          /* views_used, malloc'ed */
	double *view_pose;            /* views_used x 6 (rvec, tvec), malloc'ed */
	int64_t *view_frame;          /* views_used source frame indices, malloc'ed */
	bool has_std;                 /* standard deviations known (pinhole only) */
	double std_K[4];              /* fx fy cx cy, pixels */
	double std_dist[MVOD_MAX_DIST];
	double coverage;              /* fraction of image cells the used views' corners cover */
	double tilt_span_deg;         /* largest angle between two used views' board normals */
	double read_s, solve_s;       /* wall time reading and detecting, selecting and calibrating */
	enum mvod_calib_verdict verdict;
	char advice[640];             /* what to do about the verdict, in words */
};

/*
 * Reads the whole source, detects the board, selects, calibrates, drops outlier views and
 * calibrates again, judges, and writes o->report when set. Returns 0, or -errno with a
 * one-line reason in err (no board found, what was found instead, too few views, ...).
 * Free res with mvod_calib_result_free, also after a failure.
 */
int mvod_calibrate(const struct mvod_calib_opts *o, struct mvod_calib_result *res, char *err,
		   size_t errlen);
void mvod_calib_result_free(struct mvod_calib_result *res);

/* The file record of a result (pointers borrowed from res). */
void mvod_calib_result_meta(const struct mvod_calib_result *res, const struct mvod_calib_opts *o,
			    struct mvod_calib_meta *meta);

/* --- The decisions, in plain C so that they are unit-tested on their own. --- */

/* What selection knows of a detected view. */
struct mvod_calib_view_info {
	uint64_t cells;    /* image cells (bit y * CELLS_X + x) the board's corners cover */
	int tilt_bin;      /* orientation bin of the board (mvod_calib_tilt_bin) */
	int corners;
	float cx, cy;      /* centre of the corners, as a fraction of the image size */
	float extent;      /* diagonal of the corners' bounding box, as a fraction of the image's */
};

/* Cells covered by the corners xy (n points, pixels) in a w x h image: see calibrate.c. */
uint64_t mvod_calib_cells(const float *xy, int n, int w, int h);
/* Orientation bin of a board pose given as a board-to-camera rotation vector. */
int mvod_calib_tilt_bin(const double rvec[3]);

/*
 * Greedy selection of at most max views: each round takes the view that adds the most
 * uncovered image cells and least-used tilt bins, skipping near-duplicates of views already
 * taken. Writes the indices to picked (capacity max) and returns how many.
 */
int mvod_calib_select(const struct mvod_calib_view_info *v, int n, int max, int *picked);

/*
 * Per-view RMS above which a view is an outlier: max(median + 3 * 1.4826 * MAD, 2 * median).
 * n > 0; err is not modified.
 */
double mvod_calib_outlier_px(const double *err, int n);

/* Largest angle between the board normals of n poses (rvec, tvec rows of 6), degrees. */
double mvod_calib_tilt_span_deg(const double *pose, int n);

/* Intrinsics fx, fy, cx, cy (pixels) of a calibration and their standard deviations. */
struct mvod_calib_k4 {
	double k[4], std[4];
};

/*
 * Whether two calibrations of parts of one set of views cannot be one camera: some intrinsic
 * differs by more than 5 combined standard deviations (sqrt(sa^2 + sb^2); a chance of about
 * 1 in 10^6 for one camera with honest deviations) and by more than 1 % of the image width
 * w (calibrateCamera's deviations are too small when few views share a part). Then says in
 * why which one, with both values, e.g. "cx 342.4 +- 0.9 px against 328.3 +- 1.1 px".
 */
bool mvod_calib_differ(const struct mvod_calib_k4 *a, const struct mvod_calib_k4 *b, int w,
		       char *why, size_t len);

/* The verdict on a calibration and, in advice, what the user should do about it. */
enum mvod_calib_verdict mvod_calib_judge(int views, double rms_px, double coverage,
					 double tilt_span_deg, char *advice, size_t len);

#ifdef __cplusplus
}
#endif

#endif
