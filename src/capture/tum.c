/*
 * tum:DIR, the two TUM layouts. The RGB-D benchmark: rgb.txt ("timestamp filename", seconds),
 * the colour images it names, groundtruth.txt (the colour camera's pose, "timestamp tx ty tz
 * qx qy qz qw"); intrinsics from --calib or from the published ones of freiburg1/2/3 when
 * the folder name says which. The monoVO dataset: times.txt ("id timestamp exposure"),
 * images/ID.jpg, camera.txt (DSO's, read by camera/calib_dso.c: FOV, pinhole, RadTan and
 * Kannala-Brandt lenses; no ground truth).
 */
#include "capture/backends.h"
#include "capture/path.h"

#include <assert.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "capture/dataset.h"
#include "mvod/log.h"
#include "util/lines.h"

struct tum {
	struct mvod_dataset ds; /* first, so that the dataset ops work on it as is */
	int freiburg;           /* 1..3 when the intrinsics are that camera's published ones */
	char dir[PATH_MAX];
	char why[MVOD_ERR_MAX]; /* why the folder gives no camera, logged when one is asked for */
};

static_assert(offsetof(struct tum, ds) == 0, "the dataset ops take the tum priv");

/*
 * The colour cameras' calibration the TUM RGB-D benchmark publishes (its "file formats"
 * page): fx fy cx cy, then d0..d4 in OpenCV's order k1 k2 p1 p2 k3; 640x480. freiburg3's
 * images are already undistorted.
 */
static const double freiburg_cam[3][9] = {
	{517.3, 516.5, 318.6, 255.3, 0.2624, -0.9531, -0.0054, 0.0026, 1.1633},
	{520.9, 521.0, 325.1, 249.7, 0.2312, -0.7849, -0.0033, -0.0001, 0.9172},
	{535.4, 539.2, 320.1, 247.6, 0, 0, 0, 0, 0},
};

/* 1..3 when the last component of dir says freiburgN (rgbd_dataset_freiburg1_xyz), else 0. */
static int freiburg_of(const char *dir)
{
	char real[PATH_MAX];
	const char *base = realpath(dir, real) ? strrchr(real, '/') : NULL;
	const char *f = base ? strstr(base, "freiburg") : NULL;
	return f && f[8] >= '1' && f[8] <= '3' ? f[8] - '0' : 0;
}

static void freiburg_camera(int n, struct mvod_camera *cam)
{
	const double *c = freiburg_cam[n - 1];
	*cam = (struct mvod_camera){.width = 640, .height = 480, .fx = c[0], .fy = c[1],
				    .cx = c[2], .cy = c[3], .model = MVOD_CAM_PINHOLE_RADTAN,
				    .n_dist = 5};
	memcpy(cam->dist, c + 4, 5 * sizeof(double));
}

struct index {
	struct mvod_ds_frames frames;
	const char *path; /* rgb.txt or times.txt */
	const char *dir;  /* what names in it are relative to */
};

/* rgb.txt: "1305031102.175304 rgb/1305031102.175304.png" */
static int add_rgb(void *ctx, char *line, size_t lineno, char *err, size_t errlen)
{
	struct index *x = ctx;
	const char *end;
	int64_t ns;
	char *name = NULL;
	if (mvod_ds_parse_seconds(line, &end, &ns) == 0 && (*end == ' ' || *end == '\t')) {
		name = (char *)end + strspn(end, " \t");
		name[strcspn(name, " \t")] = '\0';
	}
	if (!name || !*name)
		return mvod_errf(err, errlen, -EINVAL, "%s line %zu: \"%.40s\" is not \"timestamp "
				 "filename\" (seconds)", x->path, lineno, line);
	return mvod_ds_frames_add(&x->frames, x->path, lineno, x->dir, name, ns, err, errlen);
}

/* groundtruth.txt: "timestamp tx ty tz qx qy qz qw", seconds, metres. */
static int gt_line(const char *line, int64_t *ns, struct mvod_pose *cam, char *why,
		   size_t whylen)
{
	const char *s;
	if (mvod_ds_parse_seconds(line, &s, ns) < 0)
		return -EINVAL;
	return mvod_ds_parse_pose(s, ' ', false, cam, why, whylen);
}

static int open_rgbd(struct tum *t, char *err, size_t errlen)
{
	struct mvod_dataset *ds = &t->ds;
	struct index x = {.path = ds->index, .dir = t->dir};
	int ret = mvod_ds_optional(ds->gt_path, sizeof(ds->gt_path), t->dir, "groundtruth.txt",
				   err, errlen);
	if (!ret)
		ret = mvod_lines_each(ds->index, "TUM rgb.txt", add_rgb, &x, err, errlen);
	if (ret) {
		mvod_ds_frames_free(&x.frames);
		return ret;
	}
	/* groundtruth.txt gives the colour camera's own pose: no body frame in between. */
	mvod_pose_identity(&ds->body_cam);
	ds->gt_line = gt_line;
	ds->gt_layout = "timestamp tx ty tz qx qy qz qw";
	t->freiburg = freiburg_of(t->dir);
	ds->has_cam = t->freiburg > 0;
	if (ds->has_cam)
		freiburg_camera(t->freiburg, &ds->cam);
	else
		mvod_errf(t->why, sizeof(t->why), 0, "tum:%s: the folder name says no freiburg1, "
			  "2 or 3, whose published intrinsics mvod knows", t->dir);
	return mvod_ds_open_frames(ds, &x.frames, err, errlen);
}

/* times.txt of monoVO: "00000 1.2345 10.2" (id, seconds, exposure ms); images/ID.jpg. */
static int add_mono(void *ctx, char *line, size_t lineno, char *err, size_t errlen)
{
	struct index *x = ctx;
	char *id = line + strspn(line, " \t"), name[64];
	size_t idlen = strcspn(id, " \t");
	const char *end;
	int64_t ns;
	if (idlen == 0 || idlen > 32 || mvod_ds_parse_seconds(id + idlen, &end, &ns) < 0)
		return mvod_errf(err, errlen, -EINVAL, "%s line %zu: \"%.40s\" is not TUM monoVO's "
				 "\"id timestamp [exposure]\" (seconds); images with one time per "
				 "line are images:DIR", x->path, lineno, line);
	char path[PATH_MAX];
	snprintf(name, sizeof(name), "images/%.*s.jpg", (int)idlen, id);
	snprintf(path, sizeof(path), "%s/%s", x->dir, name);
	if (access(path, F_OK) != 0) /* the dataset's are jpg; a converted copy may be png */
		snprintf(name, sizeof(name), "images/%.*s.png", (int)idlen, id);
	return mvod_ds_frames_add(&x->frames, x->path, lineno, x->dir, name, ns, err, errlen);
}

static int open_mono(struct tum *t, char *err, size_t errlen)
{
	struct mvod_dataset *ds = &t->ds;
	struct index x = {.path = ds->index, .dir = t->dir};
	char path[PATH_MAX];
	int ret = mvod_capture_path(path, sizeof(path), t->dir, "camera.txt", err, errlen);
	if (!ret)
		ret = mvod_lines_each(ds->index, "TUM monoVO times.txt", add_mono, &x, err,
				      errlen);
	if (ret) {
		mvod_ds_frames_free(&x.frames);
		return ret;
	}
	/*
	 * A camera.txt mvod cannot take is no reason to refuse the frames: --calib may give
	 * the camera. Why it was not taken is said when the run asks for one.
	 */
	ds->has_cam = mvod_calib_load_dso(path, &ds->cam, t->why, sizeof(t->why)) == 0;
	return mvod_ds_open_frames(ds, &x.frames, err, errlen);
}

static int tum_open(void *priv, const char *dir, char *err, size_t errlen)
{
	struct tum *t = priv;
	int n = snprintf(t->dir, sizeof(t->dir), "%s", dir);
	if (n < 0 || (size_t)n >= sizeof(t->dir))
		return mvod_errf(err, errlen, -ENAMETOOLONG, "path too long: %s", dir);
	char times[PATH_MAX];
	int ret = mvod_capture_path(t->ds.index, sizeof(t->ds.index), dir, "rgb.txt", err, errlen);
	if (!ret)
		ret = mvod_capture_path(times, sizeof(times), dir, "times.txt", err, errlen);
	if (ret)
		return ret;
	if (access(t->ds.index, F_OK) == 0)
		return open_rgbd(t, err, errlen);
	if (access(times, F_OK) == 0) {
		memcpy(t->ds.index, times, sizeof(times));
		return open_mono(t, err, errlen);
	}
	return mvod_errf(err, errlen, -ENOENT, "%s is not a TUM sequence: it has neither rgb.txt "
			 "(RGB-D benchmark) nor times.txt (monoVO)", dir);
}

static int tum_camera(void *priv, struct mvod_camera *cam)
{
	const struct tum *t = priv;
	int ret = mvod_ds_camera(priv, cam);
	if (ret == 0 && t->freiburg)
		LOG(INFO, "tum:%s: intrinsics and distortion of freiburg%d's colour camera, as the "
			  "TUM RGB-D benchmark publishes them (the folder name says freiburg%d); "
			  "--calib FILE overrides", t->dir, t->freiburg, t->freiburg);
	if (ret == -ENOENT)
		LOG(WARN, "%s", t->why);
	return ret;
}

const struct mvod_source_ops mvod_source_tum_ops = {
	.scheme = "tum",
	.summary = "tum:DIR  TUM RGB-D (rgb.txt, rgb/, groundtruth.txt) or monoVO (times.txt, "
		   "images/, camera.txt) sequence",
	.priv_size = sizeof(struct tum),
	.open = tum_open,
	.read = mvod_images_read,
	.info = mvod_images_info,
	.camera = tum_camera,
	.ground_truth = mvod_ds_ground_truth,
	.close = mvod_ds_close,
};
