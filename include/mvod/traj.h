/* Trajectories: crash-safe writers, readers for ground truth, and a bounded path for plots. */
#ifndef MVOD_TRAJ_H
#define MVOD_TRAJ_H

#include <stddef.h>
#include <stdint.h>

#include "mvod/geom.h"

#ifdef __cplusplus
extern "C" {
#endif

enum mvod_traj_format {
	MVOD_TRAJ_TUM = 0,   /* "t tx ty tz qx qy qz qw" */
	MVOD_TRAJ_KITTI = 1, /* row-major 3x4 [R|t], one pose per line */
};

/* The formats' names in enum order, NULL-terminated (the config file's choices). */
extern const char *const mvod_traj_format_names[];
const char *mvod_traj_format_name(enum mvod_traj_format fmt);

/*
 * Writer: each pose is formatted into one buffer and written with a single write(2), so a
 * killed process leaves only complete lines. Opened through the output policy (util/output.h):
 * a symlink is followed, a device or FIFO written into, an input of this process refused, the
 * file locked against a second writer; an existing file is truncated only when the first pose
 * is written, so a run that fails before keeps the trajectory before. Returns 0 or -errno with
 * a reason in err.
 */
struct mvod_traj_writer;
int mvod_traj_writer_open(const char *path, enum mvod_traj_format fmt,
			  struct mvod_traj_writer **out, char *err, size_t errlen);
/* t in seconds (ignored by KITTI). */
int mvod_traj_writer_add(struct mvod_traj_writer *w, double t, const struct mvod_pose *pose);
/*
 * Log rotation: opens the file by its name again (creating it, appending when it exists) and
 * closes the old one after an fsync. On failure the old file stays in use; reason in err.
 */
int mvod_traj_writer_reopen(struct mvod_traj_writer *w, char *err, size_t errlen);
/* fsyncs and closes; returns the first error seen by any add or the close. NULL is a no-op. */
int mvod_traj_writer_close(struct mvod_traj_writer *w);

/* A whole trajectory in memory (ground truth, test output). */
struct mvod_traj {
	int n;
	double *t;              /* seconds; for KITTI files the line index times 0 (unknown) */
	struct mvod_pose *pose; /* camera-to-world */
	enum mvod_traj_format format;
};

/*
 * The one check of every pose that enters mvod (ground truth of any source, --gt, the poses
 * mvod view receives): each number finite, the position at most MVOD_POSE_MAX_M from the
 * origin, the rotation a unit quaternion or a rotation matrix to within MVOD_POSE_UNIT_TOL.
 * A zero quaternion or an all-zero rotation made 39 of 40 trajectory lines "nan" (exit 0).
 */
/*
 * Beyond any coordinate on Earth (geocentric ones reach 6.4e6 m, UTM northings 1e7 m), and
 * where a double still holds the position to 15 nm.
 */
#define MVOD_POSE_MAX_M 1e8
/*
 * How far a quaternion's length, and each entry of R^T R - I, may be from a unit: 1 %. Tools
 * print poses to 4 or more digits (TUM's ground truth: 4 decimals, within 2e-4; KITTI's: 6,
 * within 1e-6); a column mix-up or a zero is off by far more.
 */
#define MVOD_POSE_UNIT_TOL 0.01
/*
 * t (metres) and a quaternion q = (w, x, y, z) into *p, normalised. -EINVAL with the reason
 * in why ("quaternion (w x y z) = (0 0 0 0) has length 0, not 1") when they are no pose.
 */
int mvod_pose_from_quat(const double t[3], const double q[4], struct mvod_pose *p, char *why,
			size_t whylen);
/* A row-major 3x4 [R | t] into *p, as given; -EINVAL with the reason in why as above. */
int mvod_pose_from_matrix(const double rt[12], struct mvod_pose *p, char *why, size_t whylen);

/* Reads TUM or KITTI, told apart by the column count (8 or 12). -errno with a reason in err. */
int mvod_traj_load(const char *path, struct mvod_traj *out, char *err, size_t errlen);
void mvod_traj_free(struct mvod_traj *traj);

/*
 * A fixed-capacity record of positions for plotting a run of any length: when full, every
 * second point is dropped and the keep-stride doubles, so memory never grows.
 */
struct mvod_path {
	int n, cap;
	int64_t stride, seen;
	double *xyz; /* n * 3 */
};
int mvod_path_init(struct mvod_path *p, int cap);
void mvod_path_add(struct mvod_path *p, const double xyz[3]);
void mvod_path_fini(struct mvod_path *p);

#ifdef __cplusplus
}
#endif

#endif
