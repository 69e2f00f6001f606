/* mvod mount: the camera's height, pitch and roll from a board lying on the floor. */
#include "mvod/mount.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "calib/calib_shim.h"
#include "mvod/geom.h"
#include "mvod/log.h"
#include "util/atomic_file.h"
#include "util/errbuf.h"
#include "util/linalg.h"
#include "util/text_guard.h"

#define DEG (180.0 / M_PI)

/* Height, pitch, roll as k = 0, 1, 2, for loops over the three. */
static double *field(struct mvod_mount *m, int k)
{
	return k == 0 ? &m->height_m : k == 1 ? &m->pitch_deg : &m->roll_deg;
}

void mvod_mount_from_pose(const double rvec[3], const double tvec[3], double thickness_m,
			  struct mvod_mount *m)
{
	double R[9];
	mvod_rot_exp(rvec, R);
	const double n[3] = {R[2], R[5], R[8]};
	m->height_m = n[0] * tvec[0] + n[1] * tvec[1] + n[2] * tvec[2] + thickness_m;
	m->pitch_deg = asin(fmax(-1.0, fmin(1.0, n[2]))) * DEG;
	m->roll_deg = atan2(n[0], n[1]) * DEG;
}

/* Central differences: the mount is smooth in the pose, 1e-6 rad or m is far above rounding. */
void mvod_mount_sd(const double rvec[3], const double tvec[3], const double cov[36],
		   struct mvod_mount *sd)
{
	const double step = 1e-6;
	double J[3][6];
	for (int j = 0; j < 6; j++) {
		double p[2][6];
		struct mvod_mount m[2];
		for (int s = 0; s < 2; s++) {
			memcpy(p[s], rvec, 3 * sizeof(double));
			memcpy(p[s] + 3, tvec, 3 * sizeof(double));
			p[s][j] += s ? step : -step;
			mvod_mount_from_pose(p[s], p[s] + 3, 0, &m[s]);
		}
		for (int k = 0; k < 3; k++)
			J[k][j] = (*field(&m[1], k) - *field(&m[0], k)) / (2 * step);
	}
	for (int k = 0; k < 3; k++) {
		double var = 0;
		for (int a = 0; a < 6; a++)
			for (int b = 0; b < 6; b++)
				var += J[k][a] * cov[6 * a + b] * J[k][b];
		*field(sd, k) = sqrt(fmax(var, 0));
	}
}

/* Whether view v is within 3 sigma plus the floor's allowance of the median med. */
static bool agrees(struct mvod_mount_view *v, struct mvod_mount *med)
{
	for (int k = 0; k < 3; k++) {
		double allow = k == 0 ? MVOD_MOUNT_AGREE_REL * med->height_m : MVOD_MOUNT_AGREE_DEG;
		if (fabs(*field(&v->m, k) - *field(med, k)) > 3 * *field(&v->sd, k) + allow)
			return false;
	}
	return true;
}

int mvod_mount_combine(struct mvod_mount_view *v, int n, struct mvod_mount *m,
		       struct mvod_mount *sd)
{
	double *vals = malloc(sizeof(double) * (size_t)(n > 0 ? n : 1));
	struct mvod_mount med = {0};
	int used = 0;
	for (int k = 0; vals && k < 3; k++) {
		int c = 0;
		for (int i = 0; i < n; i++)
			if (v[i].verdict == MVOD_MOUNT_USED)
				vals[c++] = *field(&v[i].m, k);
		*field(&med, k) = c ? mvod_median(vals, c) : NAN;
	}
	free(vals);
	double sw[3] = {0}, swx[3] = {0};
	for (int i = 0; i < n; i++) {
		if (v[i].verdict != MVOD_MOUNT_USED)
			continue;
		if (!agrees(&v[i], &med)) {
			v[i].verdict = MVOD_MOUNT_DISAGREES;
			continue;
		}
		used++;
		for (int k = 0; k < 3; k++) {
			/* A zero deviation (exact corners, in tests) weighs most, finitely. */
			double s = *field(&v[i].sd, k), w = 1 / (s * s + 1e-300);
			sw[k] += w;
			swx[k] += w * *field(&v[i].m, k);
		}
	}
	for (int k = 0; k < 3; k++) {
		*field(m, k) = used ? swx[k] / sw[k] : NAN;
		*field(sd, k) = used ? 1 / sqrt(sw[k]) : NAN;
	}
	return used;
}

/* The view's pose, mount and verdict. */
static int judge_view(const struct mvod_mount_opts *o, const struct mvod_camera *cam,
		      const struct mvod_calib_obs *obs, struct mvod_mount_view *v)
{
	struct mvod_calib_pose pose;
	int ret = mvod_calib_board_pose(&o->board, obs, cam, MVOD_MOUNT_MIN_SIGMA_PX, &pose);
	v->frame = obs->frame;
	if (ret == -EDOM) {
		/* No pose, or one the corners do not pin down: a view like any uncertain one. */
		*v = (struct mvod_mount_view){.frame = obs->frame, .m = {NAN, NAN, NAN},
					      .sd = {INFINITY, INFINITY, INFINITY},
					      .rms_px = NAN, .verdict = MVOD_MOUNT_UNCERTAIN};
		return 0;
	}
	if (ret)
		return ret;
	v->rms_px = pose.rms_px;
	/* The covariance scales with the corners' error squared. */
	double s = fmax(pose.rms_px, MVOD_MOUNT_MIN_SIGMA_PX) / MVOD_MOUNT_MIN_SIGMA_PX;
	for (int k = 0; k < 36; k++)
		pose.cov[k] *= s * s;
	mvod_mount_from_pose(pose.rvec, pose.tvec, o->thickness_m, &v->m);
	mvod_mount_sd(pose.rvec, pose.tvec, pose.cov, &v->sd);
	if (pose.rms_px > MVOD_MOUNT_MAX_RMS_PX)
		v->verdict = MVOD_MOUNT_HIGH_ERROR;
	else if (!(fabs(v->m.pitch_deg) <= MVOD_MOUNT_MAX_ANGLE_DEG &&
		   fabs(v->m.roll_deg) <= MVOD_MOUNT_MAX_ANGLE_DEG))
		v->verdict = MVOD_MOUNT_NOT_FLAT;
	else if (!(v->sd.height_m <= MVOD_MOUNT_MAX_SD_REL * fabs(v->m.height_m) &&
		   v->sd.pitch_deg <= MVOD_MOUNT_MAX_SD_DEG && v->sd.roll_deg <= MVOD_MOUNT_MAX_SD_DEG))
		v->verdict = MVOD_MOUNT_UNCERTAIN;
	else
		v->verdict = MVOD_MOUNT_USED;
	return 0;
}

/* How far a refused view is from being used: its deviation when uncertain, else its error. */
static double badness(const struct mvod_mount_view *v)
{
	return v->verdict == MVOD_MOUNT_UNCERTAIN ? v->sd.height_m : v->rms_px;
}

/* The best of the views refused for verdict: its numbers are the message's. */
static const struct mvod_mount_view *typical(const struct mvod_mount_result *res,
					     enum mvod_mount_verdict verdict)
{
	const struct mvod_mount_view *best = NULL;
	for (int i = 0; i < res->n_views; i++)
		if (res->views[i].verdict == verdict &&
		    (!best || badness(&res->views[i]) < badness(best)))
			best = &res->views[i];
	return best;
}

/* The views that agree are too few: why, in the words of the commonest refusal. */
static int too_few(const struct mvod_mount_result *res, const int *count, char *err,
		   size_t errlen)
{
	int most = MVOD_MOUNT_HIGH_ERROR;
	for (int k = MVOD_MOUNT_HIGH_ERROR; k <= MVOD_MOUNT_DISAGREES; k++)
		most = count[k] > count[most] ? k : most;
	if (res->used > 0)
		most = MVOD_MOUNT_DISAGREES;
	const struct mvod_mount_view *v = typical(res, (enum mvod_mount_verdict)most);
	char of[48] = "";
	if (res->n_views > 1 && count[most] == res->n_views)
		snprintf(of, sizeof(of), "in every view ");
	else if (res->n_views > 1)
		snprintf(of, sizeof(of), "in %d of %d views ", count[most], res->n_views);
	if (most == MVOD_MOUNT_HIGH_ERROR)
		return mvod_errf(err, errlen, -EDOM, "the board's corners %sare %.2f px or more off "
				 "its best pose (at most %g px): move the board closer (corners far "
				 "away or at a grazing angle are found poorly), and check that the "
				 "camera file is this camera's and --board the printed board's sizes",
				 of, v->rms_px, MVOD_MOUNT_MAX_RMS_PX);
	if (most == MVOD_MOUNT_NOT_FLAT)
		return mvod_errf(err, errlen, -EDOM, "the board %sis not lying flat on the floor: its "
				 "plane gives a pitch of %.1f deg and a roll of %.1f deg (a mount has at "
				 "most %g): lay it flat on the floor in front of the camera", of,
				 v->m.pitch_deg, v->m.roll_deg, MVOD_MOUNT_MAX_ANGLE_DEG);
	if (most == MVOD_MOUNT_UNCERTAIN)
		return mvod_errf(err, errlen, -EDOM, "the board %sis too small in the image or too "
				 "far for a good pose: height +-%.1f mm (at most %g %%), pitch +-%.2f "
				 "deg, roll +-%.2f deg (at most %g): move it closer to the camera or "
				 "print a bigger board", of, 1e3 * v->sd.height_m,
				 100 * MVOD_MOUNT_MAX_SD_REL, v->sd.pitch_deg, v->sd.roll_deg,
				 MVOD_MOUNT_MAX_SD_DEG);
	double lo = INFINITY, hi = -INFINITY;
	for (int i = 0; i < res->n_views; i++) {
		if (res->views[i].verdict != MVOD_MOUNT_DISAGREES &&
		    res->views[i].verdict != MVOD_MOUNT_USED)
			continue;
		lo = fmin(lo, res->views[i].m.height_m);
		hi = fmax(hi, res->views[i].m.height_m);
	}
	return mvod_errf(err, errlen, -EDOM, "%d of %d good views disagree with the others "
			 "(heights %.3f to %.3f m): the camera moved, or the board was not flat on "
			 "the floor in all of them", count[MVOD_MOUNT_DISAGREES],
			 count[MVOD_MOUNT_DISAGREES] + res->used, lo, hi);
}

/* Whether enough views agree: some, and more than disagree with them. */
static int enough_views(const struct mvod_mount_result *res, char *err, size_t errlen)
{
	int count[MVOD_MOUNT_DISAGREES + 1] = {0};
	for (int i = 0; i < res->n_views; i++)
		count[res->views[i].verdict]++;
	if (res->used == 0 || count[MVOD_MOUNT_DISAGREES] > res->used)
		return too_few(res, count, err, errlen);
	return 0;
}

/* The frames' size must be the one the intrinsics were made for. */
static int check_size(const struct mvod_mount_opts *o, const struct mvod_camera *cam,
		      const struct mvod_calib_views *views, char *err, size_t errlen)
{
	if (cam->width == 0 || (cam->width == views->w && cam->height == views->h))
		return 0;
	return mvod_errf(err, errlen, -EINVAL, "the camera file is for %dx%d images but %s has "
			 "%dx%d frames: use the camera file of this camera at this size",
			 cam->width, cam->height, o->source, views->w, views->h);
}

int mvod_mount_measure(const struct mvod_mount_opts *o, const struct mvod_camera *cam,
		       struct mvod_mount_result *res, char *err, size_t errlen)
{
	memset(res, 0, sizeof(*res));
	/* The board's pose undistorts its corners through OpenCV, which has no FOV lens. */
	if (cam->model == MVOD_CAM_FOV && mvod_camera_has_distortion(cam))
		return mvod_errf(err, errlen, -ENOTSUP, "the camera file's lens is FOV, which mvod "
				 "mount cannot undistort (OpenCV has no model for it): measure with "
				 "a pinhole or fisheye calibration of the camera (mvod calibrate)");
	struct mvod_calib_opts co;
	mvod_calib_opts_default(&co);
	co.source = o->source;
	co.board = o->board;
	co.max_frames = o->max_frames;
	co.stop = o->stop;
	co.command = "mount";
	struct mvod_calib_views views;
	int ret = mvod_calib_read_views(&co, 1, &views, err, errlen);
	res->frames_read = views.frames;
	if (!ret)
		ret = check_size(o, cam, &views, err, errlen);
	if (!ret && !(res->views = calloc((size_t)views.n, sizeof(*res->views))))
		ret = mvod_errf(err, errlen, -ENOMEM, "out of memory for %d views", views.n);
	for (int i = 0; !ret && i < views.n; i++) {
		ret = judge_view(o, cam, &views.obs[i], &res->views[i]);
		res->n_views++;
		const struct mvod_mount_view *v = &res->views[i];
		LOG(DEBUG, "mount: frame %lld: %d corners, %.3f px, height %.4f m +- %.4f, pitch %.3f "
			   "+- %.3f, roll %.3f +- %.3f deg, verdict %d", (long long)v->frame,
		    views.obs[i].n, v->rms_px, v->m.height_m, v->sd.height_m, v->m.pitch_deg,
		    v->sd.pitch_deg, v->m.roll_deg, v->sd.roll_deg, (int)v->verdict);
		if (ret)
			mvod_errf(err, errlen, ret, "%s: frame %lld: no board pose: %s", o->source,
				  (long long)views.obs[i].frame, strerror(-ret));
	}
	if (!ret) {
		res->used = mvod_mount_combine(res->views, res->n_views, &res->m, &res->sd);
		ret = enough_views(res, err, errlen);
		if (!ret && !(res->m.height_m > 0 && res->m.height_m <= MVOD_MOUNT_MAX_HEIGHT_M))
			ret = mvod_errf(err, errlen, -EDOM, "the board puts the camera %.3f m above "
					"the floor, outside (0, %g]: check --board's square size",
					res->m.height_m, MVOD_MOUNT_MAX_HEIGHT_M);
	}
	mvod_calib_views_free(&views);
	return ret;
}

void mvod_mount_result_free(struct mvod_mount_result *res)
{
	free(res->views);
	res->views = NULL;
}

/* Rounded to 10^-digits: the file says no more than the measurement knows. */
static double rounded(double v, int digits)
{
	double s = pow(10, digits);
	return round(v * s) / s;
}

/* root with its "mount" block set to m, in its place when it has one, else at the end. */
static int set_mount(cJSON *root, const struct mvod_mount *m)
{
	cJSON *block = cJSON_CreateObject();
	if (!block || !cJSON_AddNumberToObject(block, "height_m", rounded(m->height_m, 4)) ||
	    !cJSON_AddNumberToObject(block, "pitch_deg", rounded(m->pitch_deg, 2)) ||
	    !cJSON_AddNumberToObject(block, "roll_deg", rounded(m->roll_deg, 2))) {
		cJSON_Delete(block);
		return -ENOMEM;
	}
	bool ok = cJSON_GetObjectItemCaseSensitive(root, "mount")
			  ? cJSON_ReplaceItemInObjectCaseSensitive(root, "mount", block)
			  : cJSON_AddItemToObject(root, "mount", block);
	if (!ok)
		cJSON_Delete(block);
	return ok ? 0 : -ENOMEM;
}

/* An OpenCV or ROS YAML camera file: its mount scalars set, every other byte kept. */
static int write_filestorage(const char *path, const char *text, const struct mvod_mount *m,
			     char *err, size_t errlen)
{
	const double mount[3] = {rounded(m->height_m, 4), rounded(m->pitch_deg, 2),
				 rounded(m->roll_deg, 2)};
	char *out = NULL, why[512];
	int ret = mvod_calib_filestorage_set_mount(text, mount, &out, why, sizeof(why));
	if (ret)
		return mvod_errf(err, errlen, ret, "%s: %s", path, why);
	ret = mvod_write_replace(path, out, strlen(out));
	free(out);
	if (ret)
		mvod_errf(err, errlen, ret, "cannot write %s: %s", path, strerror(-ret));
	return ret;
}

int mvod_mount_write(const char *path, const char *text, const struct mvod_mount *m, char *err,
		     size_t errlen)
{
	char first = text[strspn(text, " \t\r\n")];
	if (first != '{' && first != '[') /* JSON: mvod's object, or another tool's array */
		return write_filestorage(path, text, m, err, errlen);
	char why[256];
	int ret = mvod_text_guard(text, strlen(text), MVOD_TEXT_JSON, why, sizeof(why));
	if (ret)
		return mvod_errf(err, errlen, ret, "%s: %s", path, why);
	cJSON *root = cJSON_Parse(text);
	const cJSON *fmt = cJSON_GetObjectItemCaseSensitive(root, "format");
	char *out = NULL;
	if (!cJSON_IsObject(root) || !cJSON_IsString(fmt) ||
	    strcmp(fmt->valuestring, MVOD_CALIB_FORMAT) != 0) {
		ret = mvod_errf(err, errlen, -EINVAL, "%s is not mvod JSON (%s), the only JSON camera "
				"file that carries a mount: convert it with mvod calib-convert %s calib.json",
				path, MVOD_CALIB_FORMAT, path);
		goto out;
	}
	ret = set_mount(root, m);
	/* cJSON_Print's layout is the one mvod_calib_save wrote the file in. */
	if (!ret && !(out = cJSON_Print(root)))
		ret = -ENOMEM;
	char *end = out ? realloc(out, strlen(out) + 2) : NULL;
	if (end) {
		out = end;
		strcat(out, "\n");
		ret = mvod_write_replace(path, out, strlen(out));
	} else if (!ret) {
		ret = -ENOMEM;
	}
	if (ret)
		mvod_errf(err, errlen, ret, "cannot write %s: %s", path, strerror(-ret));
out:
	free(out);
	cJSON_Delete(root);
	return ret;
}
