/*
 * euroc:DIR[?cam=N], the EuRoC MAV layout: DIR is a sequence folder holding mav0/, or mav0
 * itself. Frames from mav0/camN/data.csv ("timestamp [ns],filename", the files in camN/data/),
 * the camera from camN/sensor.yaml, the ground truth from
 * mav0/state_groundtruth_estimate0/data.csv (body poses, turned into this camera's by T_BS).
 */
#include "capture/backends.h"
#include "capture/path.h"

#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

#include "capture/dataset.h"
#include "capture/euroc_sensor.h"
#include "capture/uri.h"
#include "util/lines.h"

static bool is_dir(const char *path)
{
	struct stat st;
	return stat(path, &st) == 0 && S_ISDIR(st.st_mode);
}

static int take_param(void *ctx, const char *key, const char *value, char *err, size_t errlen)
{
	if (strcmp(key, "cam") != 0)
		return mvod_uri_unknown(key, "cam", err, errlen);
	return mvod_uri_int(key, value, 0, 9, ctx, err, errlen);
}

/* DIR/mav0/camN, or DIR/camN when DIR is mav0 itself. */
static int find_camera(const char *location, char *camdir, size_t len, char *mav0, size_t mlen,
		       char *err, size_t errlen)
{
	char dir[PATH_MAX], name[8];
	long cam = 0;
	int ret = mvod_uri_parse(location, dir, sizeof(dir), take_param, &cam, err, errlen);
	if (ret)
		return ret;
	snprintf(name, sizeof(name), "cam%ld", cam);
	ret = mvod_capture_path(mav0, mlen, dir, "mav0", err, errlen);
	if (!ret && !is_dir(mav0))
		snprintf(mav0, mlen, "%s", dir);
	if (!ret)
		ret = mvod_capture_path(camdir, len, mav0, name, err, errlen);
	if (!ret && !is_dir(camdir))
		ret = mvod_errf(err, errlen, -ENOENT, "%s is not a EuRoC sequence: neither %s/mav0/%s "
				"nor %s/%s exists (euroc:DIR takes the folder holding mav0/, or mav0; "
				"?cam=1 for the second camera)", dir, dir, name, dir, name);
	return ret;
}

struct index {
	struct mvod_ds_frames frames;
	const char *path; /* data.csv */
	char data[PATH_MAX]; /* camN/data */
};

/*
 * "1403636579763555584,1403636579763555584.png", the published files' lines ending in CRLF
 * (cut by the line reader); empty fields after the name (a trailing comma) are no column.
 */
static int add_frame(void *ctx, char *line, size_t lineno, char *err, size_t errlen)
{
	struct index *x = ctx;
	const char *end;
	int64_t ns;
	char *name = NULL, *rest = NULL;
	if (mvod_ds_parse_ns(line, &end, &ns) == 0 && *(end += strspn(end, " \t")) == ',') {
		name = (char *)end + 1 + strspn(end + 1, " \t");
		rest = name + strcspn(name, " \t,");
	}
	if (!name || rest[strspn(rest, " \t,")])
		return mvod_errf(err, errlen, -EINVAL, "%s line %zu: \"%.40s\" is not \"timestamp "
				 "[ns],filename\"", x->path, lineno, line);
	*rest = '\0';
	if (!*name)
		return mvod_errf(err, errlen, -EINVAL, "%s line %zu: no file name after the "
				 "timestamp", x->path, lineno);
	return mvod_ds_frames_add(&x->frames, x->path, lineno, x->data, name, ns, err, errlen);
}

/* "timestamp [ns], p_RS_R x y z [m], q_RS w x y z, ..." (velocities and biases follow). */
static int gt_line(const char *line, int64_t *ns, struct mvod_pose *body, char *why,
		   size_t whylen)
{
	const char *s;
	if (mvod_ds_parse_ns(line, &s, ns) < 0)
		return -EINVAL;
	return mvod_ds_parse_pose(s, ',', true, body, why, whylen);
}

static int euroc_open(void *priv, const char *location, char *err, size_t errlen)
{
	struct mvod_dataset *ds = priv;
	char camdir[PATH_MAX], mav0[PATH_MAX], sensor[PATH_MAX];
	struct index x = {.path = ds->index};
	int ret = find_camera(location, camdir, sizeof(camdir), mav0, sizeof(mav0), err, errlen);
	if (!ret)
		ret = mvod_capture_path(sensor, sizeof(sensor), camdir, "sensor.yaml", err, errlen);
	if (!ret)
		ret = mvod_capture_path(ds->index, sizeof(ds->index), camdir, "data.csv", err, errlen);
	if (!ret)
		ret = mvod_capture_path(x.data, sizeof(x.data), camdir, "data", err, errlen);
	if (!ret)
		ret = mvod_ds_optional(ds->gt_path, sizeof(ds->gt_path), mav0,
				       "state_groundtruth_estimate0/data.csv", err, errlen);
	/* The camera first: a sequence without one fails before any image is decoded. */
	if (!ret)
		ret = mvod_euroc_sensor_load(sensor, &ds->cam, &ds->body_cam, err, errlen);
	if (!ret)
		ret = mvod_lines_each(ds->index, "EuRoC data.csv", add_frame, &x, err, errlen);
	if (ret) {
		mvod_ds_frames_free(&x.frames);
		return ret;
	}
	ds->has_cam = true;
	ds->gt_line = gt_line;
	ds->gt_layout = "timestamp [ns], p_RS_R x, y, z [m], q_RS w, x, y, z, ...";
	return mvod_ds_open_frames(ds, &x.frames, err, errlen);
}

const struct mvod_source_ops mvod_source_euroc_ops = {
	.scheme = "euroc",
	.summary = "euroc:DIR[?cam=N]  EuRoC MAV sequence (DIR holds mav0/): camN/data.csv, "
		   "data/, sensor.yaml; ground truth from state_groundtruth_estimate0",
	.priv_size = sizeof(struct mvod_dataset),
	.open = euroc_open,
	.read = mvod_images_read,
	.info = mvod_images_info,
	.camera = mvod_ds_camera,
	.ground_truth = mvod_ds_ground_truth,
	.close = mvod_ds_close,
};
