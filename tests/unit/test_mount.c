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
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <cmocka.h>

#include "harness.h"
#include "mvod/calib.h"
#include "mvod/mount.h"
#include "vo/core/camera.h"

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

#define FS_YAML "%YAML:1.0\n---\nimage_width: 640\nimage_height: 480\n" \
		"camera_matrix: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n" \
		"   data: [ 500., 0., 320., 0., 500., 240., 0., 0., 1. ]\n" \
		"distortion_coefficients: !!opencv-matrix\n   rows: 1\n   cols: 4\n   dt: d\n" \
		"   data: [ 0.1, 0., 0., 0. ]\n"
#define FS_XML "<?xml version=\"1.0\"?>\n<opencv_storage>\n" \
	       "<camera_matrix type_id=\"opencv-matrix\"><rows>3</rows><cols>3</cols><dt>d</dt>" \
	       "<data>500. 0. 320. 0. 500. 240. 0. 0. 1.</data></camera_matrix>\n" \
	       "<distortion_coefficients type_id=\"opencv-matrix\"><rows>1</rows><cols>4</cols>" \
	       "<dt>d</dt><data>0.1 0. 0. 0.</data></distortion_coefficients>\n"

/* OpenCV YAML and XML carry the mount as three top-level scalars. */
static void test_mount_filestorage_read(void **state)
{
	(void)state;
	struct mvod_camera c;
	char err[512] = "";
	assert_int_equal(mvod_calib_parse_filestorage(FS_YAML "mount_height_m: 1.65\nmount_pitch_deg: 2.5\n"
						      "mount_roll_deg: -0.5\n", &c, NULL, err, sizeof(err)), 0);
	assert_true(c.has_mount && c.mount_height_m == 1.65 && c.mount_pitch_deg == 2.5 &&
		    c.mount_roll_deg == -0.5);
	assert_int_equal(mvod_calib_parse_filestorage(FS_XML "<mount_height_m> 0.3 </mount_height_m>\n"
						      "<mount_roll_deg>1.5</mount_roll_deg></opencv_storage>\n",
						      &c, NULL, err, sizeof(err)), 0);
	assert_true(c.has_mount && c.mount_height_m == 0.3 && c.mount_pitch_deg == 0 &&
		    c.mount_roll_deg == 1.5);
	assert_int_equal(mvod_calib_parse_filestorage(FS_YAML, &c, NULL, err, sizeof(err)), 0);
	assert_false(c.has_mount);
}

/* Each malformed mount is refused, in YAML and in XML, the message naming the keys. */
static void test_mount_filestorage_malformed(void **state)
{
	(void)state;
	static const char *const bad[][2] = {
		{"mount_height_m", "0"},   {"mount_height_m", "-1.6"}, {"mount_height_m", "25"},
		{"mount_height_m", "\"1.6\""}, {"mount_height_m", "[1.6]"}, {"mount_height_m", ".nan"},
		{"mount_pitch_deg", "75"}, {"mount_roll_deg", "level"},
	};
	for (size_t i = 0; i < sizeof(bad) / sizeof(bad[0]); i++) {
		char text[2048], err[512] = "";
		struct mvod_camera c;
		/* A pitch or roll alone lacks the height; with the height, it is out of bounds. */
		bool height = strcmp(bad[i][0], "mount_height_m") == 0;
		snprintf(text, sizeof(text), "%s%s%s: %s\n", FS_YAML, height ? "" : "mount_height_m: 1.6\n",
			 bad[i][0], bad[i][1]);
		assert_int_equal(mvod_calib_parse_filestorage(text, &c, NULL, err, sizeof(err)), -EINVAL);
		assert_non_null(strstr(err, "\"mount_height_m\": metres above the ground"));
		if (bad[i][1][0] == '"' || bad[i][1][0] == '[')
			continue; /* XML has no quoting or sequences */
		snprintf(text, sizeof(text), FS_XML "<%s>%s</%s></opencv_storage>\n", bad[i][0], bad[i][1],
			 bad[i][0]);
		assert_int_equal(mvod_calib_parse_filestorage(text, &c, NULL, err, sizeof(err)), -EINVAL);
		assert_non_null(strstr(err, "\"mount_height_m\""));
	}
}

/* The edit, byte for byte: values replaced in place, missing keys added where the map ends. */
static void test_mount_filestorage_edit(void **state)
{
	(void)state;
	static const char *const cases[][2] = {
		/* none there: all three added; the comments (one not ASCII) and the rest kept */
		{FS_YAML "# caméra ° gauche\navg_reprojection_error: 0.25 # px\n# end\n",
		 FS_YAML "# caméra ° gauche\navg_reprojection_error: 0.25 # px\n# end\n"
		 "mount_height_m: 1.6543\nmount_pitch_deg: 2.5\nmount_roll_deg: -0.25\n"},
		/* one there, mid-file, no newline at the end: replaced, the others added */
		{FS_YAML "mount_height_m: 9  # é\nimage_name: x.png",
		 FS_YAML "mount_height_m: 1.6543  # é\nimage_name: x.png\n"
		 "mount_pitch_deg: 2.5\nmount_roll_deg: -0.25\n"},
		/* all there, after text not ASCII, CRLF line ends: replaced in place only */
		{"# ° é\r\nimage_width: 640\r\ncamera_matrix:\r\n  rows: 3\r\n  cols: 3\r\n  data: [500, 0, 320, 0, "
		 "500, 240, 0, 0, 1]\r\ndistortion_coefficients:\r\n  rows: 1\r\n  cols: 5\r\n  data: [0, 0, "
		 "0, 0, 0]\r\nmount_height_m: 1\r\nmount_pitch_deg: 0\r\nmount_roll_deg: 0\r\n",
		 "# ° é\r\nimage_width: 640\r\ncamera_matrix:\r\n  rows: 3\r\n  cols: 3\r\n  data: [500, 0, 320, 0, "
		 "500, 240, 0, 0, 1]\r\ndistortion_coefficients:\r\n  rows: 1\r\n  cols: 5\r\n  data: [0, 0, "
		 "0, 0, 0]\r\nmount_height_m: 1.6543\r\nmount_pitch_deg: 2.5\r\nmount_roll_deg: -0.25\r\n"},
	};
	const double m[3] = {1.6543, 2.5, -0.25};
	for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
		char *out = NULL, err[512] = "";
		if (mvod_calib_filestorage_set_mount(cases[i][0], m, &out, err, sizeof(err)) != 0)
			fail_msg("case %zu: %s", i, err);
		assert_string_equal(out, cases[i][1]);
		free(out);
	}
}

/*
 * OpenCV XML: the mount added as three top-level elements after the last one, each on its own
 * line as OpenCV lays them out, every other byte kept (a comment among them); set again, the
 * values are replaced where they are and nothing is added.
 */
static void test_mount_filestorage_xml(void **state)
{
	(void)state;
	const double m[3] = {1.6, -2.5, 0.25}, m2[3] = {0.75, 3, 0};
	char *out = NULL, *again = NULL, err[512] = "";
	assert_int_equal(mvod_calib_filestorage_set_mount(FS_XML "<!-- kept -->\n</opencv_storage>\n",
							  m, &out, err, sizeof(err)), 0);
	assert_string_equal(out, FS_XML "<!-- kept -->\n<mount_height_m>1.6</mount_height_m>\n"
				 "<mount_pitch_deg>-2.5</mount_pitch_deg>\n"
				 "<mount_roll_deg>0.25</mount_roll_deg>\n</opencv_storage>\n");
	assert_int_equal(mvod_calib_filestorage_set_mount(out, m2, &again, err, sizeof(err)), 0);
	assert_string_equal(again, FS_XML "<!-- kept -->\n<mount_height_m>0.75</mount_height_m>\n"
				   "<mount_pitch_deg>3</mount_pitch_deg>\n"
				   "<mount_roll_deg>0</mount_roll_deg>\n</opencv_storage>\n");
	struct mvod_camera c;
	assert_int_equal(mvod_calib_parse_filestorage(again, &c, NULL, err, sizeof(err)), 0);
	assert_true(c.has_mount && c.mount_height_m == 0.75 && c.mount_pitch_deg == 3 &&
		    c.mount_roll_deg == 0 && c.fx == 500);
	free(out);
	free(again);
	/* Not a camera: refused before any edit, with the parser's reason. */
	out = NULL;
	assert_int_equal(mvod_calib_filestorage_set_mount("<?xml version=\"1.0\"?>\n<opencv_storage>"
							  "\n</opencv_storage>\n", m, &out, err,
							  sizeof(err)), -EINVAL);
	assert_null(out);
}

/* YAML whose top level is not one key a line is refused with the way out. */
static void test_mount_filestorage_refused(void **state)
{
	(void)state;
	const double m[3] = {1.6, 0, 0};
	char *out = NULL, err[512] = "";
	assert_int_equal(mvod_calib_filestorage_set_mount(
				 "{camera_matrix: {rows: 3, cols: 3, data: [500, 0, 320, 0, 500, 240, 0, 0, "
				 "1]}, distortion_coefficients: {rows: 1, cols: 4, data: [0, 0, 0, 0]}}\n",
				 m, &out, err, sizeof(err)), -ENOTSUP);
	assert_null(out);
	assert_non_null(strstr(err, "block map"));
}

/*
 * mvod_mount_write on a YAML file: replaced by temp+rename (a new inode: never rewritten in
 * place, so never half-written), read back with the mount rounded as in mvod JSON.
 */
static void test_mount_write_yaml(void **state)
{
	(void)state;
	char path[300], err[512] = "", text[4096];
	snprintf(path, sizeof(path), "%s/cam.yml", dir);
	harness_write_file(path, FS_YAML "# kept\n");
	struct stat before, after;
	assert_int_equal(stat(path, &before), 0);
	const struct mvod_mount m = {.height_m = 1.23456, .pitch_deg = -3.14159, .roll_deg = 0.004};
	assert_int_equal(mvod_mount_write(path, FS_YAML "# kept\n", &m, err, sizeof(err)), 0);
	assert_int_equal(stat(path, &after), 0);
	assert_true(after.st_ino != before.st_ino);
	harness_read_file(path, text, sizeof(text));
	assert_string_equal(text, FS_YAML "# kept\nmount_height_m: 1.2346\nmount_pitch_deg: -3.14\n"
				  "mount_roll_deg: 0\n");
	struct mvod_camera c;
	assert_int_equal(mvod_calib_load(path, &c, err, sizeof(err)), 0);
	assert_true(c.has_mount && c.mount_height_m == 1.2346 && c.mount_pitch_deg == -3.14);
	/* XML: the same, rounded alike. */
	snprintf(path, sizeof(path), "%s/cam.xml", dir);
	harness_write_file(path, FS_XML "</opencv_storage>\n");
	assert_int_equal(mvod_mount_write(path, FS_XML "</opencv_storage>\n", &m, err, sizeof(err)), 0);
	harness_read_file(path, text, sizeof(text));
	assert_string_equal(text, FS_XML "<mount_height_m>1.2346</mount_height_m>\n"
				  "<mount_pitch_deg>-3.14</mount_pitch_deg>\n"
				  "<mount_roll_deg>0</mount_roll_deg>\n</opencv_storage>\n");
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
		cmocka_unit_test(test_mount_filestorage_read),
		cmocka_unit_test(test_mount_filestorage_malformed),
		cmocka_unit_test(test_mount_filestorage_edit),
		cmocka_unit_test(test_mount_filestorage_xml),
		cmocka_unit_test(test_mount_filestorage_refused),
		cmocka_unit_test(test_mount_write_yaml),
		cmocka_unit_test(test_mount_normal),
	};
	return cmocka_run_group_tests(tests, setup, harness_teardown);
}
