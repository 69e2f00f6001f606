/*
 * The calibration files real tools wrote (OpenCV's samples, in ../shared/data) load with the
 * numbers their YAML says. Skips (77) when the data is absent.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <cmocka.h>

#include "harness.h"

#include "mvod/calib.h"

static void load(const char *rel, struct mvod_camera *c, enum mvod_calib_format *fmt)
{
	char path[600], err[512] = "";
	snprintf(path, sizeof(path), "%s/%s", getenv("MVOD_DATA"), rel);
	if (mvod_calib_load_format(path, c, fmt, err, sizeof(err)))
		fail_msg("%s", err);
}

/* The YAML's numbers are the decimal literals below, read by the same strtod: exact. */
static void test_charuco_tutorial(void **state)
{
	(void)state;
	struct mvod_camera c;
	enum mvod_calib_format fmt;
	load("opencv-charuco/params/tutorial_camera_charuco.yml", &c, &fmt);
	assert_int_equal(fmt, MVOD_CALIB_FMT_OPENCV);
	assert_int_equal(c.model, MVOD_CAM_PINHOLE_RADTAN);
	assert_int_equal(c.width, 640);
	assert_int_equal(c.height, 480);
	assert_true(c.fx == 4.5251072219637672e+02 && c.fy == 4.5676707935146891e+02);
	assert_true(c.cx == 3.1770297317353277e+02 && c.cy == 2.7775155919135995e+02);
	assert_int_equal(c.n_dist, 5);
	assert_true(c.dist[0] == 1.2136925618707872e-01 && c.dist[1] == -1.0854664722560681e+00 &&
		    c.dist[2] == 1.1786843796668460e-04 && c.dist[3] == -4.6240686046485508e-04 &&
		    c.dist[4] == 2.9542589406810080e+00);
}

static void test_chessboard_left(void **state)
{
	(void)state;
	struct mvod_camera c;
	enum mvod_calib_format fmt;
	load("opencv-chessboard/params/left_intrinsics.yml", &c, &fmt);
	assert_int_equal(fmt, MVOD_CALIB_FMT_OPENCV);
	assert_int_equal(c.width, 640);
	assert_int_equal(c.height, 480);
	assert_true(c.fx == 5.3591573396163199e+02 && c.fy == 5.3591573396163199e+02);
	assert_true(c.cx == 3.4228315473308373e+02 && c.cy == 2.3557082909788173e+02);
	assert_int_equal(c.n_dist, 5); /* a 5x1 column there */
	assert_true(c.dist[0] == -2.6637260909660682e-01 && c.dist[4] == 2.3839153080878486e-01);
}

/* OpenCV's stereo sample: M1/D1 are the first camera; no image size in the file. */
static void test_chessboard_stereo(void **state)
{
	(void)state;
	struct mvod_camera c;
	enum mvod_calib_format fmt;
	load("opencv-chessboard/params/stereo_intrinsics_M1D1M2D2.yml", &c, &fmt);
	assert_int_equal(c.width, 0);
	assert_true(c.fx == 5.3480326845051309e+02 && c.cx == 3.3568643204394891e+02 &&
		    c.cy == 2.4066183054066337e+02);
	assert_int_equal(c.n_dist, 5);
	assert_true(c.dist[0] == 2.9589439552724328e-01 && c.dist[1] == -1.0354662043042675e+00);
}

/* An image list is XML FileStorage too, but no calibration: the reason says what is missing. */
static void test_image_list_refused(void **state)
{
	(void)state;
	char path[600], err[512] = "";
	snprintf(path, sizeof(path), "%s/opencv-chessboard/params/stereo_calib.xml", getenv("MVOD_DATA"));
	struct mvod_camera c;
	assert_int_not_equal(mvod_calib_load(path, &c, err, sizeof(err)), 0);
	assert_non_null(strstr(err, "stereo_calib.xml"));
	assert_non_null(strstr(err, "camera_matrix"));
}

int main(void)
{
	const char *data = getenv("MVOD_DATA");
	char probe[600];
	struct stat st;
	snprintf(probe, sizeof(probe), "%s/opencv-chessboard/params", data ? data : "");
	if (!data || stat(probe, &st) != 0) {
		fprintf(stderr, "skipping: %s not found\n", probe);
		return EXIT_SKIP;
	}
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_charuco_tutorial),
		cmocka_unit_test(test_chessboard_left),
		cmocka_unit_test(test_chessboard_stereo),
		cmocka_unit_test(test_image_list_refused),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
