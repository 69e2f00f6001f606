/*
 * Outlier views dropped end to end: mvod calibrate on 24 mvod-synth chessboard views of one
 * lens, three of which (frames 5, 12 and 19) are swapped for the same views through another,
 * strongly distorted lens. Those three cannot fit the intrinsics the others share, so their
 * per-view error stands far above the outlier bound (median + 3 sigma); calibrate must drop
 * exactly them, say so, calibrate again without them, and leave them out of the file's views.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>
#include <cmocka.h>

#include "harness.h"

#include "mvod/calib.h"
#include "util/read_file.h"

#define BOARD "chessboard:9x6:0.025"
#define VIEWS 24

static const int spoilt[] = {5, 12, 19};

static void render(const char *dir, const char *distortion)
{
	char *argv[] = {(char *)harness_bin("MVOD_SYNTH"), "--out", (char *)dir, "--board", BOARD,
			"--views", "24", "--format", "png", "--fx", "500", "--fy", "505", "--noise",
			"1", "--distortion", (char *)distortion, NULL};
	struct run_result r;
	assert_int_equal(harness_run(argv, &r), 0);
	if (!r.exited || r.status != 0)
		fail_msg("mvod-synth failed (%d): %s", r.status, r.err);
}

/* The "frame" of every view in calibration file path, into frames; how many. */
static int used_frames(const char *path, int *frames, int max)
{
	char err[256], *text;
	assert_int_equal(mvod_read_file(path, 1 << 22, "calibration", 0, &text, NULL, err, sizeof(err)),
			 0);
	cJSON *root = cJSON_Parse(text);
	free(text);
	assert_non_null(root);
	const cJSON *v;
	int n = 0;
	cJSON_ArrayForEach(v, cJSON_GetObjectItemCaseSensitive(root, "views")) {
		const cJSON *frame = cJSON_GetObjectItemCaseSensitive(v, "frame");
		assert_true(cJSON_IsNumber(frame) && n < max);
		frames[n++] = frame->valueint;
	}
	cJSON_Delete(root);
	return n;
}

static void test_distorted_views_dropped(void **state)
{
	(void)state;
	char good[300], bad[300], cmd[1024], src[320], out[320];
	snprintf(good, sizeof(good), "%s/good", harness_tmpdir());
	snprintf(bad, sizeof(bad), "%s/bad", harness_tmpdir());
	/* A mild lens for the sequence; k1 = -0.35 for the three strangers (same seed: same poses). */
	render(good, "-0.05,0.01,0,0");
	render(bad, "-0.35,0.12,0,0");
	for (size_t i = 0; i < sizeof(spoilt) / sizeof(spoilt[0]); i++) {
		snprintf(cmd, sizeof(cmd), "cp '%s/images/%06d.png' '%s/images/'", bad, spoilt[i], good);
		assert_int_equal(system(cmd), 0);
	}
	snprintf(src, sizeof(src), "images:%s/images", good);
	snprintf(out, sizeof(out), "%s/est.json", good);
	char *argv[] = {(char *)harness_bin("MVOD"), "calibrate", "--source", src, "--board", BOARD,
			"--out", out, "--max-views", "80", NULL};
	struct run_result r;
	assert_int_equal(harness_run(argv, &r), 0);
	if (!r.exited || r.status != 0)
		fail_msg("mvod calibrate failed (%d): %s", r.status, r.err);
	if (!strstr(r.err, "dropped 3 of "))
		fail_msg("expected 'dropped 3 of N views': %s", r.err);
	int frames[VIEWS];
	int n = used_frames(out, frames, VIEWS);
	assert_true(n >= 10);
	for (int i = 0; i < n; i++)
		for (size_t k = 0; k < sizeof(spoilt) / sizeof(spoilt[0]); k++)
			if (frames[i] == spoilt[k])
				fail_msg("view of frame %d, through the other lens, was kept", spoilt[k]);
	/* Without them the refit is the good lens's: fx within 0.5 % as in test_synth_calib. */
	struct mvod_camera est;
	char err[256];
	assert_int_equal(mvod_calib_load(out, &est, err, sizeof(err)), 0);
	print_message("%d views kept: fx %.3f fy %.3f k1 %.4f\n", n, est.fx, est.fy, est.dist[0]);
	assert_true(fabs(est.fx - 500) / 500 < 0.005 && fabs(est.fy - 505) / 505 < 0.005);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_distorted_views_dropped),
	};
	return cmocka_run_group_tests(tests, NULL, harness_teardown);
}
