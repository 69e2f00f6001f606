/*
 * mvod-synth --board: the files a calibration test relies on, checked against an independent
 * projection in C (pinhole radial-tangential and fisheye Kannala-Brandt, from OpenCV's
 * documented equations), and the same seed giving the same bytes.
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

#include "mvod/board.h"
#include "mvod/calib.h"

#define VIEWS 8

/*
 * corners.txt prints 9 decimals (5e-10 px rounding); OpenCV's projectPoints and the C below
 * evaluate the same polynomials in a different order. Measured worst: 7.0e-10 px. 1e-6 px
 * leaves room for platform libm differences, while any wrong convention (a half-pixel shift,
 * swapped axes, a missing distortion term) is far above 1e-3 px.
 */
#define PROJ_TOL_PX 1e-6

static void rodrigues(const double r[3], double R[9])
{
	double th = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
	double k[3] = {0, 0, 0};
	if (th > 0)
		for (int i = 0; i < 3; i++)
			k[i] = r[i] / th;
	double c = cos(th), s = sin(th), v = 1 - c;
	const double K[9] = {0, -k[2], k[1], k[2], 0, -k[0], -k[1], k[0], 0};
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 3; j++)
			R[3 * i + j] = (i == j ? c : 0) + v * k[i] * k[j] + s * K[3 * i + j];
}

static void project(const struct mvod_camera *cam, const double R[9], const double t[3],
		    const double X[3], double *u, double *v)
{
	double p[3];
	for (int i = 0; i < 3; i++)
		p[i] = R[3 * i] * X[0] + R[3 * i + 1] * X[1] + R[3 * i + 2] * X[2] + t[i];
	double x = p[0] / p[2], y = p[1] / p[2], xd, yd;
	const double *k = cam->dist;
	if (cam->model == MVOD_CAM_FISHEYE_KB4) {
		double r = sqrt(x * x + y * y), th = atan(r), th2 = th * th;
		double thd = th * (1 + th2 * (k[0] + th2 * (k[1] + th2 * (k[2] + th2 * k[3]))));
		double s = r > 0 ? thd / r : 1;
		xd = x * s;
		yd = y * s;
	} else {
		double r2 = x * x + y * y, k3 = cam->n_dist > 4 ? k[4] : 0;
		double radial = cam->n_dist ? 1 + r2 * (k[0] + r2 * (k[1] + r2 * k3)) : 1;
		double p1 = cam->n_dist ? k[2] : 0, p2 = cam->n_dist ? k[3] : 0;
		xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x);
		yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y;
	}
	*u = cam->fx * xd + cam->cx;
	*v = cam->fy * yd + cam->cy;
}

static void render(const char *dir, const char *board, const char *lens_opt, const char *lens)
{
	char views[8];
	snprintf(views, sizeof(views), "%d", VIEWS);
	char *argv[] = {(char *)harness_bin("MVOD_SYNTH"), "--out", (char *)dir, "--board", (char *)board,
			"--views", views, "--format", "png", "--fx", "500", "--fy", "505", "--cx", "322.5",
			"--cy", "236.25", "--seed", "3", (char *)lens_opt, (char *)lens, NULL};
	struct run_result r;
	assert_int_equal(harness_run(argv, &r), 0);
	if (!r.exited || r.status != 0)
		fail_msg("mvod-synth --board %s failed (%d): %s", board, r.status, r.err);
}

/* Reads board_poses.txt into rvec/tvec per view. */
static void read_poses(const char *dir, double pose[VIEWS][6])
{
	size_t len;
	char *text = harness_slurp(dir, "board_poses.txt", &len);
	int n = 0;
	for (char *line = strtok(text, "\n"); line; line = strtok(NULL, "\n")) {
		if (line[0] == '#')
			continue;
		int view;
		double *p = pose[n < VIEWS ? n : 0];
		assert_int_equal(sscanf(line, "%d %lf %lf %lf %lf %lf %lf", &view, p, p + 1, p + 2, p + 3,
					p + 4, p + 5), 7);
		assert_int_equal(view, n);
		n++;
	}
	assert_int_equal(n, VIEWS);
	free(text);
}

/* Every corner of every view, once, in the image, where the poses and calib.json put it. */
static void check_corners(const char *dir, const struct mvod_board *b, const struct mvod_camera *cam)
{
	double pose[VIEWS][6];
	read_poses(dir, pose);
	size_t len;
	char *text = harness_slurp(dir, "corners.txt", &len);
	int n = 0, count = mvod_board_corner_count(b);
	double worst = 0;
	for (char *line = strtok(text, "\n"); line; line = strtok(NULL, "\n")) {
		if (line[0] == '#')
			continue;
		int view, id;
		double u, v, R[9], X[3], pu, pv;
		assert_int_equal(sscanf(line, "%d %d %lf %lf", &view, &id, &u, &v), 4);
		assert_int_equal(view, n / count);
		assert_int_equal(id, n % count);
		assert_true(u >= 0 && v >= 0 && u <= cam->width - 1 && v <= cam->height - 1);
		rodrigues(pose[view], R);
		mvod_board_corner(b, id, X);
		project(cam, R, pose[view] + 3, X, &pu, &pv);
		worst = fmax(worst, hypot(pu - u, pv - v));
		n++;
	}
	free(text);
	assert_int_equal(n, VIEWS * count);
	print_message("%s: %d corners, worst disagreement with the C projection %.2e px\n", dir, n, worst);
	assert_true(worst < PROJ_TOL_PX);
}

static void check_set(const char *name, const char *spec, const char *lens_opt, const char *lens,
		      enum mvod_cam_model model, int n_dist)
{
	char dir[300], again[300], err[512];
	snprintf(dir, sizeof(dir), "%s/%s", harness_tmpdir(), name);
	snprintf(again, sizeof(again), "%s/%s-again", harness_tmpdir(), name);
	render(dir, spec, lens_opt, lens);

	struct mvod_board b;
	assert_int_equal(mvod_board_parse(spec, &b, err, sizeof(err)), 0);
	struct mvod_camera cam;
	char calib[400];
	snprintf(calib, sizeof(calib), "%s/calib.json", dir);
	if (mvod_calib_load(calib, &cam, err, sizeof(err)))
		fail_msg("%s", err);
	assert_true(cam.fx == 500 && cam.fy == 505 && cam.cx == 322.5 && cam.cy == 236.25);
	assert_int_equal(cam.width, 640);
	assert_int_equal(cam.model, model);
	assert_int_equal(cam.n_dist, n_dist);
	check_corners(dir, &b, &cam);

	/* Same arguments and seed: the same bytes, images included. */
	render(again, spec, lens_opt, lens);
	static const char *const files[] = {"board_poses.txt", "corners.txt", "gt.tum",
					    "images/000000.png", "images/000007.png"};
	for (size_t i = 0; i < sizeof(files) / sizeof(files[0]); i++) {
		size_t n1, n2;
		char *a = harness_slurp(dir, files[i], &n1), *c = harness_slurp(again, files[i], &n2);
		if (n1 != n2 || memcmp(a, c, n1) != 0)
			fail_msg("%s differs between two runs with the same seed", files[i]);
		free(a);
		free(c);
	}
}

static void test_chessboard_radtan(void **state)
{
	(void)state;
	check_set("chess", "chessboard:9x6:0.025", "--distortion", "-0.2,0.05,0.001,-0.001,0.01",
		  MVOD_CAM_PINHOLE_RADTAN, 5);
}

static void test_charuco_fisheye(void **state)
{
	(void)state;
	check_set("charuco", "charuco:5x7:0.04:0.02:DICT_6X6_250", "--fisheye", "0.1,-0.02,0.01,-0.002",
		  MVOD_CAM_FISHEYE_KB4, 4);
}

/* A street option with --board is a usage error, not silently ignored. */
static void test_board_usage(void **state)
{
	(void)state;
	char *argv[] = {(char *)harness_bin("MVOD_SYNTH"), "--out", (char *)harness_tmpdir(), "--board",
			"chessboard:9x6:0.025", "--path", "turn", NULL};
	struct run_result r;
	assert_int_equal(harness_run(argv, &r), 0);
	assert_true(r.exited && r.status == 2);
	assert_non_null(strstr(r.err, "--board"));
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_chessboard_radtan),
		cmocka_unit_test(test_charuco_fisheye),
		cmocka_unit_test(test_board_usage),
	};
	return cmocka_run_group_tests(tests, NULL, harness_teardown);
}
