/*
 * The FOV lens (camera/lens.c) against its closed form, forward and back; the undistortion
 * maps cv_shim.cpp remaps FOV frames through; and mvod_camera_check on FOV lenses.
 */
#include <errno.h>
#include <float.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "mvod/calib.h"

/*
 * The TUM monoVO camera.txt that circulates in public repositories' tests and notebooks
 * ("0.535719308086809 0.669566858850269 0.493248545285398 0.500408664348414
 * 0.897966326944875", 1280 1024), in pixels as DSO reads the relative form.
 */
static struct mvod_camera monovo(void)
{
	return (struct mvod_camera){.width = 1280, .height = 1024, .fx = 0.535719308086809 * 1280,
				    .fy = 0.669566858850269 * 1024,
				    .cx = 0.493248545285398 * 1280 - 0.5,
				    .cy = 0.500408664348414 * 1024 - 0.5, .model = MVOD_CAM_FOV,
				    .n_dist = 1, .dist = {0.897966326944875}};
}

/*
 * Points where the closed form is exact in rationals: w = pi/2 makes 2 tan(w/2) = 2, so
 * r = 1/2 lands where atan(1) / (pi/2) = 1/2; w = 2 pi/3, 2 tan(w/2) = 2 sqrt(3), so
 * r = 1/(2 sqrt 3) lands at (pi/4) / (2 pi/3) = 3/8. Bound: a few roundings of numbers
 * near 1 (tan and atan are within an ulp in glibc), 4 DBL_EPSILON.
 */
static void test_fov_closed_form(void **state)
{
	(void)state;
	const double tol = 4 * DBL_EPSILON;
	assert_true(fabs(mvod_fov_distort_radius(M_PI / 2, 0.5) - 0.5) < tol);
	assert_true(fabs(mvod_fov_undistort_radius(M_PI / 2, 0.5) - 0.5) < tol);
	double r = 1 / (2 * sqrt(3.0));
	assert_true(fabs(mvod_fov_distort_radius(2 * M_PI / 3, r) - 0.375) < tol);
	assert_true(fabs(mvod_fov_undistort_radius(2 * M_PI / 3, 0.375) - r) < tol);
	/* w = 0 is no lens; the image plane's edge (r_d w = pi/2) has no ray. */
	assert_true(mvod_fov_distort_radius(0, 0.7) == 0.7);
	assert_true(mvod_fov_undistort_radius(0, 0.7) == 0.7);
	assert_true(isinf(mvod_fov_undistort_radius(M_PI / 2, 1.0)));
	/* Back and forth over monoVO's w, out to 80 degrees off the axis: 1e-14 relative. */
	const double w = monovo().dist[0];
	for (double t = 0.001; t < 1.4; t += 0.01) {
		double rr = tan(t), back = mvod_fov_undistort_radius(w, mvod_fov_distort_radius(w, rr));
		if (fabs(back - rr) > 1e-14 * rr)
			fail_msg("r = %.17g came back as %.17g", rr, back);
	}
}

/* mvod_camera_distort on an FOV camera: radially by the closed form, on the axis its limit. */
static void test_fov_distort_point(void **state)
{
	(void)state;
	struct mvod_camera c = {.model = MVOD_CAM_FOV, .n_dist = 1, .dist = {M_PI / 2}};
	double xd, yd;
	mvod_camera_distort(&c, 0.3, 0.4, &xd, &yd); /* r = 0.5, r_d = 0.5 */
	assert_true(fabs(xd - 0.3) < 4 * DBL_EPSILON && fabs(yd - 0.4) < 4 * DBL_EPSILON);
	mvod_camera_distort(&c, 0, 0, &xd, &yd);
	assert_true(xd == 0 && yd == 0);
	/* Near the axis the image is magnified by 2 tan(w/2) / w = 4 / pi. */
	mvod_camera_distort(&c, 1e-9, 0, &xd, &yd);
	assert_true(fabs(xd / 1e-9 - 4 / M_PI) < 1e-12);
}

/*
 * The maps into a pinhole of other intrinsics and size (the --resize 0.5 case): every entry is
 * the closed form's pixel, computed here apart in long double, rounded once to float, so
 * within half a float ulp of it; and undistorting it gives back the output pixel's ray.
 */
static void test_fov_maps(void **state)
{
	(void)state;
	const struct mvod_camera c = monovo();
	const int w = 640, h = 512;
	const double K[9] = {c.fx / 2, 0, (c.cx + 0.5) / 2 - 0.5, 0, c.fy / 2, (c.cy + 0.5) / 2 - 0.5,
			     0, 0, 1};
	float *mx = malloc(sizeof(float) * w * h), *my = malloc(sizeof(float) * w * h);
	assert_non_null(mx);
	assert_non_null(my);
	mvod_camera_undistort_maps(&c, K, w, h, mx, my);
	const long double om = c.dist[0];
	for (int v = 0; v < h; v += 7) {
		for (int u = 0; u < w; u += 5) {
			long double x = (u - K[2]) / K[0], y = (v - K[5]) / K[4], r = hypotl(x, y);
			long double s = r > 0 ? atanl(2 * r * tanl(om / 2)) / (om * r) : 1;
			long double px = c.fx * x * s + c.cx, py = c.fy * y * s + c.cy;
			float gx = mx[v * w + u], gy = my[v * w + u];
			if (fabsl(gx - px) > (nextafterf(gx, INFINITY) - gx) / 2 + 1e-9 ||
			    fabsl(gy - py) > (nextafterf(gy, INFINITY) - gy) / 2 + 1e-9)
				fail_msg("(%d, %d): map (%.9g, %.9g), closed form (%.9Lg, %.9Lg)", u, v,
					 gx, gy, px, py);
			/* Back through the inverse: float's 6e-5 px over fx 686 is 1e-7 in r. */
			double xd = (gx - c.cx) / c.fx, yd = (gy - c.cy) / c.fy, rd = hypot(xd, yd);
			double rr = mvod_fov_undistort_radius(c.dist[0], rd);
			assert_true(fabs(rr - (double)r) < 2e-7);
		}
	}
	free(mx);
	free(my);
}

static void test_fov_check(void **state)
{
	(void)state;
	char err[256] = "";
	struct mvod_camera c = monovo();
	if (mvod_camera_check(&c, err, sizeof(err)))
		fail_msg("monoVO's camera refused: %s", err);
	c.dist[0] = M_PI;
	assert_int_equal(mvod_camera_check(&c, err, sizeof(err)), -EINVAL);
	assert_non_null(strstr(err, "the FOV lens's w = 3.14159 rad is outside [0, pi)"));
	c.dist[0] = -0.5;
	assert_int_equal(mvod_camera_check(&c, err, sizeof(err)), -EINVAL);
	/*
	 * An image circle inside the frame (90 degrees off the axis lands 94 px out, at
	 * pi / (2 w) fx) passes, as a circular fisheye's does (calib_check.c).
	 */
	c = monovo();
	c.fx = c.fy = 150;
	c.dist[0] = 2.5;
	assert_int_equal(mvod_camera_check(&c, err, sizeof(err)), 0);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_fov_closed_form),
		cmocka_unit_test(test_fov_distort_point),
		cmocka_unit_test(test_fov_maps),
		cmocka_unit_test(test_fov_check),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
