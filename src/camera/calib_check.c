/*
 * Whether intrinsics can be a real camera of their image size: a focal length, a principal
 * point and a lens model that some lens could have. A calibration that fails here (focal length
 * 1e300, distortion 1e6) would run with every frame held and a summary that reads as fine.
 */
#include "mvod/calib.h"

#include <errno.h>
#include <math.h>
#include <stdbool.h>

#include "util/errbuf.h"

/*
 * Focal lengths as multiples of the image width. 0.05 w is a pinhole horizontal field of view
 * of 2 atan(10) = 169 degrees (a fisheye's fx, pixels per radian, is about w / pi = 0.32 w for
 * 180 degrees); 20 w is 2.9 degrees, a 700 mm lens on a 35 mm sensor. Outside, it is no camera.
 */
#define F_MIN_W 0.05
#define F_MAX_W 20.0
/* A principal point may sit off centre (lens shift, a crop), but not half the image outside it. */
#define PP_MARGIN 0.5
/* Angles sampled from the axis to 90 degrees along each ray: 0.045 degrees apart. */
#define RAY_STEPS 2000
/*
 * The lens may put the image edge at most this many times further out than a pinhole would.
 * Real pincushion lenses do tens of percent; fisheyes pull the edge in (ratio < 1).
 */
#define MAX_STRETCH 4.0

/*
 * Walks the ray from the principal point towards image point (px, py) outward, from the axis to
 * 90 degrees off it: the distorted image must move strictly outward until it reaches that
 * point (or the ray reaches 90 degrees). 0, or -EINVAL with why in err.
 */
static int check_ray(const struct mvod_camera *c, double px, double py, const char *toward,
		     char *err, size_t errlen)
{
	double ux = (px - c->cx) / c->fx, uy = (py - c->cy) / c->fy;
	double un = hypot(ux, uy), edge = hypot(px - c->cx, py - c->cy), last = 0;
	if (un <= 0)
		return 0;
	for (int i = 1; i < RAY_STEPS; i++) {
		double rho = tan(i * (M_PI / 2) / RAY_STEPS), xd, yd;
		mvod_camera_distort(c, rho * ux / un, rho * uy / un, &xd, &yd);
		/* How far out along the ray, in pixels: negative once the image crosses the axis. */
		double q = (xd * c->fx * (px - c->cx) + yd * c->fy * (py - c->cy)) / edge;
		if (!(q > last))
			return mvod_errf(err, errlen, -EINVAL, "the distortion folds the image: toward "
					 "the %s its image turns back %.0f px from the principal point, "
					 "inside the image (edge at %.0f px); no lens does that",
					 toward, last, edge);
		if (q >= edge)
			return hypot(xd, yd) > MAX_STRETCH * rho
				       ? mvod_errf(err, errlen, -EINVAL, "the distortion puts the "
						   "%s %.0f times as far out as a pinhole would "
						   "(at most %g for a real lens)", toward,
						   hypot(xd, yd) / rho, MAX_STRETCH)
				       : 0;
		last = q;
	}
	/*
	 * Still short of the edge 90 degrees off the axis: the image there sees nothing, as the
	 * corners of a circular fisheye's image (an Intel T265's 848x800 at fx 285) do.
	 */
	return 0;
}

/* The corners and edge midpoints, each checked along its ray. */
static int check_lens(const struct mvod_camera *c, char *err, size_t errlen)
{
	static const char *const names[8] = {"top-left corner", "top edge", "top-right corner",
					     "right edge", "bottom-right corner", "bottom edge",
					     "bottom-left corner", "left edge"};
	static const double at[8][2] = {{0, 0}, {0.5, 0}, {1, 0}, {1, 0.5},
					{1, 1}, {0.5, 1}, {0, 1}, {0, 0.5}};
	for (int i = 0; i < 8; i++) {
		int ret = check_ray(c, at[i][0] * c->width, at[i][1] * c->height, names[i], err,
				    errlen);
		if (ret)
			return ret;
	}
	return 0;
}

/*
 * Every distortion coefficient a number: a nan one made the ray walk fail at its first step,
 * "the distortion folds the image", which sent the user looking at the lens.
 */
static int check_numbers(const struct mvod_camera *c, char *err, size_t errlen)
{
	static const char *const opencv[MVOD_MAX_DIST] = {
		"k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6", "s1", "s2", "s3", "s4", "tx", "ty"};
	static const char *const kb4[4] = {"k1", "k2", "k3", "k4"};
	for (int i = 0; i < c->n_dist; i++)
		if (!isfinite(c->dist[i]))
			return mvod_errf(err, errlen, -EINVAL, "distortion coefficient %s = %g is "
					 "not a number", c->model == MVOD_CAM_FOV ? "w"
					 : c->model == MVOD_CAM_FISHEYE_KB4 && i < 4 ? kb4[i]
					 : opencv[i], c->dist[i]);
	return 0;
}

/* value within [lo, hi], else -EINVAL naming it. */
static int in_range(const char *name, double value, double lo, double hi, const char *why,
		    char *err, size_t errlen)
{
	if (value >= lo && value <= hi)
		return 0;
	if (!isfinite(value))
		return mvod_errf(err, errlen, -EINVAL, "%s = %g is not a number", name, value);
	return mvod_errf(err, errlen, -EINVAL, "%s = %g px is outside [%g, %g] px (%s)", name, value,
			 lo, hi, why);
}

int mvod_camera_check(const struct mvod_camera *c, char *err, size_t errlen)
{
	const double w = c->width, h = c->height;
	const char *fwhy = "0.05 to 20 times the image width: fields of view from 169 to 2.9 "
			   "degrees";
	const char *pwhy = "the image and half its size around it";
	int ret = in_range("fx", c->fx, F_MIN_W * w, F_MAX_W * w, fwhy, err, errlen);
	if (!ret)
		ret = in_range("fy", c->fy, F_MIN_W * w, F_MAX_W * w, fwhy, err, errlen);
	if (!ret)
		ret = in_range("cx", c->cx, -PP_MARGIN * w, (1 + PP_MARGIN) * w, pwhy, err, errlen);
	if (!ret)
		ret = in_range("cy", c->cy, -PP_MARGIN * h, (1 + PP_MARGIN) * h, pwhy, err, errlen);
	if (!ret)
		ret = check_numbers(c, err, errlen);
	/* w = pi would put the whole half-space in a finite image circle: no FOV lens does. */
	if (!ret && c->model == MVOD_CAM_FOV && !(c->dist[0] >= 0 && c->dist[0] < M_PI))
		ret = mvod_errf(err, errlen, -EINVAL, "the FOV lens's w = %g rad is outside [0, pi) "
				"(its field of view; TUM monoVO's are 0.9 to 0.95)", c->dist[0]);
	if (!ret && mvod_camera_has_distortion(c))
		ret = check_lens(c, err, errlen);
	return ret;
}
