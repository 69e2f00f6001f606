/*
 * The live path without a camera, through the real binary: a file played with ?realtime=1 at
 * 1000 fps outruns the VO, so frames are dropped, and the status messages in a file:// LCM log
 * account for every one, as do the frame numbers of the poses. Bad camera URIs each fail with one clear line; --list-cameras on a
 * machine without cameras says so and succeeds.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "harness.h"
#include "mvod_pose_t.h"
#include "mvod_status_t.h"

#define FRAMES 200

static char dir[256];

static int setup(void **state)
{
	(void)state;
	snprintf(dir, sizeof(dir), "%s/seq", harness_tmpdir());
	harness_synth(dir, "forward", FRAMES, "mkv", "--fps", "1000", NULL);
	return 0;
}

static void test_realtime_drops_are_reported(void **state)
{
	(void)state;
	char source[320], calib[300], url[400], log[300];
	snprintf(source, sizeof(source), "file:%s/video.mkv?realtime=1", dir);
	snprintf(calib, sizeof(calib), "%s/calib.json", dir);
	snprintf(log, sizeof(log), "%s/live.lcmlog", harness_tmpdir());
	snprintf(url, sizeof(url), "file://%s?mode=w", log);
	char *argv[] = {(char *)harness_bin("MVOD"), "--source", source, "--calib", calib,
			"--lcm-url", url, NULL};
	struct run_result r;
	assert_int_equal(harness_run(argv, &r), 0);
	if (!r.exited || r.status)
		fail_msg("mvod failed: %s", r.err);
	mvod_status_t all[FRAMES + 16];
	int n = harness_statuses(log, all, FRAMES + 16);
	assert_true(n >= 2 && n <= FRAMES + 16);
	mvod_status_t last = all[n - 1];
	assert_int_equal(last.state, 5); /* STATE_STOPPING: the closing status */
	/* Every frame of the clip was either processed or counted as dropped, exactly. */
	assert_int_equal(last.frames + last.dropped_frames, FRAMES);
	/*
	 * And the drops are exactly the frame numbers the poses skip. How many frames a machine
	 * drops depends on its speed (about 30 ms a frame at 640x480 against 1 ms between frames
	 * here), so the count itself is not asserted.
	 */
	static mvod_pose_t poses[FRAMES];
	int np = harness_poses(log, poses, FRAMES);
	assert_int_equal(np, last.frames);
	int64_t skipped = poses[0].frame;
	for (int i = 1; i < np; i++)
		skipped += poses[i].frame - poses[i - 1].frame - 1;
	assert_int_equal(skipped, last.dropped_frames);
	char want[64];
	snprintf(want, sizeof(want), ", %lld dropped\n", (long long)last.dropped_frames);
	if (!strstr(r.out, want))
		fail_msg("summary does not say \"%s\": %s", want, r.out);
}

/* Exit 1 and one line on stderr naming the problem. */
static void expect_failure(const char *source, const char *needle)
{
	char *argv[] = {(char *)harness_bin("MVOD"), "--no-lcm", "--source", (char *)source, NULL};
	struct run_result r;
	assert_int_equal(harness_run(argv, &r), 0);
	if (!r.exited || r.status != 1 || !strstr(r.err, needle))
		fail_msg("%s: expected exit 1 and \"%s\", got %d: %s", source, needle, r.status, r.err);
	const char *nl = strchr(r.err, '\n');
	assert_non_null(nl);
	assert_int_equal(nl[1], '\0');
}

static void test_bad_camera_uris(void **state)
{
	(void)state;
	expect_failure("v4l2:/dev/nonexistent", "no such device /dev/nonexistent");
	expect_failure("v4l2:/dev/null", "/dev/null is not a V4L2 device");
	expect_failure("v4l2:/dev/video0?format=BGR3", "format=BGR3: expected one of GREY, YUYV");
	expect_failure("v4l2:/dev/video0?width=abc", "width=abc: expected an integer");
	expect_failure("v4l2:/dev/video0?focus=1", "unknown source parameter \"focus\"");
	expect_failure("file:/nonexistent.mkv?realtime=2", "realtime=2: expected an integer in [0, 1]");
}

/* Index 63 is past any real machine's cameras: a clear message whether or not it has libcamera. */
static void test_libcamera_without_camera(void **state)
{
	(void)state;
	char *argv[] = {(char *)harness_bin("MVOD"), "--no-lcm", "--source", "libcamera:63", NULL};
	struct run_result r;
	assert_int_equal(harness_run(argv, &r), 0);
	assert_true(r.exited);
	assert_int_equal(r.status, 1);
	if (!strstr(r.err, "no libcamera camera 63") && !strstr(r.err, "built without libcamera"))
		fail_msg("unclear: %s", r.err);
	/* libcamera's own log lines are kept out unless --log-level debug. */
	assert_null(strstr(r.err, " INFO "));
}

static void test_list_cameras(void **state)
{
	(void)state;
	char *argv[] = {(char *)harness_bin("MVOD"), "--list-cameras", NULL};
	struct run_result r;
	assert_int_equal(harness_run(argv, &r), 0);
	assert_true(r.exited);
	assert_int_equal(r.status, 0);
	/* Either the cameras with a URI each, or a plain "none" (this build machine has none). */
	assert_true(strstr(r.out, "--source '") || strstr(r.out, "No cameras found"));
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_realtime_drops_are_reported),
		cmocka_unit_test(test_bad_camera_uris),
		cmocka_unit_test(test_libcamera_without_camera),
		cmocka_unit_test(test_list_cameras),
	};
	return cmocka_run_group_tests(tests, setup, harness_teardown);
}
