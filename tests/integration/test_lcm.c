/*
 * LCM output: over memq:// (in-process, so the pipeline runs in this process) a subscriber
 * gets exactly one mvod.pose_t per frame, in order, stamped with the source clock; and a
 * file:// log written by the real binary reads back with one pose event per frame.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>
#include <lcm/lcm.h>

#include "harness.h"
#include "mvod/pipeline.h"
#include "mvod_pose_t.h"
#include "mvod_status_t.h"

#define FRAMES 30
#define FPS 10

static char dir[256];

struct received {
	int poses, statuses;
	int64_t frame[FRAMES + 1];
	int64_t utime[FRAMES + 1];
	int bad_quat;
};

static void on_pose(const lcm_recv_buf_t *rbuf, const char *ch, const mvod_pose_t *msg, void *user)
{
	(void)rbuf;
	(void)ch;
	struct received *r = user;
	if (r->poses <= FRAMES) {
		r->frame[r->poses] = msg->frame;
		r->utime[r->poses] = msg->utime;
	}
	const double *q = msg->orientation;
	r->bad_quat += fabs(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3] - 1) > 1e-9;
	r->poses++;
}

static void on_status(const lcm_recv_buf_t *rbuf, const char *ch, const mvod_status_t *msg,
		      void *user)
{
	(void)rbuf;
	(void)ch;
	(void)msg;
	((struct received *)user)->statuses++;
}

static int setup(void **state)
{
	(void)state;
	snprintf(dir, sizeof(dir), "%s/seq", harness_tmpdir());
	harness_synth(dir, "forward", FRAMES, "mkv", NULL);
	return 0;
}

static void test_memq_one_pose_per_frame(void **state)
{
	(void)state;
	lcm_t *lcm = lcm_create("memq://");
	assert_non_null(lcm);
	struct received got = {0};
	mvod_pose_t_subscription_t *ps = mvod_pose_t_subscribe(lcm, "TEST_POSE", on_pose, &got);
	mvod_status_t_subscription_t *ss =
		mvod_status_t_subscribe(lcm, "TEST_STATUS", on_status, &got);
	struct mvod_ipc *ipc;
	assert_int_equal(mvod_ipc_create_on(lcm, "TEST_POSE", "TEST_STATUS", &ipc), 0);

	char video[300], calib[300];
	snprintf(video, sizeof(video), "file:%s/video.mkv", dir);
	snprintf(calib, sizeof(calib), "%s/calib.json", dir);
	struct mvod_run_opts o;
	mvod_run_opts_default(&o);
	o.source = video;
	o.calib = calib;
	struct mvod_run_summary sum;
	assert_int_equal(mvod_run(&o, ipc, NULL, &sum), 0);
	assert_int_equal(sum.frames, FRAMES);
	while (lcm_handle_timeout(lcm, 0) > 0)
		;
	assert_int_equal(got.poses, FRAMES);
	assert_true(got.statuses >= 1);
	assert_int_equal(got.bad_quat, 0);
	for (int i = 0; i < FRAMES; i++) {
		assert_int_equal(got.frame[i], i);
		/* The media clock of a 10 fps video: frame i at i * 100 ms. */
		assert_true(llabs(got.utime[i] - (int64_t)i * 1000000 / FPS) <= 1000);
	}
	mvod_ipc_destroy(ipc);
	mvod_pose_t_unsubscribe(lcm, ps);
	mvod_status_t_unsubscribe(lcm, ss);
	lcm_destroy(lcm);
}

static void test_file_log_from_binary(void **state)
{
	(void)state;
	char video[300], calib[300], url[400], log[300];
	snprintf(video, sizeof(video), "file:%s/video.mkv", dir);
	snprintf(calib, sizeof(calib), "%s/calib.json", dir);
	snprintf(log, sizeof(log), "%s/mvod.lcmlog", harness_tmpdir());
	snprintf(url, sizeof(url), "file://%s?mode=w", log);
	char *argv[] = {(char *)harness_bin("MVOD"), "--source", video, "--calib", calib, "--lcm-url",
			url, NULL};
	struct run_result r;
	assert_int_equal(harness_run(argv, &r), 0);
	if (!r.exited || r.status)
		fail_msg("mvod failed: %s", r.err);
	struct log_contents c;
	harness_read_log(log, &c, NULL, NULL);
	/* Every message decodes, and the poses are frames 0, 1, 2, ... without a gap. */
	assert_int_equal(c.bad, 0);
	assert_int_equal(c.gaps, 0);
	assert_int_equal(c.poses, FRAMES);
	assert_int_equal(c.last_frame, FRAMES - 1);
	assert_true(c.statuses >= 1);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_memq_one_pose_per_frame),
		cmocka_unit_test(test_file_log_from_binary),
	};
	return cmocka_run_group_tests(tests, setup, harness_teardown);
}
