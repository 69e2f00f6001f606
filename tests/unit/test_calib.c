/* Calibration files: the mvod JSON reader and writer, the KITTI reader, each malformation. */
#include <errno.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>

#include "harness.h"

#include "mvod/calib.h"

static const char *dir;

static int setup(void **state)
{
	(void)state;
	dir = harness_tmpdir();
	return 0;
}

static const char *write_file(const char *name, const char *text)
{
	static char path[256];
	snprintf(path, sizeof(path), "%s/%s", dir, name);
	harness_write_file(path, text);
	return path;
}

#define VALID                                                                                     \
	"{\"format\": \"mvod-calibration/1\", \"model\": \"pinhole-radtan\",\n"                    \
	" \"image_size\": [640, 480],\n"                                                          \
	" \"K\": [[500.5, 0, 319.5], [0, 501.25, 239.75], [0, 0, 1]],\n"                          \
	" \"distortion\": [-0.1, 0.01, 0.001, -0.002, 0.0005]}"

static void test_valid_json(void **state)
{
	(void)state;
	struct mvod_camera c;
	char err[256] = "";
	assert_int_equal(mvod_calib_parse_json(VALID, &c, err, sizeof(err)), 0);
	assert_int_equal(c.width, 640);
	assert_int_equal(c.height, 480);
	assert_true(c.fx == 500.5 && c.fy == 501.25 && c.cx == 319.5 && c.cy == 239.75);
	assert_int_equal(c.model, MVOD_CAM_PINHOLE_RADTAN);
	assert_int_equal(c.n_dist, 5);
	assert_true(c.dist[0] == -0.1 && c.dist[4] == 0.0005);
	assert_true(mvod_camera_has_distortion(&c));
}

/* Each malformation is rejected with a message naming the offending field. */
static void test_malformed_json(void **state)
{
	(void)state;
	static const struct {
		const char *text, *needle;
	} cases[] = {
		{"{", "JSON"},
		{"[1,2]", "format"},
		{"{\"format\": \"other/2\"}", "format"},
		{"{\"format\": \"mvod-calibration/1\", \"model\": \"pinhole-radtan\", \"image_size\": "
		 "[640, 480], \"K\": [[500,0,320],[0,500,240],[0,0,1]], \"distortion\": []}",
		 NULL},
		{"{\"format\": \"mvod-calibration/1\", \"model\": \"weird\"}", "model"},
		{"{\"format\": \"mvod-calibration/1\", \"model\": \"pinhole-radtan\", \"image_size\": "
		 "[640]}", "image_size"},
		{"{\"format\": \"mvod-calibration/1\", \"model\": \"pinhole-radtan\", \"image_size\": "
		 "[640.5, 480]}", "image_size"},
		{"{\"format\": \"mvod-calibration/1\", \"model\": \"pinhole-radtan\", \"image_size\": "
		 "[640, 480], \"K\": [[500,0,320],[0,500,240]]}", "K"},
		{"{\"format\": \"mvod-calibration/1\", \"model\": \"pinhole-radtan\", \"image_size\": "
		 "[640, 480], \"K\": [[-5,0,320],[0,500,240],[0,0,1]], \"distortion\": []}", "K"},
		{"{\"format\": \"mvod-calibration/1\", \"model\": \"pinhole-radtan\", \"image_size\": "
		 "[640, 480], \"K\": [[500,0,320],[0,\"x\",240],[0,0,1]], \"distortion\": []}", "K"},
		{"{\"format\": \"mvod-calibration/1\", \"model\": \"pinhole-radtan\", \"image_size\": "
		 "[640, 480], \"K\": [[500,0,320],[0,500,240],[0,0,1]], \"distortion\": [1,2,3]}",
		 "distortion"},
		{"{\"format\": \"mvod-calibration/1\", \"model\": \"fisheye-kb4\", \"image_size\": "
		 "[640, 480], \"K\": [[500,0,320],[0,500,240],[0,0,1]], \"distortion\": [1,2,3,4,5]}",
		 "distortion"},
		{"{\"format\": \"mvod-calibration/1\", \"model\": \"pinhole-radtan\", \"image_size\": "
		 "[640, 480], \"K\": [[500,0,320],[0,500,240],[0,0,1]]}", "distortion"},
		{"{\"format\": \"mvod-calibration/1\", \"model\": \"pinhole-radtan\", \"image_size\": "
		 "[640, 480], \"K\": [[500,0,320],[0,500,240],[0,0,1]], \"distortion\": [], "
		 "\"verdict\": 3}", "verdict"},
	};
	for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
		struct mvod_camera c;
		char err[256] = "";
		int ret = mvod_calib_parse_json(cases[i].text, &c, err, sizeof(err));
		if (!cases[i].needle) {
			assert_int_equal(ret, 0); /* the well-formed control case */
			continue;
		}
		assert_int_equal(ret, -EINVAL);
		if (!strstr(err, cases[i].needle))
			fail_msg("case %zu: '%s' does not mention %s", i, err, cases[i].needle);
	}
}

static void test_kitti(void **state)
{
	(void)state;
	const char *p = write_file("calib.txt",
		"P0: 7.070912000000e+02 0.000000000000e+00 6.018873000000e+02 0.000000000000e+00 "
		"0.000000000000e+00 7.070912000000e+02 1.831104000000e+02 0.000000000000e+00 "
		"0.000000000000e+00 0.000000000000e+00 1.000000000000e+00 0.000000000000e+00\n"
		"P1: 1 2 3 4 5 6 7 8 9 10 11 12\n");
	struct mvod_camera c;
	char err[256] = "";
	assert_int_equal(mvod_calib_load(p, &c, err, sizeof(err)), 0);
	assert_true(c.fx == 707.0912 && c.fy == 707.0912 && c.cx == 601.8873 && c.cy == 183.1104);
	assert_int_equal(c.width, 0);
	assert_int_equal(c.n_dist, 0);

	p = write_file("short.txt", "P0: 7.07e+02 0 6.0e+02 0 0 7.07e+02\n");
	assert_int_equal(mvod_calib_load_kitti(p, &c, err, sizeof(err)), -EINVAL);
	assert_non_null(strstr(err, "12 numbers"));
	p = write_file("nop0.txt", "P1: 1 2 3 4 5 6 7 8 9 10 11 12\n");
	assert_int_equal(mvod_calib_load_kitti(p, &c, err, sizeof(err)), -EINVAL);
	assert_non_null(strstr(err, "P0"));
}

static void test_load_errors(void **state)
{
	(void)state;
	struct mvod_camera c;
	char err[256] = "";
	char missing[300];
	snprintf(missing, sizeof(missing), "%s/none.json", dir);
	assert_int_equal(mvod_calib_load(missing, &c, err, sizeof(err)), -ENOENT);
	assert_non_null(strstr(err, "none.json"));
	const char *p = write_file("junk.yaml", "%YAML:1.0\nfoo: bar\n");
	assert_int_equal(mvod_calib_load(p, &c, err, sizeof(err)), -EINVAL);
	assert_non_null(strstr(err, "unknown calibration format"));
	p = write_file("bad.json", "{\"format\": \"mvod-calibration/1\", \"model\": 3}");
	assert_int_equal(mvod_calib_load(p, &c, err, sizeof(err)), -EINVAL);
	assert_non_null(strstr(err, "bad.json"));
	assert_non_null(strstr(err, "model"));
}

static void test_save_round_trip(void **state)
{
	(void)state;
	struct mvod_camera c = {.width = 1226, .height = 370, .fx = 707.0912, .fy = 707.0913,
				.cx = 601.8873, .cy = 183.1104, .model = MVOD_CAM_FISHEYE_KB4,
				.n_dist = 4, .dist = {0.1, -0.02, 0.003, 1.0 / 3.0}};
	struct mvod_calib_meta meta = {.rms_px = 0.25, .board = "charuco:5x7:0.04:0.02:DICT_6X6_250",
				       .source = "test"};
	char path[300];
	snprintf(path, sizeof(path), "%s/out.json", dir);
	assert_int_equal(mvod_calib_save(path, &c, &meta), 0);
	struct mvod_camera r;
	char err[256] = "";
	assert_int_equal(mvod_calib_load(path, &r, err, sizeof(err)), 0);
	/* Bit-exact: the writer prints enough digits to round-trip every double. */
	assert_memory_equal(&c.fx, &r.fx, 4 * sizeof(double));
	assert_memory_equal(c.dist, r.dist, 4 * sizeof(double));
	assert_int_equal(r.model, MVOD_CAM_FISHEYE_KB4);
	assert_int_equal(r.width, 1226);
	assert_string_equal(r.verdict, ""); /* none recorded */
	/*
	 * mvod calibrate's verdict reads back (mvod run warns on it), and a file saved from a
	 * camera read with one, by calib-convert, keeps it; the meta's own verdict comes first.
	 */
	snprintf(meta.verdict, sizeof(meta.verdict), "not one camera");
	char judged[300], converted[300];
	snprintf(judged, sizeof(judged), "%s/judged.json", dir);
	snprintf(converted, sizeof(converted), "%s/converted.json", dir);
	assert_int_equal(mvod_calib_save(judged, &c, &meta), 0);
	assert_int_equal(mvod_calib_load(judged, &r, err, sizeof(err)), 0);
	assert_string_equal(r.verdict, "not one camera");
	assert_int_equal(mvod_calib_save(converted, &r, &(struct mvod_calib_meta){.rms_px = -1}), 0);
	assert_int_equal(mvod_calib_load(converted, &r, err, sizeof(err)), 0);
	assert_string_equal(r.verdict, "not one camera");
	/* A failed save (unwritable directory) leaves nothing behind. */
	assert_true(mvod_calib_save("/nonexistent-dir/x.json", &c, NULL) < 0);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_valid_json),
		cmocka_unit_test(test_malformed_json),
		cmocka_unit_test(test_kitti),
		cmocka_unit_test(test_load_errors),
		cmocka_unit_test(test_save_round_trip),
	};
	return cmocka_run_group_tests(tests, setup, harness_teardown);
}
