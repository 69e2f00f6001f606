/*
 * mvod calibrate on a folder that holds two cameras' photos (issue 18): mvod-synth renders
 * chessboard views through two different lenses (fx = fy = 576 and 640 px), named a_* and
 * b_* as two cameras' files would be. The verdict is "not one camera", in the JSON too, naming the parameter that differs;
 * one camera's photos alone are not. A folder with frames of two sizes gets the same verdict.
 * And calibration says nothing about a missing times.txt, which it does not use.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "harness.h"

#define BOARD "chessboard:9x6:0.025"

static char both[300], only_a[300];

/* Renders `views` chessboard views with extra camera options into tmp/name/images/. */
static void render(const char *name, const char *views, char *extra1, char *extra2)
{
	char dir[300];
	snprintf(dir, sizeof(dir), "%s/%s", harness_tmpdir(), name);
	char *argv[] = {(char *)harness_bin("MVOD_SYNTH"), "--out", dir, "--board", BOARD,
			"--views", (char *)views, "--format", "png", "--noise", "1",
			extra1, extra2, NULL};
	struct run_result r;
	assert_int_equal(harness_run(argv, &r), 0);
	if (!r.exited || r.status != 0)
		fail_msg("mvod-synth %s: %s", name, r.err);
}

/* Copies the PNGs of tmp/FROM/images into dir, each name prefixed "PREFIX_" (no times.txt). */
static void gather(const char *dir, const char *from, const char *prefix)
{
	char cmd[1024];
	snprintf(cmd, sizeof(cmd), "mkdir -p %s && cd %s/%s/images && for f in *.png; do "
		 "cp \"$f\" %s/%s_\"$f\"; done", dir, harness_tmpdir(), from, dir, prefix);
	assert_int_equal(system(cmd), 0);
}

static int setup(void **state)
{
	(void)state;
	render("cam_a", "12", NULL, NULL);
	render("cam_b", "12", "--fx", "640");
	snprintf(both, sizeof(both), "%s/both", harness_tmpdir());
	snprintf(only_a, sizeof(only_a), "%s/only_a", harness_tmpdir());
	gather(both, "cam_a", "a");
	gather(both, "cam_b", "b");
	gather(only_a, "cam_a", "a");
	return 0;
}

/* mvod calibrate on DIR; its stdout and stderr in r, the JSON's text in json. */
static void calibrate(const char *dir, struct run_result *r, char *json, size_t len)
{
	char src[320], out[320];
	snprintf(src, sizeof(src), "images:%s", dir);
	snprintf(out, sizeof(out), "%s.json", dir);
	char *argv[] = {(char *)harness_bin("MVOD"), "calibrate", "--source", src, "--board", BOARD,
			"--out", out, NULL};
	assert_int_equal(harness_run(argv, r), 0);
	if (!r->exited || r->status != 0)
		fail_msg("calibrate %s: %d %s%s", dir, r->status, r->out, r->err);
	harness_read_file(out, json, len);
	/* Calibration does not use frame times: no word about times.txt. */
	assert_null(strstr(r->err, "times.txt"));
}

static void test_two_cameras(void **state)
{
	(void)state;
	struct run_result r;
	static char json[1 << 16];
	calibrate(both, &r, json, sizeof(json));
	if (!strstr(r.out, "verdict: not one camera. These frames cannot all come from one camera"))
		fail_msg("no \"not one camera\" verdict: %s", r.out);
	/*
	 * 576 against 640 px: the halves (a_*, then b_*) name a focal length, fx or fy, whichever
	 * is more deviations apart. (The blend of the two fits at an RMS of 0.12 px.)
	 */
	const char *f = strstr(r.out, "give f");
	if (!f || !strstr(f, " 576.") || !strstr(f, "against 6"))
		fail_msg("the focal lengths are not named: %s", r.out);
	assert_non_null(strstr(json, "\"verdict\":\t\"not one camera\""));
}

static void test_one_camera(void **state)
{
	(void)state;
	struct run_result r;
	static char json[1 << 16];
	calibrate(only_a, &r, json, sizeof(json));
	assert_null(strstr(r.out, "not one camera"));
	assert_non_null(strstr(r.out, "verdict: "));
}

static void test_two_sizes(void **state)
{
	(void)state;
	render("cam_c", "4", "--size", "800x600");
	char dir[300];
	snprintf(dir, sizeof(dir), "%s/sizes", harness_tmpdir());
	gather(dir, "cam_a", "a");
	gather(dir, "cam_c", "c");
	struct run_result r;
	static char json[1 << 16];
	calibrate(dir, &r, json, sizeof(json));
	if (!strstr(r.out, "not one camera") ||
	    !strstr(r.out, "4 frames of another size than 640x480 were skipped"))
		fail_msg("no verdict on the sizes: %s", r.out);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_two_cameras),
		cmocka_unit_test(test_one_camera),
		cmocka_unit_test(test_two_sizes),
	};
	return cmocka_run_group_tests(tests, setup, harness_teardown);
}
