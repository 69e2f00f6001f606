/*
 * Calibration formats by name, and the plain-text writers: ROS camera_info YAML, KITTI
 * calib.txt, DSO's camera.txt.
 */
#include "mvod/calib.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "camera/calib_internal.h"
#include "util/atomic_file.h"
#include "util/errbuf.h"

static const struct {
	const char *name, *title;
} formats[] = {
	[MVOD_CALIB_FMT_MVOD] = {"mvod", "mvod JSON"},
	[MVOD_CALIB_FMT_OPENCV] = {"opencv", "OpenCV FileStorage"},
	[MVOD_CALIB_FMT_ROS] = {"ros", "ROS camera_info YAML"},
	[MVOD_CALIB_FMT_KITTI] = {"kitti", "KITTI calib.txt"},
	[MVOD_CALIB_FMT_PAIR] = {"pair", "JSON [K, dist] pair"},
	[MVOD_CALIB_FMT_DSO] = {"dso", "DSO camera.txt"},
};
#define N_FORMATS ((int)(sizeof(formats) / sizeof(formats[0])))

const char *mvod_calib_format_name(enum mvod_calib_format fmt)
{
	return (unsigned)fmt < N_FORMATS ? formats[fmt].name : "unknown";
}

const char *mvod_calib_format_title(enum mvod_calib_format fmt)
{
	return (unsigned)fmt < N_FORMATS ? formats[fmt].title : "unknown format";
}

int mvod_calib_format_parse(const char *name, enum mvod_calib_format *out)
{
	for (int i = 0; i < N_FORMATS; i++) {
		if (strcmp(name, formats[i].name) == 0) {
			*out = (enum mvod_calib_format)i;
			return 0;
		}
	}
	return -EINVAL;
}

/* The shortest decimal that reads back as the same double (17 digits always would). */
static void put_number(FILE *f, double v)
{
	char buf[32];
	for (int digits = 15; digits <= 17; digits++) {
		snprintf(buf, sizeof(buf), "%.*g", digits, v);
		if (strtod(buf, NULL) == v)
			break;
	}
	fputs(buf, f);
}

static void put_numbers(FILE *f, const double *v, int n, const char *sep)
{
	for (int i = 0; i < n; i++) {
		fputs(i ? sep : "", f);
		put_number(f, v[i]);
	}
}

static void put_ros_matrix(FILE *f, const char *key, int rows, int cols, const double *v)
{
	fprintf(f, "%s:\n  rows: %d\n  cols: %d\n  data: [", key, rows, cols);
	put_numbers(f, v, rows * cols, ", ");
	fputs("]\n", f);
}

/* P = [K | 0]: a single camera's projection, as ROS and KITTI files hold it. */
static void projection(const struct mvod_camera *cam, double P[12])
{
	double K[9];
	mvod_camera_K(cam, K);
	for (int r = 0; r < 3; r++) {
		memcpy(P + 4 * r, K + 3 * r, 3 * sizeof(double));
		P[4 * r + 3] = 0;
	}
}

/* Text built in a memory stream, then written whole (write_text). */
struct text {
	char *buf;
	size_t len;
	FILE *f;
};

static int open_text(struct text *t, const char *path, char *err, size_t errlen)
{
	*t = (struct text){0};
	t->f = open_memstream(&t->buf, &t->len);
	return t->f ? 0 : mvod_errf(err, errlen, -ENOMEM, "cannot write %s: out of memory", path);
}

/* buf and len are valid once f is closed; the text is freed in any case. */
static int write_text(const char *path, struct text *t, char *err, size_t errlen)
{
	int ret = fclose(t->f) == 0 ? mvod_write_replace(path, t->buf, t->len) : -ENOMEM;
	free(t->buf);
	if (ret)
		mvod_errf(err, errlen, ret, "cannot write %s: %s", path, strerror(-ret));
	return ret;
}

/*
 * ROS knows plumb_bob (5), rational_polynomial (8) and equidistant (4): fewer pinhole
 * coefficients are padded with zeros, and the thin-prism and tilt terms of 12 or 14 are
 * dropped only when they are zero.
 */
static int ros_distortion(const struct mvod_camera *cam, const char **model, int *n)
{
	if (cam->model == MVOD_CAM_FOV)
		return -ENOTSUP;
	if (cam->model == MVOD_CAM_FISHEYE_KB4) {
		*model = "equidistant";
		*n = 4;
		return 0;
	}
	for (int i = 8; i < cam->n_dist; i++)
		if (cam->dist[i] != 0)
			return -EINVAL;
	*model = cam->n_dist > 5 ? "rational_polynomial" : "plumb_bob";
	*n = cam->n_dist > 5 ? 8 : 5;
	return 0;
}

int mvod_calib_save_ros(const char *path, const struct mvod_camera *cam, char *err, size_t errlen)
{
	const char *model;
	int n;
	if (cam->width <= 0 || cam->height <= 0)
		return mvod_errf(err, errlen, -EINVAL,
			    "%s: ROS camera_info needs the image size, which the calibration lacks", path);
	int ret = ros_distortion(cam, &model, &n);
	if (ret == -ENOTSUP)
		return mvod_errf(err, errlen, -EINVAL, "%s: ROS camera_info has no FOV lens model "
				 "(image_geometry knows plumb_bob, rational_polynomial and "
				 "equidistant): write mvod JSON, OpenCV YAML or DSO's camera.txt", path);
	if (ret)
		return mvod_errf(err, errlen, -EINVAL,
			    "%s: ROS camera_info has no model for non-zero thin-prism or tilt "
			    "coefficients (the 9th and later)", path);
	struct text t;
	if ((ret = open_text(&t, path, err, errlen)))
		return ret;
	FILE *f = t.f;
	double dist[MVOD_MAX_DIST] = {0};
	memcpy(dist, cam->dist, sizeof(double) * (size_t)cam->n_dist);
	double K[9];
	mvod_camera_K(cam, K);
	const double R[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
	double P[12];
	projection(cam, P);
	fprintf(f, "image_width: %d\nimage_height: %d\ncamera_name: camera\n", cam->width, cam->height);
	put_ros_matrix(f, "camera_matrix", 3, 3, K);
	fprintf(f, "distortion_model: %s\n", model);
	put_ros_matrix(f, "distortion_coefficients", 1, n, dist);
	put_ros_matrix(f, "rectification_matrix", 3, 3, R);
	put_ros_matrix(f, "projection_matrix", 3, 4, P);
	/* ROS's parsers ignore keys they do not know; mvod reads these back. */
	if (cam->has_mount) {
		const double v[3] = {cam->mount_height_m, cam->mount_pitch_deg, cam->mount_roll_deg};
		for (int i = 0; i < 3; i++) {
			fprintf(f, "%s: ", mvod_calib_mount_keys[i]);
			put_number(f, v[i]);
			fputc('\n', f);
		}
	}
	return write_text(path, &t, err, errlen);
}

int mvod_calib_save_kitti(const char *path, const struct mvod_camera *cam, char *err, size_t errlen)
{
	if (cam->model != MVOD_CAM_PINHOLE_RADTAN || mvod_camera_has_distortion(cam))
		return mvod_errf(err, errlen, -EINVAL,
			    "%s: KITTI calib.txt holds rectified (distortion-free) intrinsics only, and "
			    "this camera has %s distortion", path, mvod_cam_model_name(cam->model));
	struct text t;
	int ret = open_text(&t, path, err, errlen);
	if (ret)
		return ret;
	FILE *f = t.f;
	/* One camera: every P is the same [K | 0], for readers that expect all four lines. */
	double P[12];
	projection(cam, P);
	for (int i = 0; i < 4; i++) {
		fprintf(f, "P%d: ", i);
		put_numbers(f, P, 12, " ");
		fputc('\n', f);
	}
	return write_text(path, &t, err, errlen);
}

/* camera.txt's first line's name and how many coefficients follow fx fy cx cy; -EINVAL. */
static int dso_lens(const struct mvod_camera *cam, const char **name, int *n)
{
	for (int i = 4; cam->model == MVOD_CAM_PINHOLE_RADTAN && i < cam->n_dist; i++)
		if (cam->dist[i] != 0)
			return -EINVAL;
	static const char *const names[] = {[MVOD_CAM_PINHOLE_RADTAN] = "RadTan",
					    [MVOD_CAM_FISHEYE_KB4] = "KannalaBrandt",
					    [MVOD_CAM_FOV] = "FOV"};
	*name = mvod_camera_has_distortion(cam) ? names[cam->model] : "Pinhole";
	*n = !mvod_camera_has_distortion(cam) || cam->model == MVOD_CAM_FOV ? 1 : 4;
	return 0;
}

int mvod_calib_save_dso(const char *path, const struct mvod_camera *cam, char *err, size_t errlen)
{
	const char *name;
	int n;
	if (cam->width <= 0 || cam->height <= 0)
		return mvod_errf(err, errlen, -EINVAL, "%s: DSO's camera.txt needs the image size, "
				 "which the calibration lacks", path);
	/* In pixels DSO takes K as it is; within [0, 1) it would read cx, cy as fractions. */
	if (cam->cx >= 0 && cam->cx < 1 && cam->cy >= 0 && cam->cy < 1)
		return mvod_errf(err, errlen, -EINVAL, "%s: a principal point at (%g, %g) px would "
				 "read as DSO's relative form", path, cam->cx, cam->cy);
	if (dso_lens(cam, &name, &n))
		return mvod_errf(err, errlen, -EINVAL, "%s: DSO's RadTan lens has 4 coefficients "
				 "(k1 k2 p1 p2); this camera has more", path);
	struct text t;
	int ret = open_text(&t, path, err, errlen);
	if (ret)
		return ret;
	FILE *f = t.f;
	double v[8] = {cam->fx, cam->fy, cam->cx, cam->cy};
	memcpy(v + 4, cam->dist, sizeof(double) * (size_t)(n < cam->n_dist ? n : cam->n_dist));
	fprintf(f, "%s ", name);
	put_numbers(f, v, 4 + n, " ");
	/* DSO rectifies a lens into its largest whole view ("crop"); a pinhole passes ("none"). */
	fprintf(f, "\n%d %d\n%s\n%d %d\n", cam->width, cam->height,
		mvod_camera_has_distortion(cam) ? "crop" : "none", cam->width, cam->height);
	return write_text(path, &t, err, errlen);
}
