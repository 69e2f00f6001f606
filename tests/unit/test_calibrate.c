/*
 * The decisions of mvod calibrate on their own: which views are taken, which are dropped as
 * outliers, what the verdict says, and what the calibration file records.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>

#include "mvod/calibrate.h"

#define ALL_CELLS ((1ull << (MVOD_CALIB_CELLS_X * MVOD_CALIB_CELLS_Y)) - 1)

static const double no_tilt[3] = {0, 0, 0};

/* A view covering the one cell (cx, cy), at tilt bin `tilt`. */
static struct mvod_calib_view_info cell_view(int cx, int cy, int tilt)
{
	return (struct mvod_calib_view_info){
		.cells = 1ull << (cy * MVOD_CALIB_CELLS_X + cx), .tilt_bin = tilt, .corners = 54,
		.cx = (cx + 0.5f) / MVOD_CALIB_CELLS_X, .cy = (cy + 0.5f) / MVOD_CALIB_CELLS_Y,
		.extent = 0.1f};
}

static void cells_follow_the_board(void **state)
{
	(void)state;
	/* A board spanning the whole 640 x 480 image covers every cell through its hull. */
	const float full[8] = {1, 1, 639, 1, 639, 479, 1, 479};
	assert_true(mvod_calib_cells(full, 4, 640, 480) == ALL_CELLS);
	/* One corner at (100, 100) is in cell (1, 1) of the 80 x 80 px cells. */
	const float one[2] = {100, 100};
	assert_true(mvod_calib_cells(one, 1, 640, 480) == 1ull << (1 * MVOD_CALIB_CELLS_X + 1));
	/* The left half: columns 0..3 of every row. */
	const float left[8] = {0, 0, 319, 0, 319, 479, 0, 479};
	uint64_t row = 0xF, want = 0;
	for (int y = 0; y < MVOD_CALIB_CELLS_Y; y++)
		want |= row << (y * MVOD_CALIB_CELLS_X);
	assert_true(mvod_calib_cells(left, 4, 640, 480) == want);
}

static void tilt_bins_split_orientations(void **state)
{
	(void)state;
	/* Frontal: bin (4, 4) of the 8 x 8 15-degree bins; 28.6 deg about y: one bin to the right. */
	int frontal = mvod_calib_tilt_bin(no_tilt);
	assert_int_equal(frontal, 4 * 8 + 4);
	assert_int_equal(mvod_calib_tilt_bin((double[3]){0, 0.5, 0}), frontal + 1);
	assert_int_equal(mvod_calib_tilt_bin((double[3]){-0.5, 0, 0}), frontal + 8);
	/* Turning the board in its own plane does not tilt it. */
	assert_int_equal(mvod_calib_tilt_bin((double[3]){0, 0, 2.0}), frontal);
}

static void selection_spreads_over_the_image(void **state)
{
	(void)state;
	/* 50 frames of a board held still in the centre, then one in each of the 4 corner cells. */
	struct mvod_calib_view_info v[54];
	for (int i = 0; i < 50; i++)
		v[i] = cell_view(3, 2, 36);
	v[50] = cell_view(0, 0, 36);
	v[51] = cell_view(7, 0, 36);
	v[52] = cell_view(0, 5, 36);
	v[53] = cell_view(7, 5, 36);
	int picked[10];
	int n = mvod_calib_select(v, 54, 10, picked);
	/* The still board is one view, whatever its frame count: 4 corners + 1. */
	assert_int_equal(n, 5);
	int corners = 0;
	for (int i = 0; i < n; i++)
		corners += picked[i] >= 50;
	assert_int_equal(corners, 4);
}

static void selection_prefers_new_tilts(void **state)
{
	(void)state;
	/* Three views of one cell: two at the same tilt, the last at another. */
	struct mvod_calib_view_info v[3] = {cell_view(2, 2, 36), cell_view(2, 2, 36), cell_view(2, 2, 45)};
	v[1].cx += 0.1f; /* not a duplicate, just a similar view */
	int picked[2];
	assert_int_equal(mvod_calib_select(v, 3, 2, picked), 2);
	assert_int_equal(picked[0], 0);
	assert_int_equal(picked[1], 2);
}

static void selection_skips_near_duplicates(void **state)
{
	(void)state;
	/* Consecutive video frames: the board drifts by 0.4 % of the image per frame. */
	struct mvod_calib_view_info v[6];
	for (int i = 0; i < 6; i++) {
		v[i] = cell_view(3, 2, 36);
		v[i].cx += 0.004f * (float)i;
	}
	int picked[6];
	/* Frames 1..4 are within 2 % of frame 0; frame 5, 2.5 % away, is a view of its own. */
	v[5].cx = v[0].cx + 0.025f;
	assert_int_equal(mvod_calib_select(v, 6, 6, picked), 2);
	assert_int_equal(picked[0], 0);
	assert_int_equal(picked[1], 5);
}

static void outlier_bound(void **state)
{
	(void)state;
	/* Median 0.2, MAD 0.01: 0.2 + 3 * 1.4826 * 0.01 = 0.2445 < 2 x median = 0.4. */
	const double typical[] = {0.19, 0.2, 0.21, 0.2, 0.19, 0.21, 0.2, 1.5};
	assert_true(fabs(mvod_calib_outlier_px(typical, 8) - 0.4) < 1e-12);
	/* A spread-out set: median 1.0, MAD 0.5: 1 + 3 * 1.4826 * 0.5 = 3.2239 above 2 x median. */
	const double spread[] = {0.5, 0.5, 1.0, 1.5, 1.5};
	assert_true(fabs(mvod_calib_outlier_px(spread, 5) - (1.0 + 3 * 1.4826 * 0.5)) < 1e-12);
	/* The input is not reordered. */
	assert_true(typical[7] == 1.5 && spread[0] == 0.5);
}

static void tilt_span(void **state)
{
	(void)state;
	double pose[12] = {0};
	pose[6] = 30 * M_PI / 180; /* second board turned 30 deg about x */
	assert_true(fabs(mvod_calib_tilt_span_deg(pose, 2) - 30) < 1e-9);
	/* An in-plane turn leaves the normal where it was. */
	pose[6] = 0;
	pose[8] = 1.0;
	assert_true(mvod_calib_tilt_span_deg(pose, 2) < 1e-9);
}

static void verdicts(void **state)
{
	(void)state;
	char a[640];
	assert_int_equal(mvod_calib_judge(60, 0.3, 0.8, 50, a, sizeof(a)), MVOD_VERDICT_GOOD);
	assert_int_equal(mvod_calib_judge(60, 1.6, 0.8, 50, a, sizeof(a)), MVOD_VERDICT_HIGH_ERROR);
	assert_non_null(strstr(a, "1.60 px"));
	assert_int_equal(mvod_calib_judge(8, 0.3, 0.8, 50, a, sizeof(a)), MVOD_VERDICT_FEW_VIEWS);
	assert_non_null(strstr(a, "Only 8 views"));
	assert_int_equal(mvod_calib_judge(60, 0.3, 0.35, 50, a, sizeof(a)), MVOD_VERDICT_POOR_COVERAGE);
	assert_non_null(strstr(a, "cover 35 % of the image"));
	assert_int_equal(mvod_calib_judge(60, 0.3, 0.8, 12, a, sizeof(a)), MVOD_VERDICT_POOR_COVERAGE);
	assert_non_null(strstr(a, "span only 12 deg"));
	/* Every problem is named, the worst first. */
	assert_int_equal(mvod_calib_judge(5, 2.0, 0.2, 5, a, sizeof(a)), MVOD_VERDICT_HIGH_ERROR);
	assert_non_null(strstr(a, "Only 5 views"));
	assert_non_null(strstr(a, "Tilt the board more"));
}

/*
 * Two halves of the views are two cameras only when an intrinsic differs by more than 5
 * combined deviations and 1 % of the width (6.4 px at 640): OpenCV's left and right photos
 * give cx 342.0 and 330.2 +- 0.7 px.
 */
static void two_cameras(void **state)
{
	(void)state;
	char why[160] = "";
	struct mvod_calib_k4 left = {{536, 536, 342.0, 235.5}, {0.5, 0.5, 0.7, 0.7}};
	struct mvod_calib_k4 right = {{537, 537, 330.2, 241.0}, {0.5, 0.5, 0.7, 0.7}};
	assert_true(mvod_calib_differ(&left, &right, 640, why, sizeof(why)));
	assert_string_equal(why, "cx 342.0 +- 0.7 px against 330.2 +- 0.7 px");
	/* The same 11.8 px with deviations of 3 px: 2.8 sigma, chance. */
	for (int i = 0; i < 4; i++)
		left.std[i] = right.std[i] = 3;
	why[0] = '\0';
	assert_false(mvod_calib_differ(&left, &right, 640, why, sizeof(why)));
	assert_string_equal(why, "");
	/* 40 sigma but 4 px, under 1 % of the width: deviations too small to trust. */
	struct mvod_calib_k4 a = {{500, 500, 320, 240}, {0.1, 0.1, 0.1, 0.1}}, b = a;
	b.k[0] = 504;
	assert_false(mvod_calib_differ(&a, &b, 640, why, sizeof(why)));
	/* The parameter furthest out is named. */
	b.k[0] = 520;
	b.k[3] = 250;
	assert_true(mvod_calib_differ(&a, &b, 640, why, sizeof(why)));
	assert_non_null(strstr(why, "fx 500.0"));
	assert_int_equal(strcmp(mvod_calib_verdict_name(MVOD_VERDICT_MIXED), "not one camera"), 0);
}

static void file_records_the_calibration(void **state)
{
	(void)state;
	struct mvod_camera c = {.width = 640, .height = 480, .fx = 500, .fy = 501, .cx = 320,
				.cy = 240, .n_dist = 5, .dist = {-0.1, 0.01, 0, 0, 0},
				.has_focus = true, .focus = 120};
	const double rms[2] = {0.11, 0.13}, pose[12] = {0.1, 0.2, 0.3, 0.01, 0.02, 0.5};
	const int64_t frame[2] = {7, 1234567};
	struct mvod_calib_meta meta = {.rms_px = 0.12, .board = "chessboard:9x6:0.025", .source = "t",
				       .n_views = 2, .view_rms_px = rms, .view_pose = pose,
				       .view_frame = frame,
				       .has_std = true, .std_K = {1, 2, 3, 4}, .verdict = "good"};
	char path[] = "/tmp/mvod-test-calibrate-XXXXXX";
	int fd = mkstemp(path);
	assert_true(fd >= 0);
	close(fd);
	assert_int_equal(mvod_calib_save(path, &c, &meta), 0);
	struct mvod_camera r;
	char err[256];
	assert_int_equal(mvod_calib_load(path, &r, err, sizeof(err)), 0);
	assert_true(r.fx == 500 && r.n_dist == 5);
	assert_true(r.has_focus && r.focus == 120);
	char text[4096] = "";
	FILE *f = fopen(path, "r");
	assert_non_null(f);
	size_t n = fread(text, 1, sizeof(text) - 1, f);
	text[n] = '\0';
	fclose(f);
	unlink(path);
	static const char *const keys[] = {"\"views_used\":\t2", "\"frame\":\t7", "\"frame\":\t1234567",
					   "\"rvec\"", "\"tvec\"", "\"std_dev\"",
					   "\"focus\":\t120", "\"verdict\":\t\"good\"", "\"created\""};
	for (size_t i = 0; i < sizeof(keys) / sizeof(keys[0]); i++)
		if (!strstr(text, keys[i]))
			fail_msg("%s missing from:\n%s", keys[i], text);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(cells_follow_the_board),
		cmocka_unit_test(tilt_bins_split_orientations),
		cmocka_unit_test(selection_spreads_over_the_image),
		cmocka_unit_test(selection_prefers_new_tilts),
		cmocka_unit_test(selection_skips_near_duplicates),
		cmocka_unit_test(outlier_bound),
		cmocka_unit_test(tilt_span),
		cmocka_unit_test(verdicts),
		cmocka_unit_test(two_cameras),
		cmocka_unit_test(file_records_the_calibration),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
