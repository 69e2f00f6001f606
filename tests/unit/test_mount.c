/*
 * The camera file's "mount" block (how high and how pitched the camera sits above the ground,
 * for --scale height): read, written back, refused with a message when malformed.
 */
#include <errno.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "harness.h"
#include "mvod/calib.h"
#include "vo/scale.h"

static const char *dir;

#define CAMERA "{\"format\": \"mvod-calibration/1\", \"model\": \"pinhole-radtan\", " \
	       "\"image_size\": [640, 480], \"K\": [[500, 0, 320], [0, 500, 240], [0, 0, 1]], " \
	       "\"distortion\": [0, 0, 0, 0]"

static int setup(void **state)
{
	(void)state;
	dir = harness_tmpdir();
	return 0;
}

static void test_mount_read(void **state)
{
	(void)state;
	struct mvod_camera c;
	char err[512] = "";
	assert_int_equal(mvod_calib_parse_json(CAMERA ", \"mount\": {\"height_m\": 1.65, "
					       "\"pitch_deg\": 2.5, \"roll_deg\": -0.5}}",
					       &c, err, sizeof(err)),
			 0);
	assert_true(c.has_mount);
	assert_true(c.mount_height_m == 1.65 && c.mount_pitch_deg == 2.5 &&
		    c.mount_roll_deg == -0.5);
	/* Pitch and roll may be left out (0); no block: no mount. */
	assert_int_equal(mvod_calib_parse_json(CAMERA ", \"mount\": {\"height_m\": 0.3}}", &c, err,
					       sizeof(err)),
			 0);
	assert_true(c.has_mount && c.mount_pitch_deg == 0 && c.mount_roll_deg == 0);
	assert_int_equal(mvod_calib_parse_json(CAMERA "}", &c, err, sizeof(err)), 0);
	assert_false(c.has_mount);
}

/* Each malformed block is refused, the message naming the block and what it must hold. */
static void test_mount_malformed(void **state)
{
	(void)state;
	static const char *const bad[] = {
		"3",
		"{}",
		"{\"height_m\": 0}",
		"{\"height_m\": -1.6}",
		"{\"height_m\": 25}",
		"{\"height_m\": \"1.6\"}",
		"{\"height_m\": 1.6, \"pitch_deg\": 75}",
		"{\"height_m\": 1.6, \"roll_deg\": \"level\"}",
	};
	for (size_t i = 0; i < sizeof(bad) / sizeof(bad[0]); i++) {
		char text[512], err[512] = "";
		struct mvod_camera c;
		snprintf(text, sizeof(text), CAMERA ", \"mount\": %s}", bad[i]);
		assert_int_equal(mvod_calib_parse_json(text, &c, err, sizeof(err)), -EINVAL);
		assert_non_null(strstr(err, "\"mount\""));
		assert_non_null(strstr(err, "height_m"));
	}
}

static void test_mount_written(void **state)
{
	(void)state;
	struct mvod_camera c = {.width = 640, .height = 480, .fx = 500, .fy = 500, .cx = 320,
				.cy = 240, .n_dist = 4, .has_mount = true, .mount_height_m = 1.2,
				.mount_pitch_deg = 10.0, .mount_roll_deg = 1.0};
	char path[300], err[512] = "";
	snprintf(path, sizeof(path), "%s/calib.json", dir);
	assert_int_equal(mvod_calib_save(path, &c, NULL), 0);
	struct mvod_camera back;
	assert_int_equal(mvod_calib_load(path, &back, err, sizeof(err)), 0);
	assert_true(back.has_mount && back.mount_height_m == 1.2 && back.mount_pitch_deg == 10.0 &&
		    back.mount_roll_deg == 1.0);
}

/* The normal of a mount: level is straight down; pitch tips it towards the optical axis. */
static void test_mount_normal(void **state)
{
	(void)state;
	double n[3];
	mvod_ground_normal(0, 0, n);
	assert_true(n[0] == 0 && n[1] == 1 && n[2] == 0);
	mvod_ground_normal(30, 0, n);
	assert_true(fabs(n[1] - sqrt(3) / 2) < 1e-12 && fabs(n[2] - 0.5) < 1e-12);
	mvod_ground_normal(0, 30, n);
	assert_true(fabs(n[0] - 0.5) < 1e-12 && fabs(n[1] - sqrt(3) / 2) < 1e-12);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_mount_read),
		cmocka_unit_test(test_mount_malformed),
		cmocka_unit_test(test_mount_written),
		cmocka_unit_test(test_mount_normal),
	};
	return cmocka_run_group_tests(tests, setup, harness_teardown);
}
