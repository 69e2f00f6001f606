/*
 * The lens models in plain C: where a normalised ray lands on the sensor (radial-tangential,
 * Kannala-Brandt, FOV), the FOV lens's closed-form radii, and undistortion maps for the lens
 * OpenCV has no model for (FOV: cv_shim.cpp remaps through them).
 */
#include "mvod/calib.h"

#include <math.h>

/*
 * The FOV lens (Devernay and Faugeras, "Straight lines have to be straight", 2001; PTAM's
 * ATANCamera, DSO's UndistortFOV): a ray at radius r (normalised, z = 1) lands at radius
 * r_d = atan(2 r tan(w / 2)) / w, and back, r = tan(r_d w) / (2 tan(w / 2)).
 */
double mvod_fov_distort_radius(double omega, double r)
{
	return omega == 0 ? r : atan(2 * r * tan(omega / 2)) / omega;
}

double mvod_fov_undistort_radius(double omega, double rd)
{
	if (omega == 0)
		return rd;
	/* At r_d w = pi / 2 the ray lies in the image plane: beyond it, no ray lands there. */
	return rd * fabs(omega) < M_PI / 2 ? tan(rd * omega) / (2 * tan(omega / 2)) : INFINITY;
}

/* The radial lenses' r_d / r at radius r: FOV (k[0] = w), Kannala-Brandt (k1..k4). */
static double radial_factor(enum mvod_cam_model model, const double *k, double r)
{
	if (model == MVOD_CAM_FOV && k[0] == 0)
		return 1;
	if (model == MVOD_CAM_FOV) /* on the axis, the limit 2 tan(w / 2) / w */
		return r > 0 ? mvod_fov_distort_radius(k[0], r) / r : 2 * tan(k[0] / 2) / k[0];
	double th = atan(r), t2 = th * th;
	double thd = th * (1 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3]))));
	return r > 1e-12 ? thd / r : 1;
}

void mvod_camera_distort(const struct mvod_camera *c, double x, double y, double *xd, double *yd)
{
	double k[MVOD_MAX_DIST] = {0};
	for (int i = 0; i < c->n_dist; i++)
		k[i] = c->dist[i];
	double r2 = x * x + y * y;
	if (c->model == MVOD_CAM_FISHEYE_KB4 || c->model == MVOD_CAM_FOV) {
		double s = radial_factor(c->model, k, sqrt(r2));
		*xd = x * s;
		*yd = y * s;
		return;
	}
	/* OpenCV's order: k1 k2 p1 p2 k3 k4 k5 k6 s1 s2 s3 s4 (the sensor tilt tx ty is left out). */
	double radial = (1 + r2 * (k[0] + r2 * (k[1] + r2 * k[4]))) /
			(1 + r2 * (k[5] + r2 * (k[6] + r2 * k[7])));
	*xd = x * radial + 2 * k[2] * x * y + k[3] * (r2 + 2 * x * x) + r2 * (k[8] + r2 * k[9]);
	*yd = y * radial + k[2] * (r2 + 2 * y * y) + 2 * k[3] * x * y + r2 * (k[10] + r2 * k[11]);
}

void mvod_camera_undistort_maps(const struct mvod_camera *cam, const double K[9], int w, int h,
				float *mapx, float *mapy)
{
	for (int v = 0; v < h; v++) {
		for (int u = 0; u < w; u++) {
			double xd, yd;
			mvod_camera_distort(cam, (u - K[2]) / K[0], (v - K[5]) / K[4], &xd, &yd);
			/* Computed in double, rounded once: within half a float ulp of the model. */
			mapx[(size_t)v * (size_t)w + (size_t)u] = (float)(cam->fx * xd + cam->cx);
			mapy[(size_t)v * (size_t)w + (size_t)u] = (float)(cam->fy * yd + cam->cy);
		}
	}
}
