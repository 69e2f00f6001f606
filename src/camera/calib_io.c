#include "mvod/calib.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <cjson/cJSON.h>

#include "camera/calib_internal.h"
#include "util/atomic_file.h"
#include "util/errbuf.h"
#include "util/input.h"
#include "util/read_file.h"
#include "util/text_guard.h"

/* Calibration files are small; anything bigger is not one. */
#define CALIB_MAX_BYTES (4 * 1024 * 1024)

static int json_number_array(const cJSON *arr, double *dst, int min, int max, int *count)
{
	if (!cJSON_IsArray(arr))
		return -EINVAL;
	int n = cJSON_GetArraySize(arr);
	if (n < min || n > max)
		return -EINVAL;
	for (int i = 0; i < n; i++) {
		const cJSON *v = cJSON_GetArrayItem(arr, i);
		if (!cJSON_IsNumber(v) || !isfinite(v->valuedouble))
			return -EINVAL;
		dst[i] = v->valuedouble;
	}
	if (count)
		*count = n;
	return 0;
}

/* K as [[fx,0,cx],[0,fy,cy],[0,0,1]] or as 9 numbers row-major. */
static int json_K(const cJSON *K, struct mvod_camera *cam)
{
	double k[9];
	if (json_number_array(K, k, 9, 9, NULL) != 0) {
		if (!cJSON_IsArray(K) || cJSON_GetArraySize(K) != 3)
			return -EINVAL;
		for (int r = 0; r < 3; r++)
			if (json_number_array(cJSON_GetArrayItem(K, r), k + 3 * r, 3, 3, NULL) != 0)
				return -EINVAL;
	}
	return mvod_calib_set_K(k, cam);
}

static cJSON *json_parse(const char *text, char *err, size_t errlen)
{
	if (mvod_text_guard(text, strlen(text), MVOD_TEXT_JSON, err, errlen))
		return NULL;
	cJSON *root = cJSON_Parse(text);
	if (!root)
		mvod_errf(err, errlen, -EINVAL, "not valid JSON (near: %.20s)",
			  cJSON_GetErrorPtr() ? cJSON_GetErrorPtr() : "?");
	return root;
}

/* The optional "mount" block: {"height_m": H, "pitch_deg": P, "roll_deg": R}. */
static int json_mount(const cJSON *root, struct mvod_camera *c, char *err, size_t errlen)
{
	const cJSON *m = cJSON_GetObjectItemCaseSensitive(root, "mount");
	if (!m || cJSON_IsNull(m))
		return 0;
	const cJSON *h = cJSON_GetObjectItemCaseSensitive(m, "height_m");
	const cJSON *p = cJSON_GetObjectItemCaseSensitive(m, "pitch_deg");
	const cJSON *r = cJSON_GetObjectItemCaseSensitive(m, "roll_deg");
	if (!cJSON_IsObject(m) || !cJSON_IsNumber(h) || (p && !cJSON_IsNumber(p)) ||
	    (r && !cJSON_IsNumber(r)) ||
	    !mvod_calib_mount_ok(h->valuedouble, p ? p->valuedouble : 0, r ? r->valuedouble : 0))
		return mvod_errf(err, errlen, -EINVAL,
				 "\"mount\" must be {\"height_m\": metres above the ground, in (0, %g], "
				 "\"pitch_deg\": degrees down, \"roll_deg\": degrees, each within "
				 "+-%g}: correct it or remove it",
				 MVOD_MOUNT_MAX_HEIGHT_M, MVOD_MOUNT_MAX_ANGLE_DEG);
	c->has_mount = true;
	c->mount_height_m = h->valuedouble;
	c->mount_pitch_deg = p ? p->valuedouble : 0.0;
	c->mount_roll_deg = r ? r->valuedouble : 0.0;
	return 0;
}

/* The optional "verdict" of mvod calibrate, kept for mvod run's warning. */
static int json_verdict(const cJSON *root, struct mvod_camera *c, char *err, size_t errlen)
{
	const cJSON *v = cJSON_GetObjectItemCaseSensitive(root, "verdict");
	if (!v || cJSON_IsNull(v))
		return 0;
	if (!cJSON_IsString(v) || strlen(v->valuestring) >= sizeof(c->verdict))
		return mvod_errf(err, errlen, -EINVAL, "\"verdict\" must be mvod calibrate's verdict, "
				 "a string such as \"good\" (at most %zu characters)",
				 sizeof(c->verdict) - 1);
	snprintf(c->verdict, sizeof(c->verdict), "%s", v->valuestring);
	return 0;
}

static int json_camera(const cJSON *root, struct mvod_camera *cam, char *err, size_t errlen)
{
	struct mvod_camera c = {0};
	int ret = 0;
	const cJSON *fmt = cJSON_GetObjectItemCaseSensitive(root, "format");
	if (!cJSON_IsString(fmt) || strcmp(fmt->valuestring, MVOD_CALIB_FORMAT) != 0) {
		ret = mvod_errf(err, errlen, -EINVAL, "\"format\" must be \"%s\"", MVOD_CALIB_FORMAT);
		goto out;
	}
	const cJSON *model = cJSON_GetObjectItemCaseSensitive(root, "model");
	if (!cJSON_IsString(model) || mvod_cam_model_parse(model->valuestring, &c.model) != 0) {
		ret = mvod_errf(err, errlen, -EINVAL,
			   "\"model\" must be \"pinhole-radtan\", \"fisheye-kb4\" or \"fov\"");
		goto out;
	}
	double size[2];
	if (json_number_array(cJSON_GetObjectItemCaseSensitive(root, "image_size"), size, 2, 2,
			      NULL) != 0 ||
	    size[0] < 1 || size[1] < 1 || size[0] > 65535 || size[1] > 65535 ||
	    size[0] != floor(size[0]) || size[1] != floor(size[1])) {
		ret = mvod_errf(err, errlen, -EINVAL, "\"image_size\" must be [width, height] in pixels");
		goto out;
	}
	c.width = (int)size[0];
	c.height = (int)size[1];
	if (json_K(cJSON_GetObjectItemCaseSensitive(root, "K"), &c) != 0 || !mvod_calib_intrinsics_ok(&c)) {
		ret = mvod_errf(err, errlen, -EINVAL,
			   "\"K\" must be [[fx,0,cx],[0,fy,cy],[0,0,1]] with fx, fy > 0");
		goto out;
	}
	const cJSON *dist = cJSON_GetObjectItemCaseSensitive(root, "distortion");
	if (json_number_array(dist, c.dist, 0, MVOD_MAX_DIST, &c.n_dist) != 0 ||
	    !mvod_calib_dist_count_ok(c.model, c.n_dist)) {
		ret = mvod_errf(err, errlen, -EINVAL,
			   "\"distortion\" must hold %s numbers for model %s",
			   mvod_calib_dist_counts(c.model), mvod_cam_model_name(c.model));
		goto out;
	}
	const cJSON *focus = cJSON_GetObjectItemCaseSensitive(root, "focus");
	if (focus && !cJSON_IsNull(focus)) {
		if (!cJSON_IsNumber(focus) || !isfinite(focus->valuedouble)) {
			ret = mvod_errf(err, errlen, -EINVAL, "\"focus\" must be a number (the lens "
				   "focus position the calibration was made at)");
			goto out;
		}
		c.has_focus = true;
		c.focus = focus->valuedouble;
	}
	ret = json_mount(root, &c, err, errlen);
	ret = ret ? ret : json_verdict(root, &c, err, errlen);
	if (!ret)
		*cam = c;
out:
	return ret;
}

typedef int json_reader(const cJSON *root, struct mvod_camera *cam, char *err, size_t errlen);

static int parse_with(json_reader *read, const char *text, struct mvod_camera *cam, char *err, size_t errlen)
{
	cJSON *root = json_parse(text, err, errlen);
	int ret = root ? read(root, cam, err, errlen) : -EINVAL;
	cJSON_Delete(root);
	return ret;
}

int mvod_calib_parse_json(const char *text, struct mvod_camera *cam, char *err, size_t errlen)
{
	return parse_with(json_camera, text, cam, err, errlen);
}

/* Coefficients as [k1, ...] or as numpy's 1xN [[k1, ...]]. */
static int json_dist(const cJSON *d, struct mvod_camera *c)
{
	if (cJSON_GetArraySize(d) == 1 && cJSON_IsArray(cJSON_GetArrayItem(d, 0)))
		d = cJSON_GetArrayItem(d, 0);
	if (json_number_array(d, c->dist, 0, MVOD_MAX_DIST, &c->n_dist) != 0 ||
	    !mvod_calib_dist_count_ok(c->model, c->n_dist))
		return -EINVAL;
	return 0;
}

/* The object form may name the model; the array form cannot. */
static int json_pair_model(const cJSON *root, struct mvod_camera *c)
{
	const cJSON *model = cJSON_GetObjectItemCaseSensitive(root, "model");
	if (!model)
		return 0;
	return cJSON_IsString(model) ? mvod_cam_model_parse(model->valuestring, &c->model) : -EINVAL;
}

static int json_pair_camera(const cJSON *root, struct mvod_camera *cam, char *err, size_t errlen)
{
	struct mvod_camera c = {.model = MVOD_CAM_PINHOLE_RADTAN};
	int ret = 0;
	bool array = cJSON_IsArray(root);
	const char *kname = array ? "element 0 (K)" : "\"K\"";
	const char *dname = array ? "element 1 (distortion)" : "\"dist\"";
	if (!(array ? cJSON_GetArraySize(root) == 2 : cJSON_IsObject(root))) {
		ret = mvod_errf(err, errlen, -EINVAL,
			   "expected [K, dist] or {\"K\": K, \"dist\": dist} (or mvod JSON with \"format\")");
	} else if (!array && json_pair_model(root, &c) != 0) {
		ret = mvod_errf(err, errlen, -EINVAL,
			   "\"model\" must be \"pinhole-radtan\", \"fisheye-kb4\" or \"fov\"");
	} else if (json_K(array ? cJSON_GetArrayItem(root, 0) : cJSON_GetObjectItemCaseSensitive(root, "K"),
			  &c) != 0) {
		ret = mvod_errf(err, errlen, -EINVAL,
			   "%s must be [[fx,0,cx],[0,fy,cy],[0,0,1]] with fx, fy > 0", kname);
	} else if (json_dist(array ? cJSON_GetArrayItem(root, 1)
				   : cJSON_GetObjectItemCaseSensitive(root, "dist"), &c) != 0) {
		ret = mvod_errf(err, errlen, -EINVAL, "%s must hold %s numbers for model %s", dname,
			   mvod_calib_dist_counts(c.model), mvod_cam_model_name(c.model));
	} else {
		*cam = c;
	}
	return ret;
}

int mvod_calib_parse_json_pair(const char *text, struct mvod_camera *cam, char *err, size_t errlen)
{
	return parse_with(json_pair_camera, text, cam, err, errlen);
}

/* mvod JSON carries "format"; any other JSON is read as a [K, dist] pair. */
static int json_any_camera(const char *text, struct mvod_camera *cam, enum mvod_calib_format *fmt,
			   char *err, size_t errlen)
{
	cJSON *root = json_parse(text, err, errlen);
	if (!root)
		return -EINVAL;
	bool mvod = cJSON_IsObject(root) && cJSON_GetObjectItemCaseSensitive(root, "format");
	*fmt = mvod ? MVOD_CALIB_FMT_MVOD : MVOD_CALIB_FMT_PAIR;
	int ret = (mvod ? json_camera : json_pair_camera)(root, cam, err, errlen);
	cJSON_Delete(root);
	return ret;
}

/* "P0: 12 numbers": fx = P[0], cx = P[2], fy = P[5], cy = P[6]. */
static int parse_kitti(const char *text, struct mvod_camera *cam)
{
	const char *line = text;
	while (line && *line) {
		if (strncmp(line, "P0:", 3) == 0) {
			double p[12];
			const char *s = line + 3;
			for (int i = 0; i < 12; i++) {
				char *end;
				p[i] = strtod(s, &end);
				if (end == s || !isfinite(p[i]))
					return -EINVAL;
				s = end;
			}
			*cam = (struct mvod_camera){.fx = p[0], .cx = p[2], .fy = p[5], .cy = p[6],
						    .model = MVOD_CAM_PINHOLE_RADTAN};
			return mvod_calib_intrinsics_ok(cam) ? 0 : -EINVAL;
		}
		line = strchr(line, '\n');
		if (line)
			line++;
	}
	return -ENOENT;
}

static int kitti_camera(const char *text, struct mvod_camera *cam, char *err, size_t errlen)
{
	int ret = parse_kitti(text, cam);
	if (ret == -ENOENT)
		return mvod_errf(err, errlen, -EINVAL, "no \"P0:\" line (not a KITTI calib.txt)");
	if (ret)
		return mvod_errf(err, errlen, -EINVAL, "\"P0:\" needs 12 numbers with fx, fy > 0");
	return 0;
}

/* The format text is in, by its content; DSO's names the file and line itself. */
static int parse_any(const char *text, const char *path, const enum mvod_calib_format *only,
		     struct mvod_camera *cam, enum mvod_calib_format *fmt, char *err, size_t errlen)
{
	const char *p = text + strspn(text, " \t\r\n");
	const bool json = *p == '{' || *p == '[';
	char why[256] = "";
	int ret;
	*fmt = only ? *only : MVOD_CALIB_FMT_KITTI;
	if (*p && (only ? *only == MVOD_CALIB_FMT_DSO : mvod_calib_is_dso(text))) {
		*fmt = MVOD_CALIB_FMT_DSO;
		return mvod_calib_parse_dso(text, path, cam, err, errlen);
	}
	if (!*p)
		ret = mvod_errf(why, sizeof(why), -EINVAL, "the file is empty");
	else if (only || (!json && strstr(text, "P0:")))
		ret = kitti_camera(text, cam, why, sizeof(why));
	else if (json)
		ret = json_any_camera(p, cam, fmt, why, sizeof(why));
	else
		ret = mvod_calib_parse_filestorage(text, cam, fmt, why, sizeof(why));
	return ret ? mvod_errf(err, errlen, ret, "%s: %s", path, why) : 0;
}

/* Read once, parsed once by the reader the content (or only, when not NULL) asks for. */
static int load_text(const char *path, const enum mvod_calib_format *only,
		     struct mvod_camera *cam, enum mvod_calib_format *fmt, char *err, size_t errlen)
{
	char *text = NULL;
	int ret = mvod_read_file(path, CALIB_MAX_BYTES, "calibration file", MVOD_INPUT_STREAM,
				 &text, NULL, err, errlen);
	if (ret)
		return ret;
	/* A UTF-8 byte order mark (Windows editors write one) is no part of the text. */
	const char *body = strncmp(text, "\xEF\xBB\xBF", 3) == 0 ? text + 3 : text;
	enum mvod_calib_format f;
	ret = parse_any(body, path, only, cam, &f, err, errlen);
	free(text);
	if (!ret && fmt)
		*fmt = f;
	return ret;
}

int mvod_calib_load_kitti(const char *path, struct mvod_camera *cam, char *err, size_t errlen)
{
	const enum mvod_calib_format kitti = MVOD_CALIB_FMT_KITTI;
	return load_text(path, &kitti, cam, NULL, err, errlen);
}

int mvod_calib_load_dso(const char *path, struct mvod_camera *cam, char *err, size_t errlen)
{
	const enum mvod_calib_format dso = MVOD_CALIB_FMT_DSO;
	return load_text(path, &dso, cam, NULL, err, errlen);
}

int mvod_calib_load_format(const char *path, struct mvod_camera *cam, enum mvod_calib_format *fmt,
			   char *err, size_t errlen)
{
	return load_text(path, NULL, cam, fmt, err, errlen);
}

int mvod_calib_load(const char *path, struct mvod_camera *cam, char *err, size_t errlen)
{
	return mvod_calib_load_format(path, cam, NULL, err, errlen);
}

static cJSON *number_row(const double *v, int n)
{
	return cJSON_CreateDoubleArray(v, n);
}

/* Per-view records: [{"frame": i, "rms_px": e, "rvec": [..], "tvec": [..]}, ...] in the order used. */
static cJSON *views_to_json(const struct mvod_calib_meta *meta)
{
	cJSON *views = cJSON_CreateArray();
	for (int i = 0; views && i < meta->n_views; i++) {
		cJSON *v = cJSON_CreateObject();
		if (meta->view_frame)
			cJSON_AddNumberToObject(v, "frame", (double)meta->view_frame[i]);
		cJSON_AddNumberToObject(v, "rms_px", meta->view_rms_px[i]);
		if (meta->view_pose) {
			cJSON_AddItemToObject(v, "rvec", number_row(meta->view_pose + 6 * i, 3));
			cJSON_AddItemToObject(v, "tvec", number_row(meta->view_pose + 6 * i + 3, 3));
		}
		cJSON_AddItemToArray(views, v);
	}
	return views;
}

static void meta_to_json(cJSON *root, const struct mvod_camera *cam,
			 const struct mvod_calib_meta *meta)
{
	if (meta->rms_px >= 0)
		cJSON_AddNumberToObject(root, "rms_px", meta->rms_px);
	if (meta->has_std) {
		cJSON *sd = cJSON_AddObjectToObject(root, "std_dev");
		cJSON_AddItemToObject(sd, "fx_fy_cx_cy", number_row(meta->std_K, 4));
		cJSON_AddItemToObject(sd, "distortion", number_row(meta->std_dist, cam->n_dist));
	}
	/* A file converted from mvod JSON keeps the verdict it recorded. */
	const char *verdict = meta->verdict[0] ? meta->verdict : cam->verdict;
	if (verdict[0])
		cJSON_AddStringToObject(root, "verdict", verdict);
	if (meta->board[0])
		cJSON_AddStringToObject(root, "board", meta->board);
	if (meta->source[0])
		cJSON_AddStringToObject(root, "source", meta->source);
	if (meta->n_views > 0 && meta->view_rms_px) {
		cJSON_AddNumberToObject(root, "views_used", meta->n_views);
		cJSON_AddItemToObject(root, "views", views_to_json(meta));
	}
}

static cJSON *calib_to_json(const struct mvod_camera *cam, const struct mvod_calib_meta *meta)
{
	cJSON *root = cJSON_CreateObject();
	if (!root)
		return NULL;
	cJSON_AddStringToObject(root, "format", MVOD_CALIB_FORMAT);
	cJSON_AddStringToObject(root, "model", mvod_cam_model_name(cam->model));
	double size[2] = {cam->width, cam->height};
	cJSON_AddItemToObject(root, "image_size", number_row(size, 2));
	double K[9];
	mvod_camera_K(cam, K);
	cJSON *k = cJSON_CreateArray();
	for (int r = 0; r < 3; r++)
		cJSON_AddItemToArray(k, number_row(K + 3 * r, 3));
	cJSON_AddItemToObject(root, "K", k);
	cJSON_AddItemToObject(root, "distortion", number_row(cam->dist, cam->n_dist));
	if (cam->has_focus)
		cJSON_AddNumberToObject(root, "focus", cam->focus);
	if (cam->has_mount) {
		cJSON *m = cJSON_AddObjectToObject(root, "mount");
		cJSON_AddNumberToObject(m, "height_m", cam->mount_height_m);
		cJSON_AddNumberToObject(m, "pitch_deg", cam->mount_pitch_deg);
		cJSON_AddNumberToObject(m, "roll_deg", cam->mount_roll_deg);
	}
	char when[32];
	time_t now = time(NULL);
	struct tm tm;
	strftime(when, sizeof(when), "%Y-%m-%dT%H:%M:%SZ", gmtime_r(&now, &tm));
	cJSON_AddStringToObject(root, "created", when);
	if (meta)
		meta_to_json(root, cam, meta);
	return root;
}

int mvod_calib_save(const char *path, const struct mvod_camera *cam, const struct mvod_calib_meta *meta)
{
	cJSON *root = calib_to_json(cam, meta);
	if (!root)
		return -ENOMEM;
	char *text = cJSON_Print(root);
	cJSON_Delete(root);
	if (!text)
		return -ENOMEM;
	size_t len = strlen(text);
	char *withnl = realloc(text, len + 2);
	if (!withnl) {
		free(text);
		return -ENOMEM;
	}
	withnl[len] = '\n';
	withnl[len + 1] = '\0';
	int ret = mvod_write_replace(path, withnl, len + 1);
	free(withnl);
	return ret;
}
