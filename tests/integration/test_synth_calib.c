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

#include <cjson/cJSON.h>
#include <cmocka.h>

#include "harness.h"

#include "camera/calib_internal.h"
#include "mvod/board.h"
#include "mvod/calib.h"
#include "mvod/geom.h"
#include "util/read_file.h"

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

/*
 * Each view's "frame" is the synth view it came from: the board centre the calibration places
 * in the camera for it is that view's true one. The centre, because a chessboard's corners may
 * come back numbered from the opposite end (the same pattern turned 180 degrees about its
 * centre), which moves the pose's origin but not the centre. Measured: 0.2-0.6 mm at 0.3-0.7 m;
 * the centres of consecutive rendered views are 8.9 cm or more apart (150-view renders), so a
 * bound of 1 cm catches a frame index off by one.
 */
#define VIEW_CENTRE_BOUND_M 0.01

/* The board centre in the camera frame of pose r, t (board to camera). */
static void board_centre(const struct mvod_board *b, const double rvec[3], const double tvec[3],
			 double out[3])
{
	int across, down;
	mvod_board_squares(b, &across, &down);
	double c[3] = {across * b->square_m / 2, down * b->square_m / 2, 0}, R[9];
	mvod_rot_exp(rvec, R);
	mvod_mat3_vec(R, c, out);
	for (int k = 0; k < 3; k++)
		out[k] += tvec[k];
}

static int read_poses(const char *dir, double (*pose)[6], int max)
{
	char path[300];
	snprintf(path, sizeof(path), "%s/board_poses.txt", dir);
	FILE *f = fopen(path, "r");
	assert_non_null(f);
	int n = 0, view;
	assert_int_equal(fscanf(f, "#%*[^\n]"), 0); /* the header line */
	while (n < max && fscanf(f, "%d %lf %lf %lf %lf %lf %lf", &view, &pose[n][0], &pose[n][1],
				 &pose[n][2], &pose[n][3], &pose[n][4], &pose[n][5]) == 7)
		assert_int_equal(view, n++);
	fclose(f);
	return n;
}

static void views_name_their_frames(const char *dir, const char *spec, const char *out)
{
	double truth[512][6];
	int n_truth = read_poses(dir, truth, 512);
	struct mvod_board b;
	char err[256], *text;
	assert_int_equal(mvod_board_parse(spec, &b, err, sizeof(err)), 0);
	assert_int_equal(mvod_read_file(out, 1 << 22, "calibration", 0, &text, NULL, err, sizeof(err)), 0);
	cJSON *root = cJSON_Parse(text);
	free(text);
	const cJSON *views = cJSON_GetObjectItemCaseSensitive(root, "views"), *v;
	double worst = 0;
	assert_true(cJSON_GetArraySize(views) > 0);
	cJSON_ArrayForEach(v, views) {
		const cJSON *frame = cJSON_GetObjectItemCaseSensitive(v, "frame");
		assert_true(cJSON_IsNumber(frame) && frame->valueint >= 0 && frame->valueint < n_truth);
		double rv[3], tv[3], est[3], tru[3];
		for (int k = 0; k < 3; k++) {
			rv[k] = cJSON_GetArrayItem(cJSON_GetObjectItemCaseSensitive(v, "rvec"), k)->valuedouble;
			tv[k] = cJSON_GetArrayItem(cJSON_GetObjectItemCaseSensitive(v, "tvec"), k)->valuedouble;
		}
		board_centre(&b, rv, tv, est);
		board_centre(&b, truth[frame->valueint], truth[frame->valueint] + 3, tru);
		worst = fmax(worst, mvod_vec3_dist(est, tru));
	}
	cJSON_Delete(root);
	print_message("views' frames: worst board centre error %.4f m\n", worst);
	assert_true(worst < VIEW_CENTRE_BOUND_M);
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
	views_name_their_frames(dir, c->board, out);
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
	assert_true(file_has(log, "calibrate: stopped after") && file_has(log, "using them"));
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
