/*
 * mvod calibrate on mvod-synth renders of ChArUco and chessboard views with exact intrinsics
 * and lens distortion, as PNG sequences and as a video.
 *
 * Bounds: the renders' corners are exact to 1e-9 px and OpenCV finds them within 0.05 px
 * (median, chessboard and ChArUco after mvod's re-refinement), so with 20-40 views the focal
 * lengths and principal point come out within 0.1 % (measured: 0.001-0.13 %, cx and cy the worst). The issue asks
 * for 0.5 %; that is the bound, four times the worst measured and still tight enough that the
 * old +0.5 px ChArUco corner bias or a wrong board layout fails it (fx 503.6, RMS 2 px). The
 * RMS bound, 0.15 px, is three times the 0.045-0.06 px measured with noise of 1 grey level.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <cmocka.h>

#include "harness.h"

#include "mvod/calib.h"

#define RMS_BOUND_PX 0.15
#define INTRINSICS_BOUND 0.005

struct calib_case {
	const char *name, *board, *format, *views;
	const char *lens[2]; /* mvod-synth lens option and its value, or NULLs */
	const char *model;   /* mvod calibrate --model */
	const char *max_views;
	int inverted;
};

static struct run_result r;

static void render(const char *dir, const struct calib_case *c)
{
	char *argv[32] = {(char *)harness_bin("MVOD_SYNTH"), "--out", (char *)dir, "--board",
			  (char *)c->board, "--views", (char *)c->views, "--format", (char *)c->format,
			  "--fx", "500", "--fy", "505", "--cx", "325", "--cy", "235", "--noise", "1"};
	int n = 19;
	if (c->lens[0]) {
		argv[n++] = (char *)c->lens[0];
		argv[n++] = (char *)c->lens[1];
	}
	if (c->inverted)
		argv[n++] = "--inverted";
	argv[n] = NULL;
	assert_int_equal(harness_run(argv, &r), 0);
	if (!r.exited || r.status != 0)
		fail_msg("mvod-synth %s failed (%d): %s", c->name, r.status, r.err);
}

static double rel(double est, double truth)
{
	return fabs(est - truth) / truth;
}

/* Reads "NAME VALUE" from the calibrate summary, e.g. "RMS reprojection error 0.05 px". */
static double summary_number(const char *after)
{
	const char *p = strstr(r.out, after);
	if (!p)
		fail_msg("no '%s' in the output:\n%s", after, r.out);
	return strtod(p + strlen(after), NULL);
}

static void calibrate(const struct calib_case *c)
{
	char dir[256], source[300], out[300], truth_path[300];
	snprintf(dir, sizeof(dir), "%s/%s", harness_tmpdir(), c->name);
	render(dir, c);
	if (strcmp(c->format, "png") == 0)
		snprintf(source, sizeof(source), "images:%s/images", dir);
	else
		snprintf(source, sizeof(source), "file:%s/video.mkv", dir);
	snprintf(out, sizeof(out), "%s/est.json", dir);
	snprintf(truth_path, sizeof(truth_path), "%s/calib.json", dir);
	char *argv[] = {(char *)harness_bin("MVOD"), "calibrate", "--source", source, "--board",
			(char *)c->board, "--model", (char *)c->model, "--out", out, "--max-views",
			(char *)(c->max_views ? c->max_views : "80"), NULL};
	assert_int_equal(harness_run(argv, &r), 0);
	if (!r.exited || r.status != 0)
		fail_msg("mvod calibrate %s failed (%d): %s", c->name, r.status, r.err);

	struct mvod_camera est, truth;
	char err[256];
	assert_int_equal(mvod_calib_load(out, &est, err, sizeof(err)), 0);
	assert_int_equal(mvod_calib_load(truth_path, &truth, err, sizeof(err)), 0);
	double rms = summary_number("RMS reprojection error ");
	print_message("%s: fx %.3f fy %.3f cx %.3f cy %.3f (true %.0f %.0f %.0f %.0f), RMS %.3f px\n",
		      c->name, est.fx, est.fy, est.cx, est.cy, truth.fx, truth.fy, truth.cx, truth.cy,
		      rms);
	assert_int_equal(est.model, truth.model);
	assert_int_equal(est.width, truth.width);
	assert_true(rel(est.fx, truth.fx) < INTRINSICS_BOUND);
	assert_true(rel(est.fy, truth.fy) < INTRINSICS_BOUND);
	assert_true(rel(est.cx, truth.cx) < INTRINSICS_BOUND);
	assert_true(rel(est.cy, truth.cy) < INTRINSICS_BOUND);
	assert_true(rms < RMS_BOUND_PX);
	assert_non_null(strstr(r.out, "verdict: good"));
}

static void charuco_radtan_png(void **state)
{
	(void)state;
	calibrate(&(struct calib_case){"charuco-radtan", "charuco:5x7:0.04:0.02:DICT_6X6_250", "png",
				       "40", {"--distortion", "-0.25,0.08,0.001,-0.0005"}, "pinhole",
				       NULL, 0});
}

/* A video: the FFV1 decode path, and a chessboard. */
static void chessboard_radtan_video(void **state)
{
	(void)state;
	calibrate(&(struct calib_case){"chess-video", "chessboard:9x6:0.025", "mkv", "30",
				       {"--distortion", "-0.2,0.05,0.001,-0.001"}, "pinhole", NULL, 0});
}

/* fx 500 on 640 px is a narrow lens for the fisheye model: OpenCV's own start fails on it. */
static void charuco_fisheye(void **state)
{
	(void)state;
	calibrate(&(struct calib_case){"charuco-fisheye", "charuco:5x7:0.04:0.02:DICT_6X6_250", "png",
				       "30", {"--fisheye", "0.05,-0.02,0.01,-0.005"}, "fisheye", NULL, 0});
}

static void charuco_inverted(void **state)
{
	(void)state;
	calibrate(&(struct calib_case){"charuco-inverted", "charuco:5x7:0.04:0.02:DICT_6X6_250",
				       "png", "20", {NULL, NULL}, "pinhole", NULL, 1});
}

/*
 * 60 views, 20 kept: the selection must still cover the image and the tilts (the renders put
 * the board over a 3x3 grid of positions with tilts up to 50 deg about both axes).
 */
static void selection_spreads(void **state)
{
	(void)state;
	calibrate(&(struct calib_case){"select", "chessboard:9x6:0.025", "png", "60", {NULL, NULL},
				       "pinhole", "20", 0});
	assert_non_null(strstr(r.out, "20 views selected"));
	double coverage = summary_number("covering ");
	double span = summary_number("tilts spanning ");
	print_message("20 of 60 views cover %.0f %% of the image, tilts spanning %.0f deg\n", coverage,
		      span);
	/* Measured 100 % and 88 deg. */
	assert_true(coverage >= 70);
	assert_true(span >= 60);
}

static int file_has(const char *path, const char *needle)
{
	char buf[16384];
	harness_read_file(path, buf, sizeof(buf));
	return strstr(buf, needle) != NULL;
}

/*
 * A live camera never ends: Ctrl-C ends the recording and mvod calibrates on the frames read.
 * A 10 s video played in real time stands in for the camera; the interrupt comes once the
 * first progress line (after 5 s) shows frames were read.
 */
static void interrupt_calibrates_what_was_read(void **state)
{
	(void)state;
	const struct calib_case c = {"live", "charuco:5x7:0.04:0.02:DICT_6X6_250", "mkv", "100",
				     {NULL, NULL}, "pinhole", NULL, 0};
	char dir[256], source[300], out[300], log[300];
	snprintf(dir, sizeof(dir), "%s/%s", harness_tmpdir(), c.name);
	render(dir, &c);
	snprintf(source, sizeof(source), "file:%s/video.mkv?realtime=1", dir);
	snprintf(out, sizeof(out), "%s/est.json", dir);
	snprintf(log, sizeof(log), "%s/log.txt", dir);
	pid_t pid = fork();
	assert_true(pid >= 0);
	if (pid == 0) {
		int fd = open(log, O_WRONLY | O_CREAT | O_TRUNC, 0644);
		dup2(fd, 1);
		dup2(fd, 2);
		execl(harness_bin("MVOD"), "mvod", "calibrate", "--source", source, "--board", c.board,
		      "--out", out, (char *)NULL);
		_exit(127);
	}
	int st;
	while (!file_has(log, "with the board so far")) {
		if (waitpid(pid, &st, WNOHANG) == pid)
			fail_msg("mvod calibrate ended before the interrupt (status %d)", st);
		usleep(10000);
	}
	kill(pid, SIGINT);
	waitpid(pid, &st, 0);
	assert_true(WIFEXITED(st));
	assert_int_equal(WEXITSTATUS(st), 0);
	assert_true(file_has(log, "calibrating on them"));
	assert_true(file_has(log, "wrote"));
	assert_false(file_has(log, "100 frames read"));
	struct mvod_camera est;
	char err[256];
	assert_int_equal(mvod_calib_load(out, &est, err, sizeof(err)), 0);
	assert_true(rel(est.fx, 500) < INTRINSICS_BOUND);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(charuco_radtan_png),
		cmocka_unit_test(chessboard_radtan_video),
		cmocka_unit_test(charuco_fisheye),
		cmocka_unit_test(charuco_inverted),
		cmocka_unit_test(selection_spreads),
		cmocka_unit_test(interrupt_calibrates_what_was_read),
	};
	return cmocka_run_group_tests(tests, NULL, harness_teardown);
}
