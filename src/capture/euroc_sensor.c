/*
 * EuRoC MAV's camN/sensor.yaml (the ASL dataset format): camera_model, intrinsics
 * [fu, fv, cu, cv], distortion_model and distortion_coefficients, resolution [w, h], and T_BS,
 * the camera (sensor) pose in the body frame, 4x4 row-major in data. Read with libyaml, as the
 * calibration files are; every error names the file and the line.
 */
#include "capture/euroc.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <yaml.h>

#include "util/errbuf.h"
#include "util/read_file.h"
#include "util/text_guard.h"

/* A sensor.yaml is a few hundred bytes; anything past 1 MiB is no sensor file. */
#define SENSOR_MAX_BYTES (1u << 20)

struct sensor {
	const char *path;
	yaml_document_t doc;
	yaml_node_t *root;
};

static size_t line_of(const yaml_node_t *n)
{
	return n->start_mark.line + 1;
}

/* The value under key in the root mapping, or NULL. */
static yaml_node_t *find(const struct sensor *s, const yaml_node_t *map, const char *key)
{
	if (!map || map->type != YAML_MAPPING_NODE)
		return NULL;
	for (yaml_node_pair_t *p = map->data.mapping.pairs.start; p < map->data.mapping.pairs.top;
	     p++) {
		yaml_node_t *k = yaml_document_get_node((yaml_document_t *)&s->doc, p->key);
		if (k && k->type == YAML_SCALAR_NODE && k->data.scalar.length == strlen(key) &&
		    memcmp(k->data.scalar.value, key, k->data.scalar.length) == 0)
			return yaml_document_get_node((yaml_document_t *)&s->doc, p->value);
	}
	return NULL;
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
	size_t k = 0;
	bool ok = n->type == YAML_SEQUENCE_NODE;
	for (yaml_node_item_t *i = ok ? n->data.sequence.items.start : NULL;
	     ok && i < n->data.sequence.items.top; i++, k++) {
		const yaml_node_t *e = yaml_document_get_node((yaml_document_t *)&s->doc, *i);
		char *end = NULL;
		double x = e && e->type == YAML_SCALAR_NODE ? strtod(scalar_text(e), &end) : NAN;
		ok = k < count && end && end != scalar_text(e) && *end == '\0' && isfinite(x);
		if (ok)
			v[k] = x;
	}
	if (!ok || k != count)
		return mvod_errf(err, errlen, -EINVAL, "%s line %zu: %s must be a list of %zu "
				 "numbers", s->path, line_of(n), key, count);
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
				 line_of(model), name);
	cam->n_dist = 4;
	return numbers(s, coeffs, "distortion_coefficients", cam->dist, 4, err, errlen);
}

static int intrinsics(const struct sensor *s, struct mvod_camera *cam, char *err, size_t errlen)
{
	yaml_node_t *model, *k, *res;
	int ret = need(s, s->root, "camera_model", "pinhole", &model, err, errlen);
	if (!ret && strcmp(scalar_text(model), "pinhole") != 0)
		ret = mvod_errf(err, errlen, -EINVAL, "%s line %zu: camera_model \"%.40s\" is not one "
				"mvod reads (pinhole)", s->path, line_of(model), scalar_text(model));
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
				 s->path, line_of(k));
	*cam = (struct mvod_camera){.width = (int)wh[0], .height = (int)wh[1], .fx = v[0],
				    .fy = v[1], .cx = v[2], .cy = v[3]};
	return lens(s, cam, err, errlen);
}

/* T_BS: a rigid transform, its rotation orthonormal to 1e-6 (EuRoC's hold 1e-9). */
static int extrinsics(const struct sensor *s, struct mvod_pose *body_cam, char *err,
		      size_t errlen)
{
	yaml_node_t *t, *data;
	int ret = need(s, s->root, "T_BS", "the camera pose in the body frame", &t, err, errlen);
	if (!ret)
		ret = need(s, t, "data", "16 numbers, row-major", &data, err, errlen);
	double m[16];
	if (!ret)
		ret = numbers(s, data, "T_BS data", m, 16, err, errlen);
	if (ret)
		return ret;
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
				 "(a rotation and a translation, last row 0 0 0 1)", s->path,
				 line_of(data));
	return 0;
}

static int load(struct sensor *s, const char *text, char *err, size_t errlen)
{
	yaml_parser_t parser;
	if (!yaml_parser_initialize(&parser))
		return mvod_errf(err, errlen, -ENOMEM, "out of memory reading %s", s->path);
	size_t len = strlen(text);
	yaml_parser_set_input_string(&parser, (const unsigned char *)text, len);
	char why[256];
	int ret = mvod_text_guard(text, len, MVOD_TEXT_YAML, why, sizeof(why));
	if (ret)
		mvod_errf(err, errlen, ret, "%s %s", s->path, why);
	else if (!yaml_parser_load(&parser, &s->doc))
		ret = mvod_errf(err, errlen, -EINVAL, "%s line %zu: not YAML: %s", s->path,
				parser.problem_mark.line + 1,
				parser.problem ? parser.problem : "?");
	yaml_parser_delete(&parser);
	if (ret)
		return ret;
	s->root = yaml_document_get_root_node(&s->doc);
	if (!s->root || s->root->type != YAML_MAPPING_NODE)
		ret = mvod_errf(err, errlen, -EINVAL, "%s is not a EuRoC sensor.yaml (no mapping "
				"at the top)", s->path);
	yaml_node_t *type = ret ? NULL : find(s, s->root, "sensor_type");
	if (type && strcmp(scalar_text(type), "camera") != 0)
		ret = mvod_errf(err, errlen, -EINVAL, "%s line %zu: sensor_type \"%.40s\" is no "
				"camera: take a camN folder's sensor.yaml", s->path, line_of(type),
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
