/*
 * What the dataset sources (euroc:, tum:) share: index files read line by line, so that an
 * error names the line; timestamps parsed exactly into int64 nanoseconds; the frame list
 * handed to the images reader; and ground truth turned into poses of the camera at the
 * frames' own times.
 */
#ifndef MVOD_CAPTURE_DATASET_H
#define MVOD_CAPTURE_DATASET_H

#include <limits.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "capture/images.h"
#include "mvod/geom.h"

/*
 * One ground-truth line: its time in ns and the body pose it gives; -EINVAL when malformed,
 * with the reason in why when the numbers are there but are no pose (mvod_pose_from_quat).
 */
typedef int (*mvod_ds_gt_line_fn)(const char *line, int64_t *ns, struct mvod_pose *body,
				  char *why, size_t whylen);

/* A dataset source's state; the euroc: and tum: backends are this. */
struct mvod_dataset {
	struct mvod_images images; /* first, so that the images ops work on it as is */
	int64_t *frame_ns;         /* images.n frame times, nanoseconds, as the index gives them */
	char index[PATH_MAX];      /* the frame index file (data.csv, rgb.txt, times.txt) */
	size_t index_first, index_last; /* its lines of the first and the last frame */
	struct mvod_camera cam;    /* intrinsics the dataset carries, when has_cam */
	bool has_cam;
	char gt_path[PATH_MAX];    /* ground-truth file, "" when the dataset has none */
	mvod_ds_gt_line_fn gt_line;
	const char *gt_layout;     /* what a ground-truth line holds, for messages */
	struct mvod_pose body_cam; /* T_BS: camera to ground-truth body frame (identity for TUM) */
};

/*
 * A timestamp at s, exactly, into nanoseconds: integer nanoseconds (EuRoC) or decimal
 * seconds with up to 9 digits after the point (TUM; further digits are below a nanosecond
 * and dropped). *end points past it. -EINVAL for anything else, a negative time included.
 */
int mvod_ds_parse_ns(const char *s, const char **end, int64_t *ns);
int mvod_ds_parse_seconds(const char *s, const char **end, int64_t *ns);
/*
 * KITTI raw's calendar time "2011-09-26 13:02:25.964389445" (the digits as shown, the date
 * 1970-01-01 .. 2261-12-31, a real day of its month, no leap second, the decimals optional and
 * those past nine dropped) into nanoseconds since 1970 as if it were UTC: the clock is only
 * compared with itself. -EINVAL for anything else.
 */
int mvod_ds_parse_calendar(const char *s, const char **end, int64_t *ns);

/*
 * The 7 numbers of a pose after a line's time: "tx ty tz" in metres, then a unit quaternion,
 * w x y z (w_first, EuRoC) or x y z w (TUM); each after sep, ',' (more columns may follow) or
 * ' ' (whitespace; nothing may follow). -EINVAL when s is not that, or, with the reason in
 * why, when its numbers are no pose (traj.h: mvod_pose_from_quat).
 */
int mvod_ds_parse_pose(const char *s, char sep, bool w_first, struct mvod_pose *p, char *why,
		       size_t whylen);
/* ns as seconds with all 9 decimals ("1403636579.763555584"), into buf; returns buf. */
const char *mvod_ds_seconds(int64_t ns, char buf[24]);
/* -EINVAL with "PATH line N: time T is not after T' of line N'" for frames or poses (what). */
int mvod_ds_out_of_order(const char *path, size_t lineno, int64_t ns, int64_t prev,
			 size_t prev_line, const char *what, char *err, size_t errlen);

/* The frames an index names, gathered while it is read. Zero-initialise. */
struct mvod_ds_frames {
	char *text;        /* "dir/name\0" per frame */
	size_t len, cap;   /* bytes used and allocated in text */
	int64_t *ns;       /* frame times */
	size_t n, ncap;
	size_t first_line, last_line;
};

/*
 * Adds dir/name at time ns, from line lineno of index: -ENOENT when the file does not exist,
 * -EINVAL when ns is not after the last frame's, each with index and line in err.
 */
int mvod_ds_frames_add(struct mvod_ds_frames *f, const char *index, size_t lineno,
		       const char *dir, const char *name, int64_t ns, char *err, size_t errlen);

/* Releases what f gathered; f is zeroed. */
void mvod_ds_frames_free(struct mvod_ds_frames *f);
/*
 * Opens ds->images on the frames of f (read from index ds->index) and keeps their times in
 * ds->frame_ns. f is released in any case. -errno with the reason in err.
 */
int mvod_ds_open_frames(struct mvod_dataset *ds, struct mvod_ds_frames *f, char *err,
			size_t errlen);

/* Ops shared by the dataset backends, on a struct mvod_dataset. */
int mvod_ds_camera(void *priv, struct mvod_camera *cam);
int mvod_ds_ground_truth(void *priv, struct mvod_traj *gt, char *from, size_t fromlen,
			 char *err, size_t errlen);
void mvod_ds_close(void *priv);

/* path when it exists, else "": the optional files of a dataset (ground truth). */
int mvod_ds_optional(char *buf, size_t len, const char *dir, const char *name, char *err,
		     size_t errlen);

#endif
