/*
 * Issue 18's frames and clocks for a robot, on the real binary and an mvod-synth drive with a
 * 90 degree left turn: --frame ros (x forward, y left, z up) and a camera-to-body extrinsic,
 * applied to the trajectory and to LCM alike while the evaluation stays the camera's; the
 * per-pose quality and the capture-to-publish latency of mvod.pose2_t and status2_t; a camera
 * that never moves is never "tracked"; what the options refuse.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "harness.h"
#include "mvod/geom.h"
#include "mvod/traj.h"

/*
 * The turn (the middle 40 % of the path) over 14 frames, 6.4 degrees a frame: tracked
 * throughout at 320x240 (with 20 frames, 11 degrees a frame, tracking is lost in the turn).
 */
#define FRAMES 36
/* The extrinsic of the body runs: the camera 0.5 m ahead, 0.1 m left, 0.3 m up, level. */
#define LEVER "0.5,0.1,0.3"
#define LEVEL "-0.5,0.5,-0.5,0.5"
static const double lever[3] = {0.5, 0.1, 0.3};

static char video[400], calib[400], gt[400];
static char cam_traj[300], ros_traj[300], body_traj[300], cam_log[300], body_log[300];
static char cam_out[16384], body_out[16384]; /* the runs' stdout: their summaries */

static void run_ok(char **argv, char *out, size_t len)
{
	struct run_result r;
	assert_int_equal(harness_run(argv, &r), 0);
	if (!r.exited || r.status != 0)
		fail_msg("mvod: exit %d: %s", r.status, r.err);
	if (out)
		snprintf(out, len, "%s", r.out);
}

/*
 * mvod --scale gt on the drive into traj, publishing into the LCM log url (NULL: --no-lcm),
 * with extra arguments (NULL-terminated, at most 8). --frontend orb: the figures below were
 * measured with it, and klt (the default) loses this turn's 6.4 degrees a frame (yaw error
 * up to 12 degrees a frame, measured; BENCHMARKS.md, "The default front end and track cap").
 */
static void run_drive(const char *traj, const char *url, char *out, size_t len, ...)
{
	char *argv[24] = {(char *)harness_bin("MVOD"), "--source", video, "--calib", calib,
			  "--scale", "gt", "--gt", gt, "--trajectory", (char *)traj,
			  "--frontend", "orb"};
	int n = 13;
	if (url) {
		argv[n++] = "--lcm-url";
		argv[n++] = (char *)url;
	} else {
		argv[n++] = "--no-lcm";
	}
	va_list ap;
	va_start(ap, len);
	for (char *a; (a = va_arg(ap, char *)) && n < 22;)
		argv[n++] = a;
	va_end(ap);
	argv[n] = NULL;
	run_ok(argv, out, len);
}

static int setup(void **state)
{
	(void)state;
	char seq[300], url_cam[400], url_body[400];
	snprintf(seq, sizeof(seq), "%s/turn", harness_tmpdir());
	harness_synth(seq, "turn", FRAMES, "mkv", "--size", "320x240", NULL);
	snprintf(video, sizeof(video), "file:%s/video.mkv", seq);
	snprintf(calib, sizeof(calib), "%s/calib.json", seq);
	snprintf(gt, sizeof(gt), "%s/gt.tum", seq);
	snprintf(cam_traj, sizeof(cam_traj), "%s/cam.tum", harness_tmpdir());
	snprintf(ros_traj, sizeof(ros_traj), "%s/ros.tum", harness_tmpdir());
	snprintf(body_traj, sizeof(body_traj), "%s/body.tum", harness_tmpdir());
	snprintf(cam_log, sizeof(cam_log), "%s/cam.lcmlog", harness_tmpdir());
	snprintf(body_log, sizeof(body_log), "%s/body.lcmlog", harness_tmpdir());
	snprintf(url_cam, sizeof(url_cam), "file://%s?mode=w", cam_log);
	snprintf(url_body, sizeof(url_body), "file://%s?mode=w", body_log);
	run_drive(cam_traj, url_cam, cam_out, sizeof(cam_out), NULL);
	run_drive(ros_traj, NULL, NULL, 0, "--frame", "ros", NULL);
	run_drive(body_traj, url_body, body_out, sizeof(body_out), "--frame", "ros",
		  "--camera-to-body", LEVER "," LEVEL, NULL);
	return 0;
}

static void load(const char *path, struct mvod_traj *t)
{
	char err[512];
	if (mvod_traj_load(path, t, err, sizeof(err)))
		fail_msg("%s", err);
	assert_int_equal(t->n, FRAMES);
}

/* TUM files carry 9 significant digits: 1e-6 is rounding for paths of a few metres. */
#define FILE_TOL 1e-6

/*
 * --frame ros: the camera's path with the axes renamed (ros x = camera z, y = -camera x,
 * z = -camera y), pose by pose; and, against the drive itself, the left turn is a positive
 * yaw about z (up) and the path bends to +y (left).
 */
static void test_ros_axes(void **state)
{
	(void)state;
	struct mvod_traj c, r;
	load(cam_traj, &c);
	load(ros_traj, &r);
	static const double P[9] = {0, 0, 1, -1, 0, 0, 0, -1, 0};
	for (int i = 0; i < FRAMES; i++) {
		const double *t = c.pose[i].t;
		const double want_t[3] = {t[2], -t[0], -t[1]};
		double PR[9], want_R[9];
		mvod_mat3_mul(P, c.pose[i].R, PR);
		mvod_mat3_mul_bt(PR, P, want_R);
		for (int k = 0; k < 3; k++)
			assert_float_equal(r.pose[i].t[k], want_t[k], FILE_TOL);
		for (int k = 0; k < 9; k++)
			assert_float_equal(r.pose[i].R[k], want_R[k], FILE_TOL);
	}
	const struct mvod_pose *end = &r.pose[FRAMES - 1];
	double yaw = atan2(end->R[3], end->R[0]) * 180 / M_PI;
	/* The turn is 90 degrees: measured 90.07 (0.06 degrees a frame of rotation error). */
	assert_true(yaw > 85 && yaw < 95);
	/*
	 * Forward 1.87 m, then left 1.87 m at the camera's constant height: measured (1.886,
	 * 1.891, -0.005) m with --scale gt.
	 */
	assert_true(end->t[0] > 1.5 && end->t[1] > 1.5 && fabs(end->t[2]) < 0.05);
	mvod_traj_free(&c);
	mvod_traj_free(&r);
}

/*
 * With the extrinsic: the body turns as the camera does (a level mount), and the camera is
 * where the lever arm puts it: camera position = body position + R_body * lever - lever (the
 * world is the body's first frame, where the camera sat at lever). The LCM poses are the
 * trajectory's, and the evaluation against ground truth is the camera's, unchanged.
 */
static void test_extrinsic(void **state)
{
	(void)state;
	struct mvod_traj r, b;
	load(ros_traj, &r);
	load(body_traj, &b);
	for (int i = 0; i < FRAMES; i++) {
		double arm[3];
		mvod_mat3_vec(b.pose[i].R, lever, arm);
		for (int k = 0; k < 3; k++)
			assert_float_equal(b.pose[i].t[k] + arm[k] - lever[k], r.pose[i].t[k], FILE_TOL);
		for (int k = 0; k < 9; k++)
			assert_float_equal(b.pose[i].R[k], r.pose[i].R[k], FILE_TOL);
	}
	/* The turn swings the lever arm: the body's path is not the camera's. */
	assert_true(mvod_vec3_dist(b.pose[FRAMES - 1].t, r.pose[FRAMES - 1].t) > 0.3);
	static mvod_pose2_t p[FRAMES];
	assert_int_equal(harness_poses2(body_log, p, FRAMES), FRAMES);
	for (int i = 0; i < FRAMES; i++)
		for (int k = 0; k < 3; k++)
			assert_float_equal(p[i].position[k], b.pose[i].t[k], FILE_TOL);
	const char *ate_cam = strstr(cam_out, "ATE "), *ate_body = strstr(body_out, "ATE ");
	assert_non_null(ate_cam);
	assert_non_null(ate_body);
	assert_string_equal(ate_cam, ate_body);
	mvod_traj_free(&r);
	mvod_traj_free(&b);
}

/*
 * mvod.pose2_t's quality is in [0, 1], 0 on every pose that is not tracked, above 0 on the
 * tracked ones; mvod.status2_t's latency is present and positive; v1 and v2 go out alike.
 */
static void test_quality_and_latency(void **state)
{
	(void)state;
	static mvod_pose2_t p[FRAMES];
	static mvod_status2_t s[4 * FRAMES];
	assert_int_equal(harness_poses2(cam_log, p, FRAMES), FRAMES);
	assert_int_equal(harness_poses(cam_log, NULL, 0), FRAMES);
	int ns = harness_statuses2(cam_log, s, 4 * FRAMES), tracked = 0;
	assert_int_equal(harness_statuses(cam_log, NULL, 0), ns);
	for (int i = 0; i < FRAMES; i++) {
		bool moved = p[i].frame_status == MVOD_POSE_T_FRAME_MOTION ||
			     p[i].frame_status == MVOD_POSE_T_FRAME_ROTATION;
		bool is_tracked = moved && p[i].state == MVOD_POSE_T_STATE_TRACKING;
		assert_true(p[i].quality >= 0 && p[i].quality <= 1);
		if (!is_tracked)
			assert_true(p[i].quality == 0);
		else
			assert_true(p[i].quality > 0);
		tracked += is_tracked;
	}
	assert_true(tracked > FRAMES / 2);
	assert_true(ns >= 2);
	for (int i = 0; i < ns; i++)
		assert_true(s[i].latency_ms > 0);
}

/* A camera that never moves never leaves INITIALIZING: none of its frames is "tracked". */
static void test_static_camera(void **state)
{
	(void)state;
	char seq[300], vid[400], cal[400], out[16384];
	snprintf(seq, sizeof(seq), "%s/static", harness_tmpdir());
	harness_synth(seq, "static", 10, "mkv", "--size", "320x240", NULL);
	snprintf(vid, sizeof(vid), "file:%s/video.mkv", seq);
	snprintf(cal, sizeof(cal), "%s/calib.json", seq);
	char *argv[] = {(char *)harness_bin("MVOD"), "--source", vid, "--calib", cal, "--no-lcm",
			NULL};
	run_ok(argv, out, sizeof(out));
	if (!strstr(out, "10 frames") || !strstr(out, ", 0 tracked, 10 held"))
		fail_msg("%s", out);
}

/*
 * One err_avg: a free-scale run's summary and mvod bench give the same err_avg and err_max
 * for the same run (both on the estimate scaled by the ATE's Sim(3) alignment; before, the
 * summary's was on the estimate's own unit: 0.354 against bench's 0.195 on this drive).
 */
static void test_err_avg_one_definition(void **state)
{
	(void)state;
	char csv[400], out[16384], text[4096];
	snprintf(csv, sizeof(csv), "%s", harness_tmp_path("bench.csv"));
	char *run[] = {(char *)harness_bin("MVOD"), "--source", video, "--calib", calib, "--gt", gt,
		       "--no-lcm", NULL};
	char *bench[] = {(char *)harness_bin("MVOD"), "bench", "--source", video, "--calib", calib,
			 "--gt", gt, "--csv", csv, NULL};
	run_ok(run, out, sizeof(out));
	run_ok(bench, NULL, 0);
	harness_read_file(csv, text, sizeof(text));
	/* The CSV's second line; err_avg and err_max are its 9th and 10th fields. */
	const char *row = strchr(text, '\n');
	assert_non_null(row);
	char avg[16], max[16], want[64];
	assert_int_equal(sscanf(row + 1, "%*[^,],%*[^,],%*[^,],%*[^,],%*[^,],%*[^,],%*[^,],%*[^,],"
				"%15[^,],%15[^,]", avg, max), 2);
	snprintf(want, sizeof(want), "err_avg %s (max %s)", avg, max);
	if (!strstr(out, want))
		fail_msg("bench says %s, the run's summary: %s", want, out);
}

/* Each refusal: exit status and a message naming the option, the value and what to do. */
static void refused(int status, const char *want, const char *a1, const char *a2,
		    const char *a3, const char *a4)
{
	char *argv[] = {(char *)harness_bin("MVOD"), "--source", video, "--calib", calib,
			"--no-lcm", (char *)a1, (char *)a2, (char *)a3, (char *)a4, NULL};
	struct run_result r;
	assert_int_equal(harness_run(argv, &r), 0);
	if (!r.exited || r.status != status || !strstr(r.err, want))
		fail_msg("exit %d, wanted %d and \"%s\": %s", r.status, status, want, r.err);
}

static void test_refusals(void **state)
{
	(void)state;
	refused(2, "--camera-to-body 0,0,0,0,0,0,1 places a body frame, but --frame is camera: "
		   "pass --frame ros", "--camera-to-body", "0,0,0,0,0,0,1", NULL, NULL);
	/* A bad extrinsic is a usage error, found when the options are read. */
	refused(2, "--camera-to-body 1,2,3: expected 7 numbers x,y,z,qx,qy,qz,qw", "--frame",
		"ros", "--camera-to-body", "1,2,3");
	refused(2, "--camera-to-body 0,0,0,0,0,0,2: expected 7 numbers", "--frame", "ros",
		"--camera-to-body", "0,0,0,0,0,0,2");
	refused(2, "--clock realtime: file:", "--clock", "realtime", NULL, NULL);
	refused(2, "--frame", "--frame", "enu", NULL, NULL);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_ros_axes),
		cmocka_unit_test(test_extrinsic),
		cmocka_unit_test(test_quality_and_latency),
		cmocka_unit_test(test_static_camera),
		cmocka_unit_test(test_err_avg_one_definition),
		cmocka_unit_test(test_refusals),
	};
	return cmocka_run_group_tests(tests, setup, harness_teardown);
}
