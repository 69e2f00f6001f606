/*
 * The pipelined input end to end (issue 13): the real binary on a video file and on an image
 * folder, each longer than the capture queue, writes one pose per frame, every frame once and
 * in order: the trajectory's times are the source's, line for line. A bad frame of the folder
 * is skipped in its place. (unit/pipelined checks pixels and KITTI on the capture thread.)
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

/* Three times the capture queue's depth (4): the capture thread has to wait for room. */
#define FRAMES 12
#define BAD 5

/* The first column of each line of path (times), up to max; returns how many. */
static int first_column(const char *path, double *t, int max)
{
	FILE *f = fopen(path, "r");
	assert_non_null(f);
	int n = 0;
	char line[512];
	while (n < max && fgets(line, sizeof(line), f))
		t[n++] = strtod(line, NULL);
	fclose(f);
	return n;
}

/* mvod on source; the trajectory's times must be times.txt's, without frame skip (-1: none). */
static void run_and_check(const char *seq, const char *source, int skip)
{
	char calib[300], traj[300], times_path[300];
	snprintf(calib, sizeof(calib), "%s/calib.json", seq);
	snprintf(traj, sizeof(traj), "%s/out.tum", seq);
	snprintf(times_path, sizeof(times_path), "%s/times.txt", seq);
	char *argv[] = {(char *)harness_bin("MVOD"), "--no-lcm", "--source", (char *)source,
			"--calib", calib, "--trajectory", traj, NULL};
	struct run_result r;
	assert_int_equal(harness_run(argv, &r), 0);
	if (!r.exited || r.status != 0)
		fail_msg("mvod on %s: %d: %s", source, r.status, r.err);
	double want[FRAMES], got[FRAMES + 1];
	assert_int_equal(first_column(times_path, want, FRAMES), FRAMES);
	int n = first_column(traj, got, FRAMES + 1);
	assert_int_equal(n, skip < 0 ? FRAMES : FRAMES - 1);
	for (int i = 0, k = 0; i < FRAMES; i++) {
		if (i == skip)
			continue;
		/* TUM times are written with 6 decimals: the same microsecond, or an error. */
		assert_float_equal(got[k], want[i], 1e-6);
		k++;
	}
}

static void test_file_every_frame_in_order(void **state)
{
	(void)state;
	char seq[256], source[300];
	snprintf(seq, sizeof(seq), "%s/video", harness_tmpdir());
	harness_synth(seq, "forward", FRAMES, "mkv", "--size", "160x120", NULL);
	snprintf(source, sizeof(source), "file:%s/video.mkv", seq);
	run_and_check(seq, source, -1);
}

static void test_images_every_frame_in_order(void **state)
{
	(void)state;
	char seq[256], source[300], path[320];
	snprintf(seq, sizeof(seq), "%s/png", harness_tmpdir());
	harness_synth(seq, "forward", FRAMES, "png", "--size", "160x120", NULL);
	snprintf(path, sizeof(path), "%s/images/%06d.png", seq, BAD);
	harness_write_file(path, "not a PNG");
	/* mvod-synth writes times.txt beside images/ too: that one is the folder's own. */
	snprintf(source, sizeof(source), "images:%s/images", seq);
	run_and_check(seq, source, BAD);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_file_every_frame_in_order),
		cmocka_unit_test(test_images_every_frame_in_order),
	};
	return cmocka_run_group_tests(tests, NULL, harness_teardown);
}
