/*
 * Accuracy summaries that cannot mislead (issue 10): a static ground truth under a moving
 * estimate, a zero quaternion, a ground truth that covers part of the run.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>

#include "harness.h"

#define FRAMES 12

static char seq[256], video[300], calib[300];

static int setup(void **state)
{
	(void)state;
	snprintf(seq, sizeof(seq), "%s/seq", harness_tmpdir());
	harness_synth(seq, "forward", FRAMES, "mkv", "--size", "320x240", NULL);
	snprintf(video, sizeof(video), "file:%s/video.mkv", seq);
	snprintf(calib, sizeof(calib), "%s/calib.json", seq);
	return 0;
}

static void run_with_gt(const char *gt, struct run_result *r)
{
	char *argv[] = {(char *)harness_bin("MVOD"), "--no-lcm", "--source", video, "--calib",
			calib, "--gt", (char *)gt, NULL};
	assert_int_equal(harness_run(argv, r), 0);
	if (!r->exited)
		fail_msg("killed by signal %d: %s", r->status, r->err);
}

/* The first n lines of the sequence's ground truth file name (gt.kitti or gt.tum) into out. */
static void gt_lines(const char *name, int n, const char *out)
{
	char cmd[1024];
	snprintf(cmd, sizeof(cmd), "head -n %d '%s/%s' > '%s'", n, seq, name, out);
	assert_int_equal(system(cmd), 0);
}

/* A KITTI ground truth that stands still at the origin, one pose per frame. */
static const char *static_gt(void)
{
	static char gt[300];
	char text[FRAMES * 32 + 1] = "";
	snprintf(gt, sizeof(gt), "%s/static.kitti", harness_tmpdir());
	for (int i = 0; i < FRAMES; i++)
		strcat(text, "1 0 0 0 0 1 0 0 0 0 1 0\n");
	harness_write_file(gt, text);
	return gt;
}

/*
 * The camera drives forward; the ground truth says it stood still. A Sim(3) alignment would
 * shrink the estimate to the ground truth's one point and report ATE 0.000 m: the summary
 * says instead that the ground truth does not move and how far the estimate went.
 */
static void test_static_gt(void **state)
{
	(void)state;
	const char *gt = static_gt();
	struct run_result r;
	run_with_gt(gt, &r);
	if (r.status != 0 || strstr(r.out, "ATE 0") ||
	    !strstr(r.out, "the ground truth does not move, but the estimate went"))
		fail_msg("exit %d: %s%s", r.status, r.out, r.err);
	/* It did go somewhere: tracking a forward drive, not 0. */
	const char *went = strstr(r.out, "estimate went ");
	assert_true(strtod(went + strlen("estimate went "), NULL) > 0);
}

/*
 * mvod bench on the same: no ATE cell made up by the alignment (it would read 0.000 m), but
 * "-", and a warning saying how far the estimate went.
 */
static void test_static_gt_bench(void **state)
{
	(void)state;
	const char *gt = static_gt();
	char *argv[] = {(char *)harness_bin("MVOD"), "bench", "--source", video, "--calib", calib,
			"--gt", (char *)gt, NULL};
	struct run_result r;
	assert_int_equal(harness_run(argv, &r), 0);
	if (!r.exited || r.status != 0 || strstr(r.out, "0.000 m") ||
	    !strstr(r.err, "the ground truth does not move, but the estimate went") ||
	    !strstr(r.err, "ATE and the KITTI errors are undefined"))
		fail_msg("exit %d: %s%s", r.status, r.out, r.err);
}

/* A zero quaternion is refused at load with its line, before any NaN can reach a summary. */
static void test_zero_quaternion(void **state)
{
	(void)state;
	char gt[300];
	snprintf(gt, sizeof(gt), "%s/zero.tum", harness_tmpdir());
	harness_write_file(gt, "0.0 0 0 0 0 0 0 1\n0.1 0 0 0.1 0 0 0 0\n");
	struct run_result r;
	run_with_gt(gt, &r);
	if (r.status != 2 || !strstr(r.err, "zero.tum:2: quaternion (qx qy qz qw) = (0 0 0 0) has "
					    "length 0, not 1") || strstr(r.out, "nan"))
		fail_msg("exit %d: %s%s", r.status, r.out, r.err);
}

/* Half the run has ground truth: the summary says which frames, and measures those. */
static void test_partial_gt(void **state)
{
	(void)state;
	char gt[300];
	snprintf(gt, sizeof(gt), "%s/half.kitti", harness_tmpdir());
	gt_lines("gt.kitti", FRAMES / 2, gt);
	struct run_result r;
	run_with_gt(gt, &r);
	if (r.status != 0 || !strstr(r.out, "ground truth covers frames 0-5 of 12 (6 have a pose)") ||
	    !strstr(r.out, "ATE ") || strstr(r.out, "nan"))
		fail_msg("exit %d: %s%s", r.status, r.out, r.err);
}

/* The whole ground truth: no coverage line (it would be noise), an ATE. */
static void test_full_gt(void **state)
{
	(void)state;
	char gt[300];
	snprintf(gt, sizeof(gt), "%s/gt.kitti", seq);
	struct run_result r;
	run_with_gt(gt, &r);
	if (r.status != 0 || strstr(r.out, "covers") || !strstr(r.out, "ATE "))
		fail_msg("exit %d: %s%s", r.status, r.out, r.err);
}

/* A folder given as the ground truth is not "an empty file". */
static void test_gt_is_a_folder(void **state)
{
	(void)state;
	struct run_result r;
	run_with_gt(seq, &r);
	if (r.status != 2 || !strstr(r.err, "seq is a directory") || strstr(r.err, "no poses"))
		fail_msg("exit %d: %s%s", r.status, r.out, r.err);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_static_gt),
		cmocka_unit_test(test_static_gt_bench),
		cmocka_unit_test(test_zero_quaternion),
		cmocka_unit_test(test_partial_gt),
		cmocka_unit_test(test_full_gt),
		cmocka_unit_test(test_gt_is_a_folder),
	};
	return cmocka_run_group_tests(tests, setup, harness_teardown);
}
