/*
 * DSO's camera.txt, which TUM's monoVO dataset ships with every sequence: JakobEngel/dso's
 * README ("Geometric Calibration File") and Undistort.cpp, tum-vision/mono_dataset_code's
 * FOVUndistorter.cpp. Line 1 is the lens, "MODEL fx fy cx cy params..." (the name may be left
 * out: 5 numbers are the FOV lens, or a pinhole when w is 0; 8 are RadTan); line 2 the image
 * size "width height"; then, optionally, how DSO rectifies ("crop", "full", "none" or
 * "fx fy cx cy 0") and its output size, which mvod checks but does not use: it undistorts into
 * its own pinhole (the input's intrinsics, scaled by --resize).
 */
#include "mvod/calib.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "camera/calib_internal.h"
#include "util/errbuf.h"
#include "util/numbers.h"

static const struct {
	const char *name;
	enum mvod_cam_model model;
	int n; /* numbers after the name: fx fy cx cy, then the lens's */
} models[] = {
	{"Pinhole", MVOD_CAM_PINHOLE_RADTAN, 5}, {"RadTan", MVOD_CAM_PINHOLE_RADTAN, 8},
	{"EquiDistant", MVOD_CAM_FISHEYE_KB4, 8}, {"KannalaBrandt", MVOD_CAM_FISHEYE_KB4, 8},
	/* ATAN: PTAM's name for the same lens, and what DSO calls a bare line of 5 numbers. */
	{"FOV", MVOD_CAM_FOV, 5},                {"ATAN", MVOD_CAM_FOV, 5},
};
#define N_MODELS (sizeof(models) / sizeof(models[0]))

/* Where line lineno (from 1) of text starts, or NULL past the end. */
static const char *line_start(const char *text, size_t lineno)
{
	for (size_t i = 1; i < lineno && text; i++)
		text = strchr(text, '\n') ? strchr(text, '\n') + 1 : NULL;
	return text;
}

/* Line lineno of text, its CR cut, into buf; "" past the end. -E2BIG when it does not fit. */
static int line_at(const char *text, size_t lineno, char *buf, size_t len)
{
	text = line_start(text, lineno);
	size_t n = text ? strcspn(text, "\n") : 0;
	if (n >= len)
		return -E2BIG;
	memcpy(buf, text ? text : "", n);
	buf[n] = '\0';
	buf[strcspn(buf, "\r")] = '\0';
	return 0;
}

/* The model named at the start of line, or -1 for none of DSO's names. */
static int named(const char *line)
{
	const char *s = line + strspn(line, " \t");
	size_t len = strcspn(s, " \t");
	for (size_t i = 0; i < N_MODELS; i++)
		if (len == strlen(models[i].name) && strncmp(s, models[i].name, len) == 0)
			return (int)i;
	return -1;
}

/* Line 1: which model and its numbers; -1 when the line is none of DSO's. */
static int lens_line(const char *line, enum mvod_cam_model *model, double v[8])
{
	const char *s = line + strspn(line, " \t");
	int i = named(s);
	if (i >= 0) {
		*model = models[i].model;
		int n = mvod_parse_numbers(s + strlen(models[i].name), v, 8);
		return n == models[i].n ? n : -1;
	}
	int n = mvod_parse_numbers(s, v, 8);
	*model = n == 5 ? MVOD_CAM_FOV : MVOD_CAM_PINHOLE_RADTAN;
	return n == 5 || n == 8 ? n : -1;
}

bool mvod_calib_is_dso(const char *text)
{
	char line[512];
	enum mvod_cam_model model;
	double v[8];
	return line_at(text, 1, line, sizeof(line)) == 0 &&
	       (named(line) >= 0 || lens_line(line, &model, v) > 0);
}

/* "width height": two whole numbers of pixels, nothing else. */
static bool size_line(const char *line, int *w, int *h)
{
	double v[2];
	if (mvod_parse_numbers(line, v, 2) != 2 || v[0] != floor(v[0]) || v[1] != floor(v[1]) ||
	    v[0] < 1 || v[1] < 1 || v[0] > 65535 || v[1] > 65535)
		return false;
	*w = (int)v[0];
	*h = (int)v[1];
	return true;
}

/*
 * DSO's relative form (0 <= cx, cy < 1): fractions of the image, pixel edges at 0 (its
 * README). A negative principal point is in pixels (outside the image's left or top edge),
 * not a fraction: taken for one, it made "fx = 368640 px" of a 576 px focal length.
 */
static void from_relative(struct mvod_camera *cam)
{
	if (!(cam->cx >= 0 && cam->cx < 1 && cam->cy >= 0 && cam->cy < 1))
		return;
	cam->fx *= cam->width;
	cam->fy *= cam->height;
	cam->cx = cam->cx * cam->width - 0.5;
	cam->cy = cam->cy * cam->height - 0.5;
}

/* The lens of line 1 (n numbers in v) as mvod's camera; false for Pinhole's 5th not 0. */
static bool set_lens(enum mvod_cam_model model, const double *v, int n, struct mvod_camera *c)
{
	c->fx = v[0];
	c->fy = v[1];
	c->cx = v[2];
	c->cy = v[3];
	c->model = model;
	/* A pinhole is FOV with w = 0 (DSO's rule for 5 bare numbers): no lens, no coefficient. */
	if (n == 5 && (model == MVOD_CAM_PINHOLE_RADTAN || v[4] == 0)) {
		c->model = MVOD_CAM_PINHOLE_RADTAN;
		return v[4] == 0;
	}
	c->n_dist = n - 4;
	memcpy(c->dist, v + 4, (size_t)c->n_dist * sizeof(double));
	return true;
}

/* Lines 3 and 4, optional: how DSO rectifies, and its output size; then nothing more. */
static int rectification(const char *text, const char *path, char *err, size_t errlen)
{
	char l3[512], l4[512];
	double v[5];
	int w, h;
	if (line_at(text, 3, l3, sizeof(l3)) || line_at(text, 4, l4, sizeof(l4)))
		return mvod_errf(err, errlen, -EINVAL, "%s: a line past 511 characters: not DSO's "
				 "camera.txt", path);
	if (!l3[strspn(l3, " \t")])
		return 0;
	if (strcmp(l3, "crop") != 0 && strcmp(l3, "full") != 0 && strcmp(l3, "none") != 0 &&
	    !(mvod_parse_numbers(l3, v, 5) == 5 && v[4] == 0))
		return mvod_errf(err, errlen, -EINVAL, "%s line 3: \"%.40s\" is none of DSO's "
				 "rectifications (crop, full, none, or fx fy cx cy 0)", path, l3);
	if (!size_line(l4, &w, &h))
		return mvod_errf(err, errlen, -EINVAL, "%s line 4: expected the output size \"width "
				 "height\" after line 3's rectification", path);
	/* Blank lines may follow, nothing else. */
	const char *rest = line_start(text, 5), *bad = rest ? rest + strspn(rest, " \t\r\n") : NULL;
	if (bad && *bad) {
		size_t lineno = 5;
		for (const char *p = rest; p < bad; p++)
			lineno += *p == '\n';
		return mvod_errf(err, errlen, -EINVAL, "%s line %zu: DSO's camera.txt has 4 lines "
				 "and nothing after them", path, lineno);
	}
	return 0;
}

int mvod_calib_parse_dso(const char *text, const char *path, struct mvod_camera *cam, char *err,
			 size_t errlen)
{
	char l1[512], l2[512];
	double v[8];
	enum mvod_cam_model model;
	struct mvod_camera c = {0};
	int n = line_at(text, 1, l1, sizeof(l1)) ? -1 : lens_line(l1, &model, v);
	if (n < 0 || !set_lens(model, v, n, &c))
		return mvod_errf(err, errlen, -EINVAL, "%s line 1: \"%.40s\" is not one of DSO's "
				 "lenses (FOV fx fy cx cy w, Pinhole fx fy cx cy 0, RadTan or "
				 "EquiDistant or KannalaBrandt fx fy cx cy and 4 coefficients; the name "
				 "may be left out of FOV and RadTan)", path, l1);
	if (line_at(text, 2, l2, sizeof(l2)) || !size_line(l2, &c.width, &c.height))
		return mvod_errf(err, errlen, -EINVAL, "%s line 2: expected the image size \"width "
				 "height\" in pixels", path);
	from_relative(&c);
	if (!(c.fx > 0 && c.fy > 0))
		return mvod_errf(err, errlen, -EINVAL, "%s line 1: the focal lengths must be "
				 "positive", path);
	int ret = rectification(text, path, err, errlen);
	if (!ret)
		*cam = c;
	return ret;
}
