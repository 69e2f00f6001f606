/* Trajectory writers and readers (both formats round-trip), and the bounded plot path. */
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

#include "mvod/traj.h"

static const char *dir;

static int setup(void **state)
{
	(void)state;
	dir = harness_tmpdir();
	return 0;
}

static void make_pose(int i, struct mvod_pose *p)
{
	double w[3] = {0.01 * i, -0.3 + 0.02 * i, 0.005 * i * i};
	mvod_rot_exp(w, p->R);
	p->t[0] = 0.5 * i;
	p->t[1] = -0.01 * i;
	p->t[2] = 1.25 * i + 0.125;
}

static void round_trip(enum mvod_traj_format fmt, double tol)
{
	char path[128];
	snprintf(path, sizeof(path), "%s/traj.%s", dir, mvod_traj_format_name(fmt));
	struct mvod_traj_writer *w;
	assert_int_equal(mvod_traj_writer_open(path, fmt, &w, NULL, 0), 0);
	for (int i = 0; i < 50; i++) {
		struct mvod_pose p;
		make_pose(i, &p);
		assert_int_equal(mvod_traj_writer_add(w, 1000.0 + 0.1 * i, &p), 0);
	}
	assert_int_equal(mvod_traj_writer_close(w), 0);
	struct mvod_traj tr;
	char err[256];
	assert_int_equal(mvod_traj_load(path, &tr, err, sizeof(err)), 0);
	assert_int_equal(tr.n, 50);
	assert_int_equal(tr.format, fmt);
	for (int i = 0; i < 50; i++) {
		struct mvod_pose p;
		make_pose(i, &p);
		for (int k = 0; k < 9; k++)
			assert_true(fabs(tr.pose[i].R[k] - p.R[k]) < tol);
		for (int k = 0; k < 3; k++)
			assert_true(fabs(tr.pose[i].t[k] - p.t[k]) < tol * 10);
		if (fmt == MVOD_TRAJ_TUM)
			assert_true(fabs(tr.t[i] - (1000.0 + 0.1 * i)) < 1e-6);
	}
	mvod_traj_free(&tr);
}

static void test_tum_round_trip(void **state)
{
	(void)state;
	/* %.9g quaternions: rotation entries to ~1e-8. */
	round_trip(MVOD_TRAJ_TUM, 1e-7);
}

static void test_kitti_round_trip(void **state)
{
	(void)state;
	round_trip(MVOD_TRAJ_KITTI, 1e-8);
}

/* Loading a file of this text fails with -EINVAL and a message holding both needles. */
static void expect_load_error(const char *text, const char *needle1, const char *needle2)
{
	char path[128], err[256] = "";
	struct mvod_traj tr;
	snprintf(path, sizeof(path), "%s/bad.txt", dir);
	FILE *f = fopen(path, "w");
	assert_non_null(f);
	fputs(text, f);
	fclose(f);
	assert_int_equal(mvod_traj_load(path, &tr, err, sizeof(err)), -EINVAL);
	if (!strstr(err, needle1) || !strstr(err, needle2))
		fail_msg("expected '%s' and '%s' in: %s", needle1, needle2, err);
}

static void test_load_errors(void **state)
{
	(void)state;
	/* The line, what the first line made it expect, and what it found instead. */
	expect_load_error("1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0\n",
			  "bad.txt:2: expected 12 numbers (KITTI", "found 8");
	expect_load_error("0.1 0 0 0 0 0 0 1\n0.2 0 0 0 0 0 one 1\n",
			  "bad.txt:2: expected 8 numbers (TUM", "found text");
	expect_load_error("0.1 0 0 0 0 0 0 1\n0.2 0 0 nan 0 0 0 1\n", "bad.txt:2",
			  "found nan or inf");
	expect_load_error("# only a comment\n\n", "bad.txt", "no poses");
	/*
	 * Numbers that are no pose: a KITTI rotation all zero (accepted, then nan everywhere), one
	 * mirrored (det -1), one 2 % off orthonormal; a position of 1e308; a zero quaternion.
	 */
	expect_load_error("1 0 0 0 0 1 0 0 0 0 1 0\n0 0 0 1 0 0 0 2 0 0 0 3\n", "bad.txt:2: rotation "
			  "[0 0 0; 0 0 0; 0 0 0] is no rotation: R^T R is 1 off the identity",
			  "(KITTI: a row-major 3x4 pose)");
	expect_load_error("-1 0 0 0 0 1 0 0 0 0 1 0\n", "bad.txt:1: rotation", "det R = -1");
	expect_load_error("1.01 0 0 0 0 1 0 0 0 0 1 0\n", "bad.txt:1: rotation",
			  "R^T R is 0.0201 off the identity (within 0.01)");
	expect_load_error("0.1 0 0 0 0 0 0 1\n0.2 1e308 0 0 0 0 0 1\n", "bad.txt:2: position "
			  "(1e+308 0 0) m is that far", "(TUM: t tx ty tz qx qy qz qw)");
	expect_load_error("0.1 0 0 0 0 0 0 0\n", "bad.txt:1: quaternion (qx qy qz qw) = (0 0 0 0) "
			  "has length 0", "not 1 (within 0.01)");
	struct mvod_traj tr;
	char err[256];
	assert_int_equal(mvod_traj_load("/nonexistent/x", &tr, err, sizeof(err)), -ENOENT);
}

/* A pose with negative zeros (a rotation about -x by 0, a translation of -0) prints no "-0". */
static void test_no_negative_zero(void **state)
{
	(void)state;
	for (int f = 0; f < 2; f++) {
		char path[128];
		snprintf(path, sizeof(path), "%s/zero.%d", dir, f);
		struct mvod_traj_writer *w;
		assert_int_equal(mvod_traj_writer_open(path, (enum mvod_traj_format)f, &w, NULL, 0), 0);
		struct mvod_pose p = {.R = {1, -0.0, -0.0, -0.0, 1, -0.0, -0.0, -0.0, 1},
				      .t = {-0.0, -0.0, -0.0}};
		assert_int_equal(mvod_traj_writer_add(w, 0, &p), 0);
		assert_int_equal(mvod_traj_writer_close(w), 0);
		char line[512] = "";
		FILE *in = fopen(path, "r");
		assert_non_null(in);
		assert_non_null(fgets(line, sizeof(line), in));
		fclose(in);
		if (strstr(line, "-0"))
			fail_msg("format %d wrote a negative zero: %s", f, line);
	}
}

/*
 * TUM lines checked against the format's definition, not against mvod's own reader: "timestamp
 * tx ty tz qx qy qz qw", the unit quaternion (Hamilton, scalar last) of the camera-to-world
 * rotation. A quarter turn about z maps x to y: (0, 0, sin 45, cos 45); about y, z to x:
 * (0, sin 45, 0, cos 45); about x, y to z: (sin 45, 0, 0, cos 45). The matrices are written
 * out by hand (row-major), so that no conversion of mvod's stands between them and the text.
 */
static const struct {
	double R[9];
	const char *line;
} tum_golden[] = {
	{{0, -1, 0, 1, 0, 0, 0, 0, 1}, "12.500000 1 -2 3.25 0 0 0.707106781 0.707106781\n"},
	{{0, 0, 1, 0, 1, 0, -1, 0, 0}, "12.500000 1 -2 3.25 0 0.707106781 0 0.707106781\n"},
	{{1, 0, 0, 0, 0, -1, 0, 1, 0}, "12.500000 1 -2 3.25 0.707106781 0 0 0.707106781\n"},
};

static void test_tum_golden_lines(void **state)
{
	(void)state;
	char path[128], text[256];
	snprintf(path, sizeof(path), "%s/golden.tum", dir);
	for (size_t i = 0; i < sizeof(tum_golden) / sizeof(tum_golden[0]); i++) {
		struct mvod_traj_writer *w;
		assert_int_equal(mvod_traj_writer_open(path, MVOD_TRAJ_TUM, &w, NULL, 0), 0);
		struct mvod_pose p = {.t = {1, -2, 3.25}};
		memcpy(p.R, tum_golden[i].R, sizeof(p.R));
		assert_int_equal(mvod_traj_writer_add(w, 12.5, &p), 0);
		assert_int_equal(mvod_traj_writer_close(w), 0);
		harness_read_file(path, text, sizeof(text));
		assert_string_equal(text, tum_golden[i].line);
	}
	/* Read: a hand-written line (7 digits, as other tools write) gives back the matrix. */
	for (size_t i = 0; i < sizeof(tum_golden) / sizeof(tum_golden[0]); i++) {
		harness_write_file(path, tum_golden[i].line);
		struct mvod_traj tr;
		char err[256];
		assert_int_equal(mvod_traj_load(path, &tr, err, sizeof(err)), 0);
		assert_int_equal(tr.n, 1);
		assert_true(tr.t[0] == 12.5);
		for (int k = 0; k < 9; k++)
			assert_true(fabs(tr.pose[0].R[k] - tum_golden[i].R[k]) < 1e-8);
		mvod_traj_free(&tr);
	}
}

/*
 * SIGHUP reopens the trajectory by name. After a rotation (rename) that is a new file; when
 * nothing moved the file it is the same one, and its lines must stay: reopening appends.
 */
static void test_reopen_appends(void **state)
{
	(void)state;
	char path[128], moved[140];
	snprintf(path, sizeof(path), "%s/reopen.tum", dir);
	snprintf(moved, sizeof(moved), "%s.1", path);
	struct mvod_traj_writer *w;
	struct mvod_pose p;
	make_pose(1, &p);
	assert_int_equal(mvod_traj_writer_open(path, MVOD_TRAJ_TUM, &w, NULL, 0), 0);
	for (int i = 0; i < 2; i++)
		assert_int_equal(mvod_traj_writer_add(w, i, &p), 0);
	assert_int_equal(mvod_traj_writer_reopen(w, NULL, 0), 0);
	assert_int_equal(mvod_traj_writer_add(w, 2, &p), 0);
	assert_int_equal(harness_count_lines(path), 3);
	assert_int_equal(rename(path, moved), 0);
	/* Whatever is at the name when SIGHUP comes (here a line another program wrote) stays. */
	FILE *f = fopen(path, "w");
	assert_non_null(f);
	fputs("# rotated\n", f);
	fclose(f);
	assert_int_equal(mvod_traj_writer_reopen(w, NULL, 0), 0);
	assert_int_equal(mvod_traj_writer_add(w, 3, &p), 0);
	assert_int_equal(mvod_traj_writer_close(w), 0);
	assert_int_equal(harness_count_lines(moved), 3);
	assert_int_equal(harness_count_lines(path), 2);
}

static void test_writer_reports_full_disk(void **state)
{
	(void)state;
	if (access("/dev/full", W_OK) != 0)
		skip();
	struct mvod_traj_writer *w;
	assert_int_equal(mvod_traj_writer_open("/dev/full", MVOD_TRAJ_TUM, &w, NULL, 0), 0);
	struct mvod_pose p;
	make_pose(1, &p);
	assert_int_equal(mvod_traj_writer_add(w, 0, &p), -ENOSPC);
	assert_int_equal(mvod_traj_writer_close(w), -ENOSPC);
}

static void test_path_decimates_in_fixed_memory(void **state)
{
	(void)state;
	struct mvod_path p;
	assert_int_equal(mvod_path_init(&p, 100), 0);
	double *buf = p.xyz;
	for (int i = 0; i < 100000; i++) {
		double x[3] = {i, 0, 0};
		mvod_path_add(&p, x);
		assert_true(p.n <= 100);
	}
	assert_ptr_equal(p.xyz, buf);
	/* Kept points are evenly spaced samples starting at the first. */
	assert_true(p.n >= 50);
	for (int i = 0; i < p.n; i++)
		assert_true(p.xyz[3 * i] == (double)(i * p.stride));
	mvod_path_fini(&p);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_tum_round_trip),
		cmocka_unit_test(test_kitti_round_trip),
		cmocka_unit_test(test_load_errors),
		cmocka_unit_test(test_no_negative_zero),
		cmocka_unit_test(test_tum_golden_lines),
		cmocka_unit_test(test_reopen_appends),
		cmocka_unit_test(test_writer_reports_full_disk),
		cmocka_unit_test(test_path_decimates_in_fixed_memory),
	};
	return cmocka_run_group_tests(tests, setup, harness_teardown);
}
