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
#include <time.h>

#include <cmocka.h>

#include "harness.h"

#include "capture/dataset.h"
#include "capture/euroc_sensor.h"
#include "capture/oxts.h"

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

/* KITTI raw's timestamps.txt: calendar times to the nanosecond, against glibc's timegm. */
static void test_parse_calendar(void **state)
{
	(void)state;
	const char *end;
	int64_t ns;
	/* drive 0001's first line */
	assert_int_equal(mvod_ds_parse_calendar("2011-09-26 13:02:25.964389445", &end, &ns), 0);
	struct tm tm = {.tm_year = 111, .tm_mon = 8, .tm_mday = 26, .tm_hour = 13, .tm_min = 2,
			.tm_sec = 25};
	assert_true(ns == (int64_t)timegm(&tm) * 1000000000 + 964389445);
	assert_string_equal(end, "");
	/* Leap days, the last second of a year, no decimals, digits past nine dropped. */
	static const char *const days[] = {"2012-02-29 00:00:00", "2000-02-29 12:00:00.5",
					   "2011-12-31 23:59:59.1234567891", "1970-01-01 00:00:00"};
	static const int ymd[4][6] = {{112, 1, 29, 0, 0, 0}, {100, 1, 29, 12, 0, 0},
				      {111, 11, 31, 23, 59, 59}, {70, 0, 1, 0, 0, 0}};
	static const int64_t frac[4] = {0, 500000000, 123456789, 0};
	for (int i = 0; i < 4; i++) {
		struct tm t = {.tm_year = ymd[i][0], .tm_mon = ymd[i][1], .tm_mday = ymd[i][2],
			       .tm_hour = ymd[i][3], .tm_min = ymd[i][4], .tm_sec = ymd[i][5]};
		assert_int_equal(mvod_ds_parse_calendar(days[i], &end, &ns), 0);
		assert_true(ns == (int64_t)timegm(&t) * 1000000000 + frac[i]);
	}
	/* No such day, hour or second; a field of other width; no date before 1970. */
	static const char *const bad[] = {"2011-02-29 00:00:00", "1900-02-29 00:00:00",
					  "2011-09-31 00:00:00", "2011-09-26 24:00:00",
					  "2011-09-26 13:02:60", "2011-9-26 13:02:25",
					  "2011-09-26T13:02:25", "1969-12-31 23:59:59",
					  "20110-09-26 13:02:25", "2011-09-26 13:02"};
	for (size_t i = 0; i < sizeof(bad) / sizeof(bad[0]); i++)
		if (mvod_ds_parse_calendar(bad[i], &end, &ns) != -EINVAL)
			fail_msg("\"%s\" read as a time", bad[i]);
}

/*
 * The devkit's OXTS conversion: the Mercator projection is metric at the scale's latitude
 * (1e-5 degrees north is 1.1131949 m on its 6378137 m sphere: 6378137 pi / 180 1e-5), east by
 * the scale; the Euler angles turn the IMU's axes as dataformat.txt says. Bounds: a step
 * centred on the latitude leaves the projection's third-order term (1e-14 relative) and the
 * roundings of coordinates near 5.4e6 m (1e-9 m each).
 */
static void test_oxts_pose(void **state)
{
	(void)state;
	const double lat = 49.011213, lon = 8.4235924, s = mvod_oxts_scale(lat);
	struct mvod_pose a, b;
	mvod_oxts_pose((double[6]){lat - 0.5e-5, lon, 112.83, 0, 0, 0}, s, &a);
	mvod_oxts_pose((double[6]){lat + 0.5e-5, lon + 1e-5, 113.83, 0, 0, 0}, s, &b);
	const double m = 6378137 * M_PI / 180 * 1e-5;
	assert_true(fabs(b.t[1] - a.t[1] - m) < 1e-8);
	assert_true(fabs(b.t[0] - a.t[0] - s * m) < 1e-8);
	assert_true(b.t[2] - a.t[2] == 1);
	assert_true(a.R[0] == 1 && a.R[4] == 1 && a.R[8] == 1);
	/* yaw pi/2: forward (x) is north; pitch 0.1: forward dips; roll 0.1: left (y) rises. */
	mvod_oxts_pose((double[6]){lat, lon, 0, 0, 0, M_PI / 2}, s, &a);
	assert_true(fabs(a.R[3] - 1) < 1e-15 && fabs(a.R[0]) < 1e-15);
	mvod_oxts_pose((double[6]){lat, lon, 0, 0, 0.1, 0}, s, &a);
	assert_true(fabs(a.R[6] + sin(0.1)) < 1e-15);
	mvod_oxts_pose((double[6]){lat, lon, 0, 0.1, 0, 0}, s, &a);
	assert_true(fabs(a.R[7] - sin(0.1)) < 1e-15);
}

/*
 * 2011_09_26's calibration as the KITTI raw download has it (calib_imu_to_velo.txt and
 * calib_velo_to_cam.txt whole, camera 00's lines of calib_cam_to_cam.txt).
 */
static const char cam_to_cam[] =
	"calib_time: 09-Jan-2012 13:57:47\n"
	"corner_dist: 9.950000e-02\n"
	"S_00: 1.392000e+03 5.120000e+02\n"
	"S_rect_00: 1.242000e+03 3.750000e+02\n"
	"R_rect_00: 9.999239e-01 9.837760e-03 -7.445048e-03 -9.869795e-03 9.999421e-01 "
	"-4.278459e-03 7.402527e-03 4.351614e-03 9.999631e-01\n"
	"P_rect_00: 7.215377e+02 0.000000e+00 6.095593e+02 0.000000e+00 0.000000e+00 7.215377e+02 "
	"1.728540e+02 0.000000e+00 0.000000e+00 0.000000e+00 1.000000e+00 0.000000e+00\n";
static const char velo_to_cam[] =
	"calib_time: 15-Mar-2012 11:37:16\n"
	"R: 7.533745e-03 -9.999714e-01 -6.166020e-04 1.480249e-02 7.280733e-04 -9.998902e-01 "
	"9.998621e-01 7.523790e-03 1.480755e-02\n"
	"T: -4.069766e-03 -7.631618e-02 -2.717806e-01\n"
	"delta_f: 0.000000e+00 0.000000e+00\n"
	"delta_c: 0.000000e+00 0.000000e+00\n";
static const char imu_to_velo[] =
	"calib_time: 25-May-2012 16:47:16\n"
	"R: 9.999976e-01 7.553071e-04 -2.035826e-03 -7.854027e-04 9.998898e-01 -1.482298e-02 "
	"2.024406e-03 1.482454e-02 9.998881e-01\n"
	"T: -8.086759e-01 3.195559e-01 -7.997231e-01\n";

static const char *write_calib(const char *ctc)
{
	const char *dir = harness_tmpdir();
	char path[512];
	snprintf(path, sizeof(path), "%s/calib_cam_to_cam.txt", dir);
	harness_write_file(path, ctc);
	snprintf(path, sizeof(path), "%s/calib_velo_to_cam.txt", dir);
	harness_write_file(path, velo_to_cam);
	snprintf(path, sizeof(path), "%s/calib_imu_to_velo.txt", dir);
	harness_write_file(path, imu_to_velo);
	return dir;
}

static void test_kitti_raw_calib(void **state)
{
	(void)state;
	struct mvod_camera cam;
	struct mvod_pose ci, ic;
	char err[512] = "";
	if (mvod_kitti_raw_calib(write_calib(cam_to_cam), &cam, &ci, err, sizeof(err)))
		fail_msg("%s", err);
	assert_true(cam.width == 1242 && cam.height == 375 && cam.fx == 721.5377 &&
		    cam.fy == 721.5377 && cam.cx == 609.5593 && cam.cy == 172.854 && cam.n_dist == 0);
	/*
	 * A rotation to rounding, and the camera 1.08 m ahead of the IMU, 0.31 m right, 0.73 m
	 * up: the files' R and T composed apart (R^T for the inverse), within 1e-6 m since the
	 * files' rotations are orthonormal to 1e-7 and the lever arm is 1.3 m.
	 */
	double RtR[9];
	mvod_mat3_mul_at(ci.R, ci.R, RtR);
	for (int k = 0; k < 9; k++)
		assert_true(fabs(RtR[k] - (k % 4 == 0)) < 1e-15);
	mvod_pose_inverse(&ci, &ic);
	const double where[3] = {1.0833019124837928, -0.3098888727850286, 0.7299198345507933};
	assert_true(mvod_vec3_dist(ic.t, where) < 1e-6);
	/*
	 * And turned as the three rotations multiply, R_rect_00 first (composed apart; its
	 * nearest rotation moves it 1e-7): the camera's z along the IMU's x, its x the IMU's -y.
	 */
	const double R[9] = {0.000998747205656552, -0.9999903820710413, 0.004259378487635177,
			     0.008416901827557416, -0.004250821136069464, -0.9999555696753274,
			     0.9999640486966583,   0.0010345532842263618, 0.008412575208732587};
	for (int k = 0; k < 9; k++)
		assert_true(fabs(ci.R[k] - R[k]) < 1e-6);
	/* A key missing, or short of numbers, names the file and the line. */
	char text[2048];
	snprintf(text, sizeof(text), "%s", cam_to_cam);
	*strstr(text, "P_rect_00") = 'Q';
	assert_int_equal(mvod_kitti_raw_calib(write_calib(text), &cam, &ci, err, sizeof(err)),
			 -EINVAL);
	assert_non_null(strstr(err, "calib_cam_to_cam.txt has no P_rect_00"));
	snprintf(text, sizeof(text), "%s", cam_to_cam);
	memcpy(strstr(text, "3.750000e+02"), "3.750000e+0x", 12);
	assert_int_equal(mvod_kitti_raw_calib(write_calib(text), &cam, &ci, err, sizeof(err)),
			 -EINVAL);
	assert_non_null(strstr(err, "calib_cam_to_cam.txt line 4: S_rect_00 must be 2 numbers"));
	snprintf(text, sizeof(text), "%sS_rect_00: 1.242000e+03 3.750000e+02\n", cam_to_cam);
	assert_int_equal(mvod_kitti_raw_calib(write_calib(text), &cam, &ci, err, sizeof(err)),
			 -EINVAL);
	assert_non_null(strstr(err, "calib_cam_to_cam.txt line 7: S_rect_00 again (first on line 4)"));
}

static void test_oxts_read(void **state)
{
	(void)state;
	const char *path = harness_tmp_path("0000000000.txt");
	/* drive 0001's first packet, as the dataset prints it. */
	harness_write_file(path, "49.015003823272 8.4342971002335 116.43032836914 0.035752 0.00903 "
			   "-1.6071159189143 -2.2207754262503 -12.930025311342 12.872213862227 "
			   "2.4081542046026 0.14524627208781 -0.27429016623163 -0.93233011838542 "
			   "9.6936612373749 -0.80211604962628 -0.50221005398798 9.8069093155893 "
			   "0.013402052487622 0.016117592845283 -0.0027232130356244 "
			   "0.013223419811708 0.017002025279419 -0.0022223389802154 "
			   "0.11602428090011 0.030618340395178 4 11 6 6 6\n");
	double p[6];
	char err[512] = "";
	if (mvod_oxts_read(path, p, err, sizeof(err)))
		fail_msg("%s", err);
	assert_true(p[0] == 49.015003823272 && p[5] == -1.6071159189143);
	harness_write_file(path, "49.01 8.43 116.4 0.03 0.009 -1.6\n");
	assert_int_equal(mvod_oxts_read(path, p, err, sizeof(err)), -EINVAL);
	assert_non_null(strstr(err, "0000000000.txt line 1: an OXTS packet is 30 numbers"));
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
		cmocka_unit_test(test_parse_calendar),
		cmocka_unit_test(test_oxts_pose),
		cmocka_unit_test(test_kitti_raw_calib),
		cmocka_unit_test(test_oxts_read),
	};
	return cmocka_run_group_tests(tests, NULL, harness_teardown);
}
