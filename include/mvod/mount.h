/*
 * mvod mount: how the camera sits above the floor (height, pitch, roll), measured from a
 * calibration board lying flat on the floor, and written into the camera file's "mount" block,
 * which --scale height reads when no --camera-height is given.
 */
#ifndef MVOD_MOUNT_H
#define MVOD_MOUNT_H

#include <signal.h>
#include <stdint.h>

#include "mvod/board.h"
#include "mvod/calib.h"

#ifdef __cplusplus
extern "C" {
#endif

/*
 * The conventions of struct mvod_camera's mount (and of scale.c's mvod_ground_normal), in the
 * camera frame (OpenCV axes: x right, y down, z forward), with n the floor's unit normal
 * pointing down, away from the camera: n = (cos p sin r, cos p cos r, sin p).
 */
struct mvod_mount {
	double height_m;  /* distance from the camera centre to the floor plane, metres */
	double pitch_deg; /* asin(n_z): positive when the camera looks down */
	double roll_deg;  /* atan2(n_x, n_y): positive when the floor's normal leans to +x (the
			     camera turned clockwise about its axis, seen from behind) */
};

struct mvod_mount_opts {
	const char *source;       /* frames of the board on the floor (required) */
	struct mvod_board board;  /* (required) */
	double thickness_m;       /* the board's printed face above the floor, metres (0) */
	int64_t max_frames;       /* read at most this many frames; 0 = all */
	volatile sig_atomic_t *stop; /* reading stops when it becomes non-zero; may be NULL */
};

/* Why a view was not averaged in. */
enum mvod_mount_verdict {
	MVOD_MOUNT_USED = 0,
	MVOD_MOUNT_HIGH_ERROR, /* corners off the pose by more than MVOD_MOUNT_MAX_RMS_PX */
	MVOD_MOUNT_UNCERTAIN,  /* board too small or too far: the pose leaves the mount loose */
	MVOD_MOUNT_NOT_FLAT,   /* the board's plane is beyond MVOD_MOUNT_MAX_ANGLE_DEG of level */
	MVOD_MOUNT_DISAGREES,  /* far from the other views' median (board moved off the floor) */
};

/*
 * A view whose corners fit its pose worse than this is refused: wrong intrinsics, a wrong board
 * size or a bent board; detected corners of a sharp board fit to 0.1-0.3 px.
 */
#define MVOD_MOUNT_MAX_RMS_PX 1.0
/*
 * The corners' error assumed for a view's uncertainty when their fit is better than this, px:
 * a fit on few corners can come out below the detector's real precision.
 */
#define MVOD_MOUNT_MIN_SIGMA_PX 0.2
/*
 * A view is refused when its one-sigma uncertainty is above 1 % of the height or 0.5 deg of
 * tilt: the height is --scale height's metric scale itself (1 % of height = 1 % of every
 * distance), and 0.5 deg of pitch moves the ground 10 m ahead by 9 cm.
 */
#define MVOD_MOUNT_MAX_SD_REL 0.01
#define MVOD_MOUNT_MAX_SD_DEG 0.5
/*
 * A view disagrees with the median of all views when further from it than 3 sigma plus this:
 * a printed board on a floor that is not perfectly level (tiles, carpet) tilts by a few
 * tenths of a degree and lifts by a millimetre or two.
 */
#define MVOD_MOUNT_AGREE_DEG 0.3
#define MVOD_MOUNT_AGREE_REL 0.01

struct mvod_mount_view {
	int64_t frame;               /* source frame index */
	struct mvod_mount m, sd;     /* the view's mount, and one standard deviation of each */
	double rms_px;               /* corners' reprojection RMS under the pose */
	enum mvod_mount_verdict verdict;
};

struct mvod_mount_result {
	struct mvod_mount m, sd;     /* the weighted mean of the used views, its deviation */
	int64_t frames_read;
	int n_views, used;
	struct mvod_mount_view *views; /* n_views, malloc'ed */
};

/*
 * Reads the source, finds the board, takes its pose in every view under cam (intrinsics and
 * lens; its image size, when known, must be the frames'), judges each view and averages the
 * good ones weighted by their uncertainty. Returns 0, or -errno with a one-line reason in err
 * (no board, no view good enough and why). Free res with mvod_mount_result_free, also after
 * a failure.
 */
int mvod_mount_measure(const struct mvod_mount_opts *o, const struct mvod_camera *cam,
		       struct mvod_mount_result *res, char *err, size_t errlen);
void mvod_mount_result_free(struct mvod_mount_result *res);

/* --- The parts, plain C, unit-tested on their own. --- */

/*
 * The mount from one board pose (board-to-camera, X_cam = R(rvec) X_board + tvec, board frame
 * of mvod/board.h: z into the board, here into the floor): n = R's third column, height
 * n . tvec + thickness_m.
 */
void mvod_mount_from_pose(const double rvec[3], const double tvec[3], double thickness_m,
			  struct mvod_mount *m);
/* One standard deviation of each of the mount's values, given the pose's 6x6 covariance. */
void mvod_mount_sd(const double rvec[3], const double tvec[3], const double cov[36],
		   struct mvod_mount *sd);
/*
 * Marks views (whose verdict is USED so far) that disagree with the median, and averages
 * the rest into m and sd, weighted by 1 / sd^2. Returns how many were used.
 */
int mvod_mount_combine(struct mvod_mount_view *v, int n, struct mvod_mount *m,
		       struct mvod_mount *sd);

/*
 * Writes m into the camera file's text (its content, as read) to path, values rounded to
 * 0.1 mm and 0.01 deg, through mvod_write_replace (whole or not at all). mvod JSON: as its
 * "mount" block, every other field kept as it was (a "mount" already there is replaced in its
 * place); other JSON is refused (-EINVAL). Text that is no JSON: as OpenCV or ROS YAML, with
 * mvod_calib_filestorage_set_mount (every other byte kept; XML refused, -ENOTSUP). Returns 0
 * or -errno with a one-line reason in err.
 */
int mvod_mount_write(const char *path, const char *text, const struct mvod_mount *m, char *err,
		     size_t errlen);

#ifdef __cplusplus
}
#endif

#endif
