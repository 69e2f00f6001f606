/*
 * mvod calibrate on a folder that holds two cameras' photos (issue 18): mvod-synth renders
 * chessboard views through two different lenses (fx = fy = 576 and 640 px), named a_* and
 * b_* as two cameras' files would be. The verdict is "not one camera", naming the parameter
 * that differs, and the file is not written (exit 1) unless --force asks for the blend, whose
 * JSON records the verdict; one camera's photos alone are not, but their 12 views are too few
 * (exit 1, as --help says; it exited 0). A folder with frames of two sizes gets the verdict
 * "not one camera" too. And calibration says nothing about a missing times.txt, which it does
 * not use.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

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

/*
 * mvod calibrate on DIR (--force when force), expected to exit with code; its stdout and
 * stderr in r, the JSON's text in json, or "" when it wrote none.
 */
static void calibrate(const char *dir, bool force, int code, struct run_result *r, char *json,
		      size_t len)
{
	char src[320], out[320];
	snprintf(src, sizeof(src), "images:%s", dir);
	snprintf(out, sizeof(out), "%s.json", dir);
	unlink(out);
	char *argv[] = {(char *)harness_bin("MVOD"), "calibrate", "--source", src, "--board", BOARD,
			"--out", out, force ? "--force" : NULL, NULL};
	assert_int_equal(harness_run(argv, r), 0);
	if (!r->exited || r->status != code)
		fail_msg("calibrate %s: exit %d, not %d: %s%s", dir, r->status, code, r->out, r->err);
	json[0] = '\0';
	if (access(out, F_OK) == 0)
		harness_read_file(out, json, len);
	/* Calibration does not use frame times: no word about times.txt. */
	assert_null(strstr(r->err, "times.txt"));
}

static void test_two_cameras(void **state)
{
	(void)state;
	struct run_result r;
	static char json[1 << 16];
	/* A blend of two cameras is no file to run on: not written, exit 1, --force named. */
	calibrate(both, false, 1, &r, json, sizeof(json));
	assert_string_equal(json, "");
	if (!strstr(r.err, "both.json not written: the views are not one camera") ||
	    !strstr(r.err, "--force"))
		fail_msg("the refusal does not say why or how: %s", r.err);
	calibrate(both, true, 0, &r, json, sizeof(json));
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
	/* 12 views: the verdict "too few views" (under 15) is written, and exits 1. */
	calibrate(only_a, false, 1, &r, json, sizeof(json));
	assert_null(strstr(r.out, "not one camera"));
	assert_non_null(strstr(r.out, "verdict: too few views. Only 12 views were usable"));
	assert_non_null(strstr(json, "\"verdict\":\t\"too few views\""));
	if (!strstr(r.err, "only_a.json: too few views to trust it (exit status 1)"))
		fail_msg("the exit status is not explained: %s", r.err);
	/* --force accepts it: written, exit 0. */
	calibrate(only_a, true, 0, &r, json, sizeof(json));
	assert_non_null(strstr(json, "\"verdict\":\t\"too few views\""));
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
	calibrate(dir, false, 1, &r, json, sizeof(json));
	assert_string_equal(json, "");
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
