/*
 * mvod board and mvod calibrate as a user runs them: the printed board's exact pixel size and
 * DPI, and each kind of bad input failing with its reason, the right exit code, and any
 * existing calibration file left as it was.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmocka.h>

#include "harness.h"

#define CHARUCO "charuco:5x7:0.04:0.02:DICT_6X6_250"

struct png_info {
	uint32_t w, h, ppm_x, ppm_y;
	int unit; /* pHYs unit: 1 = metre; -1 without a pHYs chunk */
};

static uint32_t be32(const unsigned char *p)
{
	return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3];
}

/* IHDR and pHYs of a PNG: both come before the image data, in the first few hundred bytes. */
static void read_png_info(const char *path, struct png_info *pi)
{
	unsigned char buf[512];
	FILE *f = fopen(path, "rb");
	assert_non_null(f);
	size_t n = fread(buf, 1, sizeof(buf), f);
	fclose(f);
	assert_true(n > 33 && memcmp(buf, "\x89PNG\r\n\x1a\n", 8) == 0);
	*pi = (struct png_info){.w = be32(buf + 16), .h = be32(buf + 20), .unit = -1};
	for (size_t off = 8; off + 12 <= n;) {
		uint32_t len = be32(buf + off);
		if (memcmp(buf + off + 4, "pHYs", 4) == 0 && off + 17 <= n) {
			pi->ppm_x = be32(buf + off + 8);
			pi->ppm_y = be32(buf + off + 12);
			pi->unit = buf[off + 16];
		}
		off += 12 + len;
	}
}

static void run_mvod(char **args, struct run_result *r)
{
	char *argv[24] = {(char *)harness_bin("MVOD")};
	int n = 1;
	while (*args && n < 23)
		argv[n++] = *args++;
	argv[n] = NULL;
	assert_int_equal(harness_run(argv, r), 0);
	if (!r->exited)
		fail_msg("killed by signal %d: %s", r->status, r->err);
}

static void expect(char **args, int code, const char *needle)
{
	struct run_result r;
	run_mvod(args, &r);
	if (r.status != code || !strstr(r.err, needle))
		fail_msg("expected exit %d and '%s', got %d:\n%s%s", code, needle, r.status, r.out, r.err);
}

static void board_png(const char *spec, const char *dpi, const char *name, struct png_info *pi)
{
	char out[300];
	snprintf(out, sizeof(out), "%s/%s", harness_tmpdir(), name);
	struct run_result r;
	run_mvod((char *[]){"board", "--board", (char *)spec, "--out", out, "--dpi", (char *)dpi, NULL}, &r);
	if (r.status)
		fail_msg("mvod board failed (%d): %s", r.status, r.err);
	read_png_info(out, pi);
}

static void test_board_size_and_dpi(void **state)
{
	(void)state;
	struct png_info pi;
	/*
	 * 0.04 m at 300 dpi = 472.44 px, drawn 472 px (0.1 % small, said in the output); 5 x 7
	 * squares and a one-square white border on each side: 7 x 472 by 9 x 472.
	 */
	board_png(CHARUCO, "300", "charuco.png", &pi);
	assert_int_equal(pi.w, 7 * 472);
	assert_int_equal(pi.h, 9 * 472);
	/* 300 dpi = 300 / 0.0254 = 11811.02 px per metre. */
	assert_int_equal(pi.unit, 1);
	assert_int_equal(pi.ppm_x, 11811);
	assert_int_equal(pi.ppm_y, 11811);
	/* 9x6 inner corners = 10 x 7 squares; 0.025 m at 150 dpi = 147.6 -> 148 px. */
	board_png("chessboard:9x6:0.025", "150", "chess.png", &pi);
	assert_int_equal(pi.w, 12 * 148);
	assert_int_equal(pi.h, 9 * 148);
	assert_int_equal(pi.ppm_x, 5906);
}

static void test_board_says_how_to_print(void **state)
{
	(void)state;
	char out[300];
	snprintf(out, sizeof(out), "%s/a4.png", harness_tmpdir());
	struct run_result r;
	/* 5 x 7 squares of 25 mm with a 25 mm border: 175 x 225 mm, an A4 sheet portrait. */
	run_mvod((char *[]){"board", "--board", "charuco:5x7:0.025:0.0125:DICT_6X6_250", "--out", out, NULL}, &r);
	assert_int_equal(r.status, 0);
	assert_non_null(strstr(r.out, "A4 (portrait)"));
	assert_non_null(strstr(r.out, "100 %"));
	assert_non_null(strstr(r.out, "measure a square"));
	/* 0.025 m at 300 dpi = 295.3 px, drawn 295 px = 24.98 mm. */
	assert_non_null(strstr(r.out, "it should be 24.98 mm"));
	/*
	 * The case: 6x9 inner corners are 7 x 10 squares, 9 x 12 with the border; at
	 * 23.31 mm (275 px) that is 209.6 x 279.4 mm, which fits A4's 210 mm only without the
	 * printer's 6.35 mm margins: A3 then.
	 */
	run_mvod((char *[]){"board", "--board", "chessboard:6x9:0.02331", "--out", out, NULL}, &r);
	assert_int_equal(r.status, 0);
	if (!strstr(r.out, "= 209.6 x 279.4 mm") || !strstr(r.out, "A3 (portrait)") ||
	    !strstr(r.out, "6.35 mm printer margins"))
		fail_msg("a 209.8 mm wide board was put on A4 portrait: %s", r.out);
}

/* A board's own image, undistorted and frontal, is found: one view, too few to calibrate. */
static void test_board_image_is_detected(void **state)
{
	(void)state;
	char dir[300], src[320], out[320];
	snprintf(dir, sizeof(dir), "%s/one", harness_tmpdir());
	assert_int_equal(mkdir(dir, 0755), 0);
	struct png_info pi;
	board_png(CHARUCO, "100", "one/board.png", &pi);
	snprintf(src, sizeof(src), "images:%s", dir);
	snprintf(out, sizeof(out), "%s/one.json", harness_tmpdir());
	expect((char *[]){"calibrate", "--source", src, "--board", CHARUCO, "--out", out, NULL}, 1,
	       "found the board in 1 of 1 frames; calibration needs at least 3 views");
	assert_int_not_equal(access(out, F_OK), 0);
}

static char street[300];

static int setup(void **state)
{
	(void)state;
	char dir[256];
	snprintf(dir, sizeof(dir), "%s/street", harness_tmpdir());
	harness_synth(dir, "forward", 10, "png", NULL);
	snprintf(street, sizeof(street), "images:%s/images", dir);
	return 0;
}

static const char *existing_calib(void)
{
	static char path[300];
	snprintf(path, sizeof(path), "%s/keep.json", harness_tmpdir());
	FILE *f = fopen(path, "w");
	assert_non_null(f);
	fputs("a good calibration\n", f);
	fclose(f);
	return path;
}

static void assert_untouched(const char *path)
{
	char text[64] = "";
	FILE *f = fopen(path, "r");
	assert_non_null(f);
	assert_non_null(fgets(text, sizeof(text), f));
	fclose(f);
	assert_string_equal(text, "a good calibration\n");
}

static void test_no_board(void **state)
{
	(void)state;
	const char *out = existing_calib();
	expect((char *[]){"calibrate", "--source", street, "--board", CHARUCO, "--out", (char *)out, NULL},
	       1, "no board found in 10 frames");
	assert_untouched(out);
	expect((char *[]){"calibrate", "--source", street, "--board", "chessboard:9x6:0.025", "--out",
			  (char *)out, NULL},
	       1, "COLSxROWS counts inner corners");
	assert_untouched(out);
}

static void test_malformed_spec(void **state)
{
	(void)state;
	const char *out = existing_calib();
	expect((char *[]){"calibrate", "--source", street, "--board", "charuco:5x7:0.04:0.05:DICT_6X6_250",
			  "--out", (char *)out, NULL},
	       2, "smaller than the square");
	expect((char *[]){"calibrate", "--source", street, "--board", "chessboard:9x6", "--out", (char *)out, NULL},
	       2, "a chessboard needs 2 fields");
	expect((char *[]){"board", "--board", "hexboard:3x3:0.1", "--out", (char *)out, NULL}, 2,
	       "unknown board type 'hexboard'");
	assert_untouched(out);
}

static void test_unwritable_out(void **state)
{
	(void)state;
	expect((char *[]){"calibrate", "--source", street, "--board", CHARUCO, "--out",
			  "/nonexistent-dir/calib.json", NULL},
	       2, "cannot write in /nonexistent-dir/");
	/* Checked before reading the source: a missing source is not what it reports. */
	expect((char *[]){"calibrate", "--source", "images:/nonexistent-src", "--board", CHARUCO,
			  "--out", (char *)harness_tmpdir(), NULL},
	       2, "is a directory");
	expect((char *[]){"calibrate", "--source", street, "--board", CHARUCO, "--out", "x.json",
			  "--report", "/nonexistent-dir/r.png", NULL},
	       2, "--report /nonexistent-dir/r.png: cannot write");
	expect((char *[]){"board", "--board", CHARUCO, "--out", "/nonexistent-dir/b.png", NULL}, 2,
	       "cannot write in /nonexistent-dir/");
}

static void test_usage_errors(void **state)
{
	(void)state;
	expect((char *[]){"calibrate", "--board", CHARUCO, "--out", "x.json", NULL}, 2,
	       "--source URI is required");
	expect((char *[]){"calibrate", "--source", street, "--board", CHARUCO, "--out", "x.json",
			  "--max-views", "5", NULL},
	       2, "an integer in [10, 500]");
	expect((char *[]){"calibrate", "--source", street, "--board", CHARUCO, "--out", "x.json",
			  "--model", "fisheye", "--rational", NULL},
	       2, "--rational is for the pinhole model");
	expect((char *[]){"board", "--board", CHARUCO, "--out", "x.png", "--dpi", "10", NULL}, 2,
	       "a number in [50, 2400]");
	struct run_result r;
	run_mvod((char *[]){"calibrate", "--help", NULL}, &r);
	assert_int_equal(r.status, 0);
	assert_non_null(strstr(r.out, "Example:"));
	run_mvod((char *[]){"board", "--help", NULL}, &r);
	assert_int_equal(r.status, 0);
	assert_non_null(strstr(r.out, "Example:"));
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_board_size_and_dpi),
		cmocka_unit_test(test_board_says_how_to_print),
		cmocka_unit_test(test_board_image_is_detected),
		cmocka_unit_test(test_no_board),
		cmocka_unit_test(test_malformed_spec),
		cmocka_unit_test(test_unwritable_out),
		cmocka_unit_test(test_usage_errors),
	};
	return cmocka_run_group_tests(tests, setup, harness_teardown);
}
