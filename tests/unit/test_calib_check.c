/*
 * mvod_camera_check: real calibrations pass, impossible ones are refused with the value and
 * the range (issue 10).
 */
#include <errno.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <string.h>

#include <cmocka.h>

#include "mvod/calib.h"

static void expect(const struct mvod_camera *c, const char *needle)
{
	char err[256] = "";
	int ret = mvod_camera_check(c, err, sizeof(err));
	if (!needle) {
		if (ret)
			fail_msg("refused: %s", err);
		return;
	}
	assert_int_equal(ret, -EINVAL);
	if (!strstr(err, needle))
		fail_msg("expected '%s' in '%s'", needle, err);
}

/* OpenCV's stereo sample, left camera (../shared/data/opencv-chessboard): strong barrel, k3. */
static const struct mvod_camera chessboard = {
	.width = 640, .height = 480, .fx = 535.9157, .fy = 535.9157, .cx = 342.2832,
	.cy = 235.5708, .model = MVOD_CAM_PINHOLE_RADTAN, .n_dist = 5,
	.dist = {-0.26637, -0.038589, 0.0017832, -0.00028122, 0.23839}};

static void test_real_lenses_pass(void **state)
{
	(void)state;
	expect(&chessboard, NULL);
	/* OpenCV's ChArUco tutorial camera (../shared/data/opencv-charuco): k3 = 2.95. */
	struct mvod_camera charuco = {.width = 640, .height = 480, .fx = 452.5, .fy = 456.8,
				      .cx = 317.7, .cy = 277.8, .n_dist = 5,
				      .dist = {0.12137, -1.08547, 0.00011787, -0.00046241, 2.95426}};
	expect(&charuco, NULL);
	/* A 180-degree fisheye as OpenCV's fisheye model fits one (fx about width / pi). */
	struct mvod_camera fish = {.width = 1280, .height = 960, .fx = 400, .fy = 400, .cx = 640,
				   .cy = 480, .model = MVOD_CAM_FISHEYE_KB4, .n_dist = 4,
				   .dist = {0.03, -0.01, 0.002, -0.0005}};
	expect(&fish, NULL);
	/* KITTI: rectified, no distortion, 1241x376 with fx 718.856. */
	struct mvod_camera kitti = {.width = 1241, .height = 376, .fx = 718.856, .fy = 718.856,
				    .cx = 607.1928, .cy = 185.2157};
	expect(&kitti, NULL);
}

static void test_focal_and_centre(void **state)
{
	(void)state;
	struct mvod_camera c = chessboard;
	c.fy = 1e300;
	expect(&c, "fy = 1e+300 px is outside [32, 12800] px");
	c = chessboard;
	c.cy = -300;
	expect(&c, "cy = -300 px is outside [-240, 720] px");
}

/*
 * k3 = -0.5 on the chessboard lens: r_d = r (1 - 0.27 r^2 - 0.04 r^4 - 0.5 r^6) turns back at
 * r = 0.73, before the top-left corner (r = 0.78 there).
 */
static void test_fold(void **state)
{
	(void)state;
	struct mvod_camera c = chessboard;
	c.dist[4] = -0.5;
	expect(&c, "the distortion folds the image: toward the");
	c = chessboard;
	c.model = MVOD_CAM_FISHEYE_KB4;
	c.n_dist = 4;
	memcpy(c.dist, (double[]){1e6, 0, 0, 0}, 4 * sizeof(double));
	expect(&c, "times as far out as a pinhole would");
}

/* A coefficient that is no number is named so, not taken for a folding lens. */
static void test_not_a_number(void **state)
{
	(void)state;
	struct mvod_camera c = chessboard;
	c.dist[1] = NAN;
	expect(&c, "distortion coefficient k2 = nan is not a number");
	c = chessboard;
	c.model = MVOD_CAM_FISHEYE_KB4;
	c.n_dist = 4;
	memcpy(c.dist, (double[]){0.1, 0, INFINITY, 0}, 4 * sizeof(double));
	expect(&c, "distortion coefficient k3 = inf is not a number");
	c = chessboard;
	c.cx = NAN;
	expect(&c, "cx = nan is not a number");
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_real_lenses_pass),
		cmocka_unit_test(test_focal_and_centre),
		cmocka_unit_test(test_fold),
		cmocka_unit_test(test_not_a_number),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
