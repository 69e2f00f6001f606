/*
 * The camera model's helpers every calibration reader and writer shares: the models' names, the
 * camera matrix both ways, the distortion coefficients each model takes.
 */
#include "mvod/calib.h"

#include <errno.h>
#include <math.h>
#include <string.h>

#include "camera/calib_internal.h"

static const char *const model_names[] = {"pinhole-radtan", "fisheye-kb4", "fov"};
#define N_MODELS ((int)(sizeof(model_names) / sizeof(model_names[0])))

const char *mvod_cam_model_name(enum mvod_cam_model model)
{
	return (unsigned)model < N_MODELS ? model_names[model] : "unknown";
}

int mvod_cam_model_parse(const char *name, enum mvod_cam_model *out)
{
	for (int i = 0; i < N_MODELS; i++) {
		if (strcmp(name, model_names[i]) == 0) {
			*out = (enum mvod_cam_model)i;
			return 0;
		}
	}
	return -EINVAL;
}

bool mvod_camera_has_distortion(const struct mvod_camera *cam)
{
	for (int i = 0; i < cam->n_dist; i++)
		if (cam->dist[i] != 0.0)
			return true;
	return false;
}

bool mvod_calib_intrinsics_ok(const struct mvod_camera *c)
{
	return isfinite(c->fx) && isfinite(c->fy) && isfinite(c->cx) && isfinite(c->cy) && c->fx > 0 &&
	       c->fy > 0;
}

void mvod_camera_K(const struct mvod_camera *cam, double K[9])
{
	const double k[9] = {cam->fx, 0, cam->cx, 0, cam->fy, cam->cy, 0, 0, 1};
	memcpy(K, k, sizeof(k));
}

int mvod_calib_set_K(const double k[9], struct mvod_camera *cam)
{
	struct mvod_camera c = *cam;
	c.fx = k[0];
	c.fy = k[4];
	c.cx = k[2];
	c.cy = k[5];
	/* Skew (k[1]) is not modelled. */
	if (k[1] != 0 || k[3] != 0 || k[6] != 0 || k[7] != 0 || k[8] != 1 || !mvod_calib_intrinsics_ok(&c))
		return -EINVAL;
	*cam = c;
	return 0;
}

bool mvod_calib_dist_count_ok(enum mvod_cam_model model, int n)
{
	if (model == MVOD_CAM_FISHEYE_KB4)
		return n == 4;
	if (model == MVOD_CAM_FOV)
		return n == 1;
	return n == 0 || n == 4 || n == 5 || n == 8 || n == 12 || n == 14;
}

const char *mvod_calib_dist_counts(enum mvod_cam_model model)
{
	if (model == MVOD_CAM_FOV)
		return "1 (w, radians)";
	return model == MVOD_CAM_FISHEYE_KB4 ? "4" : "0, 4, 5, 8, 12 or 14";
}
