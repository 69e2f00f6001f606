/*
 * EuRoC MAV's camN/sensor.yaml (the ASL dataset format): camera_model, intrinsics
 * [fu, fv, cu, cv], distortion_model and distortion_coefficients, resolution [w, h], and T_BS,
 * the camera (sensor) pose in the body frame, a 4x4 matrix of rows, cols and row-major data.
 * Read through util/cvyaml.c, the calibration files' OpenCV-flavoured YAML path: a copy made
 * for OpenCV's FileStorage begins with "%YAML:1.0" (Kimera-VIO asks for one in every file),
 * which plain libyaml refuses. Every error names the file and the line.
 */
#include "capture/euroc_sensor.h"

#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <yaml.h>

#include "util/cvyaml.h"
#include "util/errbuf.h"
#include "util/read_file.h"

/* A sensor.yaml is a few hundred bytes; anything past 1 MiB is no sensor file. */
#define SENSOR_MAX_BYTES (1u << 20)

struct sensor {
	const char *path;
	yaml_document_t doc;
	yaml_node_t *root;
};

/* The value under key in map, or NULL. */
static yaml_node_t *find(const struct sensor *s, const yaml_node_t *map, const char *key)
{
	return mvod_cvyaml_child((yaml_document_t *)&s->doc, map, key);
}

/* The node under key, or -EINVAL naming what is missing. */
static int need(const struct sensor *s, const yaml_node_t *map, const char *key, const char *what,
		yaml_node_t **out, char *err, size_t errlen)
{
	*out = find(s, map, key);
	if (!*out)
		return mvod_errf(err, errlen, -EINVAL, "%s has no %s (%s): is it a EuRoC camera "
				 "sensor.yaml?", s->path, key, what);
	return 0;
}

/* The scalar text of n, or "" for another kind of node. */
static const char *scalar_text(const yaml_node_t *n)
{
	return n->type == YAML_SCALAR_NODE ? (const char *)n->data.scalar.value : "";
}

/* A sequence of exactly count finite numbers. */
static int numbers(const struct sensor *s, const yaml_node_t *n, const char *key, double *v,
		   size_t count, char *err, size_t errlen)
{
	struct mvod_cvyaml_numbers m = mvod_cvyaml_numbers_into(v, count);
	if (mvod_cvyaml_sequence((yaml_document_t *)&s->doc, n, &m) != 0 || m.count != count ||
	    m.bad != SIZE_MAX)
		return mvod_errf(err, errlen, -EINVAL, "%s line %zu: %s must be a list of %zu "
				 "numbers", s->path, mvod_cvyaml_line(n), key, count);
	return 0;
}

static int lens(const struct sensor *s, struct mvod_camera *cam, char *err, size_t errlen)
{
	yaml_node_t *model, *coeffs;
	int ret = need(s, s->root, "distortion_model", "radial-tangential or equidistant", &model,
		       err, errlen);
	if (!ret)
		ret = need(s, s->root, "distortion_coefficients", "4 numbers", &coeffs, err, errlen);
	if (ret)
		return ret;
	const char *name = scalar_text(model);
	if (strcmp(name, "radial-tangential") == 0 || strcmp(name, "radtan") == 0)
		cam->model = MVOD_CAM_PINHOLE_RADTAN; /* k1 k2 p1 p2: OpenCV's order */
	else if (strcmp(name, "equidistant") == 0 || strcmp(name, "equi") == 0)
		cam->model = MVOD_CAM_FISHEYE_KB4; /* k1..k4: OpenCV's fisheye model */
	else
		return mvod_errf(err, errlen, -EINVAL, "%s line %zu: distortion_model \"%.40s\" is "
				 "not one mvod reads (radial-tangential, equidistant)", s->path,
				 mvod_cvyaml_line(model), name);
	cam->n_dist = 4;
	return numbers(s, coeffs, "distortion_coefficients", cam->dist, 4, err, errlen);
}

static int intrinsics(const struct sensor *s, struct mvod_camera *cam, char *err, size_t errlen)
{
	yaml_node_t *model, *k, *res;
	int ret = need(s, s->root, "camera_model", "pinhole", &model, err, errlen);
	if (!ret && strcmp(scalar_text(model), "pinhole") != 0)
		ret = mvod_errf(err, errlen, -EINVAL, "%s line %zu: camera_model \"%.40s\" is not one "
				"mvod reads (pinhole)", s->path, mvod_cvyaml_line(model), scalar_text(model));
	if (!ret)
		ret = need(s, s->root, "intrinsics", "fu, fv, cu, cv", &k, err, errlen);
	double v[4], wh[2];
	if (!ret)
		ret = numbers(s, k, "intrinsics [fu, fv, cu, cv]", v, 4, err, errlen);
	if (!ret)
		ret = need(s, s->root, "resolution", "width, height", &res, err, errlen);
	if (!ret)
		ret = numbers(s, res, "resolution [width, height]", wh, 2, err, errlen);
	if (ret)
		return ret;
	if (v[0] <= 0 || v[1] <= 0 || wh[0] < 1 || wh[1] < 1 || wh[0] > 65535 || wh[1] > 65535 ||
	    wh[0] != floor(wh[0]) || wh[1] != floor(wh[1]))
		return mvod_errf(err, errlen, -EINVAL, "%s line %zu: intrinsics or resolution out of "
				 "range (focal lengths must be positive, the size whole pixels)",
				 s->path, mvod_cvyaml_line(k));
	*cam = (struct mvod_camera){.width = (int)wh[0], .height = (int)wh[1], .fx = v[0],
				    .fy = v[1], .cx = v[2], .cy = v[3]};
	return lens(s, cam, err, errlen);
}

/* T_BS: a rigid transform, its rotation orthonormal to 1e-6 (EuRoC's hold 1e-9). */
static int extrinsics(const struct sensor *s, struct mvod_pose *body_cam, char *err,
		      size_t errlen)
{
	yaml_node_t *t;
	int ret = need(s, s->root, "T_BS", "the camera pose in the body frame", &t, err, errlen);
	if (ret)
		return ret;
	double m[16];
	struct mvod_cvyaml_numbers v = mvod_cvyaml_numbers_into(m, 16);
	int rows, cols;
	size_t line;
	char why[128];
	ret = mvod_cvyaml_matrix((yaml_document_t *)&s->doc, t, &rows, &cols, &v, &line, why,
				 sizeof(why));
	if (!ret && (rows != 4 || cols != 4))
		ret = mvod_errf(why, sizeof(why), -EINVAL, "must be 4 x 4, not %d x %d", rows, cols);
	if (ret)
		return mvod_errf(err, errlen, ret, "%s line %zu: T_BS %s", s->path, line, why);
	double RtR[9];
	for (int r = 0; r < 3; r++) {
		memcpy(body_cam->R + 3 * r, m + 4 * r, 3 * sizeof(double));
		body_cam->t[r] = m[4 * r + 3];
	}
	mvod_mat3_mul_at(body_cam->R, body_cam->R, RtR);
	double off = fabs(m[12]) + fabs(m[13]) + fabs(m[14]) + fabs(m[15] - 1);
	for (int k = 0; k < 9; k++)
		off = fmax(off, fabs(RtR[k] - (k % 4 == 0)));
	if (off > 1e-6 || mvod_mat3_det(body_cam->R) < 0)
		return mvod_errf(err, errlen, -EINVAL, "%s line %zu: T_BS is not a rigid transform "
				 "(a rotation and a translation, last row 0 0 0 1)", s->path, line);
	return 0;
}

static int load(struct sensor *s, const char *text, char *err, size_t errlen)
{
	char why[256];
	int ret = mvod_cvyaml_load(text, &s->doc, why, sizeof(why));
	if (ret)
		return mvod_errf(err, errlen, ret, "%s%s%s", s->path,
				 ret == -EINVAL ? ": not YAML: " : " ", why); /* guard: "line N: ..." */
	s->root = yaml_document_get_root_node(&s->doc);
	if (!s->root || s->root->type != YAML_MAPPING_NODE)
		ret = mvod_errf(err, errlen, -EINVAL, "%s is not a EuRoC sensor.yaml (no mapping "
				"at the top)", s->path);
	yaml_node_t *type = ret ? NULL : find(s, s->root, "sensor_type");
	if (type && strcmp(scalar_text(type), "camera") != 0)
		ret = mvod_errf(err, errlen, -EINVAL, "%s line %zu: sensor_type \"%.40s\" is no "
				"camera: take a camN folder's sensor.yaml", s->path, mvod_cvyaml_line(type),
				scalar_text(type));
	if (ret)
		yaml_document_delete(&s->doc);
	return ret;
}

int mvod_euroc_sensor_load(const char *path, struct mvod_camera *cam, struct mvod_pose *body_cam,
			   char *err, size_t errlen)
{
	char *text = NULL;
	int ret = mvod_read_file(path, SENSOR_MAX_BYTES, "EuRoC sensor file", 0, &text, NULL, err,
				 errlen);
	if (ret)
		return ret;
	struct sensor s = {.path = path};
	ret = load(&s, text, err, errlen);
	if (ret == 0) {
		ret = intrinsics(&s, cam, err, errlen);
		if (ret == 0)
			ret = extrinsics(&s, body_cam, err, errlen);
		yaml_document_delete(&s.doc);
	}
	free(text);
	return ret;
}
