/*
 * The dataset sources' text parsers: timestamps read exactly into int64 nanoseconds (a double
 * holds 1.4e18 ns only to 256 ns), and the pose columns of EuRoC and TUM ground truth.
 */
#include <errno.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "harness.h"

#include "capture/dataset.h"
#include "capture/euroc.h"

static void test_parse_ns(void **state)
{
	(void)state;
	const char *end;
	int64_t ns;
	/* EuRoC's 19 digits, to the last one. */
	assert_int_equal(mvod_ds_parse_ns("1403636579763555584,x.png", &end, &ns), 0);
	assert_true(ns == 1403636579763555584LL);
	assert_string_equal(end, ",x.png");
	assert_int_equal(mvod_ds_parse_ns(" 9223372036854775807", &end, &ns), 0);
	assert_true(ns == INT64_MAX);
	/* One more is past int64; so is a 20th digit; no digit, or a sign, is no time. */
	assert_int_equal(mvod_ds_parse_ns("9223372036854775808", &end, &ns), -EINVAL);
	assert_int_equal(mvod_ds_parse_ns("14036365797635555840", &end, &ns), -EINVAL);
	assert_int_equal(mvod_ds_parse_ns(",x.png", &end, &ns), -EINVAL);
	assert_int_equal(mvod_ds_parse_ns("-1", &end, &ns), -EINVAL);
}

static void test_parse_seconds(void **state)
{
	(void)state;
	const char *end;
	int64_t ns;
	assert_int_equal(mvod_ds_parse_seconds("1305031102.175304 rgb/a.png", &end, &ns), 0);
	assert_true(ns == 1305031102175304000LL);
	assert_string_equal(end, " rgb/a.png");
	/* Nanoseconds exactly; digits below them dropped, not rounded into a carry. */
	assert_int_equal(mvod_ds_parse_seconds("1403636579.7635555849999", &end, &ns), 0);
	assert_true(ns == 1403636579763555584LL);
	assert_string_equal(end, "");
	assert_int_equal(mvod_ds_parse_seconds("12", &end, &ns), 0);
	assert_true(ns == 12000000000LL);
	assert_int_equal(mvod_ds_parse_seconds("0.5", &end, &ns), 0);
	assert_true(ns == 500000000);
	/* Past the year 2262 int64 nanoseconds end; signs and exponents are no TUM times. */
	assert_int_equal(mvod_ds_parse_seconds("9223372036.0", &end, &ns), -EINVAL);
	assert_int_equal(mvod_ds_parse_seconds("-1.5", &end, &ns), -EINVAL);
	assert_int_equal(mvod_ds_parse_seconds(".5", &end, &ns), -EINVAL);
	assert_int_equal(mvod_ds_parse_seconds("1e9", &end, &ns), 0);
	assert_string_equal(end, "e9"); /* the caller sees what follows and refuses it */
}

static void test_parse_pose(void **state)
{
	(void)state;
	struct mvod_pose p;
	char why[256] = "";
	/* EuRoC: w first, comma-separated, velocities and biases may follow. */
	assert_int_equal(mvod_ds_parse_pose(",1,2,3,0,0,0,1,9,9,9", ',', true, &p, why, sizeof(why)), 0);
	assert_true(p.t[0] == 1 && p.t[1] == 2 && p.t[2] == 3);
	/* q = (w 0, z 1): a half turn about z. */
	assert_true(fabs(p.R[0] + 1) < 1e-15 && fabs(p.R[4] + 1) < 1e-15 && p.R[8] == 1);
	/* TUM: w last, whitespace, nothing after. */
	assert_int_equal(mvod_ds_parse_pose(" 1 2 3 0 0 0 1", ' ', false, &p, why, sizeof(why)), 0);
	assert_true(p.R[0] == 1 && p.R[4] == 1 && p.R[8] == 1);
	assert_int_equal(mvod_ds_parse_pose(" 1 2 3 0 0 0 1 5", ' ', false, &p, why, sizeof(why)), -EINVAL);
	assert_int_equal(mvod_ds_parse_pose(" 1 2 3 0 0 0", ' ', false, &p, why, sizeof(why)), -EINVAL);
	assert_int_equal(mvod_ds_parse_pose(",1,2,3,0,0,0", ',', true, &p, why, sizeof(why)), -EINVAL);
	assert_int_equal(mvod_ds_parse_pose(",1,2,nan,0,0,0,1", ',', true, &p, why, sizeof(why)), -EINVAL);
	/* The separator must be there: "1.4,0" is no TUM line, "1 2" no EuRoC one. */
	assert_int_equal(mvod_ds_parse_pose(",1 2 3 0 0 0 1", ' ', false, &p, why, sizeof(why)), -EINVAL);
	assert_int_equal(mvod_ds_parse_pose(" 1 2 3 0 0 0 1", ',', true, &p, why, sizeof(why)), -EINVAL);
	assert_string_equal(why, ""); /* no pose line: the caller names the layout */
	/*
	 * Numbers that are no pose, each with the reason: a zero quaternion (39 of 40 trajectory
	 * lines were nan), one off unit length by more than 1 %, a position past any on Earth.
	 */
	assert_int_equal(mvod_ds_parse_pose(",1,2,3,0,0,0,0", ',', true, &p, why, sizeof(why)),
			 -EINVAL);
	assert_string_equal(why, "quaternion (qx qy qz qw) = (0 0 0 0) has length 0, not 1 (within "
				 "0.01): no rotation");
	assert_int_equal(mvod_ds_parse_pose(" 1 2 3 0 0 0 1.0101", ' ', false, &p, why,
					    sizeof(why)), -EINVAL);
	assert_int_equal(mvod_ds_parse_pose(" 1 2 3 0 0 0 1.0099", ' ', false, &p, why,
					    sizeof(why)), 0);
	assert_true(fabs(p.R[0] - 1) < 1e-15); /* normalised */
	assert_int_equal(mvod_ds_parse_pose(",1e308,2,3,1,0,0,0", ',', true, &p, why, sizeof(why)),
			 -EINVAL);
	assert_non_null(strstr(why, "position (1e+308 2 3) m is that far: no pose on Earth is more "
				    "than 1e+08 m from the origin"));
}

/*
 * Frames of an index must be a microsecond apart at least, mvod's frame clock: 1000 and 1400
 * ns were two frames at one time (fuzz/euroc_index).
 */
static void test_frames_a_microsecond_apart(void **state)
{
	(void)state;
	struct mvod_ds_frames f = {0};
	char err[512] = "";
	const char *dir = harness_tmpdir();
	harness_write_file(harness_tmp_path("1.png"), "");
	harness_write_file(harness_tmp_path("2.png"), "");
	assert_int_equal(mvod_ds_frames_add(&f, "data.csv", 1, dir, "1.png", 1000, err, sizeof(err)),
			 0);
	assert_int_equal(mvod_ds_frames_add(&f, "data.csv", 2, dir, "2.png", 1400, err, sizeof(err)),
			 -EINVAL);
	assert_non_null(strstr(err, "data.csv line 2: time 0.000001400 s is not after "
				    "0.000001000 s of line 1: the frames (to the microsecond)"));
	assert_int_equal(mvod_ds_frames_add(&f, "data.csv", 2, dir, "2.png", 1500, err, sizeof(err)),
			 0);
	mvod_ds_frames_free(&f);
}

/*
 * MH_01_easy's mav0/cam0/sensor.yaml as the EuRoC MAV dataset publishes it (the copy in
 * andreruas/scratch_slam, byte for byte: comments, T_BS's data over four lines, no newline
 * at the end), in the ASL dataset format.
 */
static const char euroc_mh01_cam0[] =
	"# General sensor definitions.\n"
	"sensor_type: camera\n"
	"comment: VI-Sensor cam0 (MT9M034)\n"
	"\n"
	"# Sensor extrinsics wrt. the body-frame.\n"
	"T_BS:\n"
	"  cols: 4\n"
	"  rows: 4\n"
	"  data: [0.0148655429818, -0.999880929698, 0.00414029679422, -0.0216401454975,\n"
	"         0.999557249008, 0.0149672133247, 0.025715529948, -0.064676986768,\n"
	"        -0.0257744366974, 0.00375618835797, 0.999660727178, 0.00981073058949,\n"
	"         0.0, 0.0, 0.0, 1.0]\n"
	"\n"
	"# Camera specific definitions.\n"
	"rate_hz: 20\n"
	"resolution: [752, 480]\n"
	"camera_model: pinhole\n"
	"intrinsics: [458.654, 457.296, 367.215, 248.375] #fu, fv, cu, cv\n"
	"distortion_model: radial-tangential\n"
	"distortion_coefficients: [-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05]";

/* text as a sensor.yaml, read: 0 or the error, its message in err. */
static int load_sensor(const char *text, struct mvod_camera *cam, struct mvod_pose *bs,
		       char *err, size_t errlen)
{
	const char *path = harness_tmp_path("sensor.yaml");
	harness_write_file(path, text);
	return mvod_euroc_sensor_load(path, cam, bs, err, errlen);
}

static void expect_mh01(const char *text)
{
	struct mvod_camera cam;
	struct mvod_pose bs;
	char err[512] = "";
	if (load_sensor(text, &cam, &bs, err, sizeof(err)) != 0)
		fail_msg("%s", err);
	assert_int_equal(cam.width, 752);
	assert_int_equal(cam.height, 480);
	assert_true(cam.fx == 458.654 && cam.fy == 457.296 && cam.cx == 367.215 &&
		    cam.cy == 248.375);
	assert_int_equal(cam.model, MVOD_CAM_PINHOLE_RADTAN);
	assert_int_equal(cam.n_dist, 4);
	assert_true(cam.dist[0] == -0.28340811 && cam.dist[3] == 1.76187114e-05);
	/* T_BS row-major: R's first row, then t's x at the end of it. */
	assert_true(bs.R[0] == 0.0148655429818 && bs.R[1] == -0.999880929698);
	assert_true(bs.R[8] == 0.999660727178);
	assert_true(bs.t[0] == -0.0216401454975 && bs.t[2] == 0.00981073058949);
}

/*
 * The published sensor.yaml, and the copy a FileStorage reader wants (Kimera-VIO: "Make sure
 * that each YAML file has %YAML:1.0 as first line"; OpenCV itself writes "%YAML:1.0\n---"),
 * which plain libyaml stops at on line 1; T_BS also as OpenCV writes a matrix.
 */
static void test_euroc_sensor_as_published(void **state)
{
	(void)state;
	char text[4096];
	expect_mh01(euroc_mh01_cam0);
	snprintf(text, sizeof(text), "%%YAML:1.0\n%s\n", euroc_mh01_cam0);
	expect_mh01(text);
	snprintf(text, sizeof(text), "%%YAML:1.0\n---\n%s", euroc_mh01_cam0);
	const char *t = strstr(text, "T_BS:\n");
	char tagged[4096];
	snprintf(tagged, sizeof(tagged), "%.*sT_BS: !!opencv-matrix\n  dt: d\n%s",
		 (int)(t - text), text, t + strlen("T_BS:\n"));
	expect_mh01(tagged);
}

/* A broken sensor.yaml names the file and the line, OpenCV's directive counted as line 1. */
static void test_euroc_sensor_lines(void **state)
{
	(void)state;
	char text[4096], err[512] = "";
	struct mvod_camera cam;
	struct mvod_pose bs;
	snprintf(text, sizeof(text), "%%YAML:1.0\n%s", euroc_mh01_cam0);
	*strstr(text, "[752") = '{';
	assert_int_equal(load_sensor(text, &cam, &bs, err, sizeof(err)), -EINVAL);
	if (!strstr(err, "sensor.yaml: not YAML: YAML error at line 17"))
		fail_msg("%s", err);
	snprintf(text, sizeof(text), "%%YAML:1.0\n%s", euroc_mh01_cam0);
	memcpy(strstr(text, "rows: 4"), "rows: 3", 7);
	assert_int_equal(load_sensor(text, &cam, &bs, err, sizeof(err)), -EINVAL);
	if (!strstr(err, "sensor.yaml line 10: T_BS data holds 16 numbers, not rows x cols = 3 x 4"))
		fail_msg("%s", err);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_parse_ns),
		cmocka_unit_test(test_parse_seconds),
		cmocka_unit_test(test_parse_pose),
		cmocka_unit_test(test_frames_a_microsecond_apart),
		cmocka_unit_test(test_euroc_sensor_as_published),
		cmocka_unit_test(test_euroc_sensor_lines),
	};
	return cmocka_run_group_tests(tests, NULL, harness_teardown);
}
