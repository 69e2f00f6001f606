/*
 * The file: source's video reader (src/capture/video.c) through the capture thread and its
 * queue, on videos mkvideo writes with a known pattern: every frame exactly once, in order, at
 * its container time, every pixel checked. Grey video hands over its luma plane as it is;
 * limited-range YUV is expanded to full range and colour converted to grey, which is what the
 * OpenCV reader used before gave after mvod's BGR -> grey (measured on these files: equal for
 * grey, within 1 for YUV and bgr0, the rounding of swscale's fixed-point YUV -> BGR).
 */
#include <errno.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <sys/stat.h>

#include <cmocka.h>

#include "harness.h"
#include "mvod/calib.h"
#include "mvod/capture.h"

/* Three times the capture queue's depth (4): the capture thread has to wait for room. */
#define FRAMES 12
#define W 64
#define H 48
#define PERIOD_MS 40

/* mkvideo's pattern (tests/tools/mkvideo.c): the luma, or R of bgr0. */
static int level(int x, int y, int i)
{
	return (uint8_t)((x * 7 + y * 3 + i * 5) ^ (x * y));
}

/* Limited-range Y' (16..235) to full range, rounded and clamped. */
static int expanded(int y)
{
	long g = lround((y - 16) * 255.0 / 219.0);
	return g < 0 ? 0 : g > 255 ? 255 : (int)g;
}

/* BT.601 luma of mkvideo's bgr0 pixel (R = level, G = level ^ 0x5a, B = 255 - level). */
static double luma_bgr(int r)
{
	return 0.299 * r + 0.587 * (r ^ 0x5a) + 0.114 * (255 - r);
}

/* FRAMES frames of WxH, PERIOD_MS apart, as codec[:pixfmt] into name; returns its path. */
static const char *make(const char *name, const char *codec)
{
	static char spec[FRAMES][32];
	char *argv[FRAMES + 4] = {(char *)harness_bin("MVOD_MKVIDEO"),
				  (char *)harness_tmp_path(name), (char *)codec};
	for (int i = 0; i < FRAMES; i++) {
		snprintf(spec[i], sizeof(spec[i]), "%dx%d@%d", W, H, i * PERIOD_MS);
		argv[3 + i] = spec[i];
	}
	argv[3 + FRAMES] = NULL;
	struct run_result r;
	assert_int_equal(harness_run(argv, &r), 0);
	if (!r.exited || r.status)
		fail_msg("mkvideo %s failed: %s", codec, r.err);
	return argv[1];
}

/* Pixel (x, y) of frame i off by at most tol from what kind says it must be. */
static void check_pixel(const struct mvod_frame *f, int x, int y, int i, char kind, double tol)
{
	int got = f->img.data[y * f->img.stride + x];
	int p = level(x, y, i);
	double want = kind == 'g' ? p : kind == 'y' ? expanded(p) : luma_bgr(p);
	if (fabs(got - want) > tol)
		fail_msg("frame %d (%d, %d): %d, want %.2f", i, x, y, got, want);
}

/* Every frame of path through the capture thread once, in order, then -ENODATA. */
static void drain(const char *path, char kind, double tol)
{
	char uri[600], err[512] = "";
	snprintf(uri, sizeof(uri), "file:%s", path);
	struct mvod_source *src = NULL;
	if (mvod_source_open(uri, &src, err, sizeof(err)))
		fail_msg("%s: %s", uri, err);
	struct mvod_capture *cap = NULL;
	assert_int_equal(mvod_capture_start(src, uri, &cap), 0);
	struct mvod_frame f;
	int epoch, ret;
	for (int i = 0; i < FRAMES; i++) {
		while ((ret = mvod_capture_next(cap, 1000, &f, &epoch)) == -EAGAIN)
			;
		assert_int_equal(ret, 0);
		assert_int_equal(f.index, i);
		assert_int_equal(f.utime, (int64_t)i * PERIOD_MS * 1000);
		assert_int_equal(f.img.w, W);
		assert_int_equal(f.img.h, H);
		assert_int_equal(f.img.fmt, MVOD_PIX_GREY);
		for (int y = 0; y < H; y++)
			for (int x = 0; x < W; x++)
				check_pixel(&f, x, y, i, kind, tol);
	}
	while ((ret = mvod_capture_next(cap, 1000, &f, &epoch)) == -EAGAIN)
		;
	assert_int_equal(ret, -ENODATA);
	mvod_capture_stop(cap);
}

/* Lossless grey (mvod-synth's kind of file): the decoder's luma plane, every pixel exact. */
static void test_grey(void **state)
{
	(void)state;
	drain(make("grey.mkv", "ffv1:gray"), 'g', 0);
}

/*
 * Lossless YUV 4:2:0 without a range flag, so limited range: Y' expanded by the table, exact
 * (the table's rounding is the reference; OpenCV's fixed-point path was within 1 of it).
 */
static void test_yuv(void **state)
{
	(void)state;
	drain(make("yuv.mkv", "ffv1:yuv420p"), 'y', 0);
}

/* Lossless colour (packed BGR): grey by swscale, within 1 of BT.601 luma (its fixed point). */
static void test_colour(void **state)
{
	(void)state;
	drain(make("bgr.mkv", "ffv1:bgr0"), 'c', 1.0);
}

/* Bytes of the file at path. */
static long long file_bytes(const char *path)
{
	struct stat st;
	if (stat(path, &st))
		fail_msg("%s: cannot stat", path);
	return (long long)st.st_size;
}

/* The next frame of cap; fails on anything but a frame. */
static void next_frame(struct mvod_capture *cap, struct mvod_frame *f)
{
	int epoch, ret;
	while ((ret = mvod_capture_next(cap, 1000, f, &epoch)) == -EAGAIN)
		;
	assert_int_equal(ret, 0);
}

/*
 * mvod-synth --codec raw (the cheap-to-decode sample) is lossless: the same frames, pixel for
 * pixel, as its FFV1 default, the same count, then the end; and it is uncompressed (a file at
 * least a frame's bytes a frame), so the two files really are two codecs.
 */
static void test_synth_raw(void **state)
{
	(void)state;
	enum { N = 6, SW = 160, SH = 120 };
	char ffv1[512], raw[512];
	snprintf(ffv1, sizeof(ffv1), "%s", harness_tmp_path("synth_ffv1"));
	snprintf(raw, sizeof(raw), "%s", harness_tmp_path("synth_raw"));
	harness_synth(ffv1, "turn", N, "mkv", "--size", "160x120", NULL);
	harness_synth(raw, "turn", N, "mkv", "--size", "160x120", "--codec", "raw", NULL);
	char uri[2][600], err[512] = "";
	snprintf(uri[0], sizeof(uri[0]), "file:%s/video.mkv", ffv1);
	snprintf(uri[1], sizeof(uri[1]), "file:%s/video.mkv", raw);
	assert_true(file_bytes(uri[1] + 5) >= (long long)N * SW * SH);
	assert_true(file_bytes(uri[0] + 5) < file_bytes(uri[1] + 5));
	struct mvod_source *src[2] = {NULL, NULL};
	struct mvod_capture *cap[2] = {NULL, NULL};
	for (int k = 0; k < 2; k++) {
		if (mvod_source_open(uri[k], &src[k], err, sizeof(err)))
			fail_msg("%s: %s", uri[k], err);
		assert_int_equal(mvod_capture_start(src[k], uri[k], &cap[k]), 0);
	}
	for (int i = 0; i < N; i++) {
		struct mvod_frame a, b;
		next_frame(cap[0], &a);
		next_frame(cap[1], &b);
		assert_int_equal(a.index, i);
		assert_int_equal(b.index, i);
		assert_int_equal(a.utime, b.utime);
		assert_int_equal(b.img.w, SW);
		assert_int_equal(b.img.h, SH);
		assert_int_equal(a.img.fmt, MVOD_PIX_GREY);
		assert_int_equal(b.img.fmt, MVOD_PIX_GREY);
		for (int y = 0; y < SH; y++)
			if (memcmp(a.img.data + y * a.img.stride, b.img.data + y * b.img.stride, SW))
				fail_msg("frame %d row %d differs between FFV1 and raw", i, y);
	}
	for (int k = 0; k < 2; k++) {
		struct mvod_frame f;
		int epoch, ret;
		while ((ret = mvod_capture_next(cap[k], 1000, &f, &epoch)) == -EAGAIN)
			;
		assert_int_equal(ret, -ENODATA);
		mvod_capture_stop(cap[k]);
	}
}

/*
 * Odd sizes: video.mkv carries exactly the size calib.json names, for both codecs, and the very
 * frames the PNG rendering has. OpenCV's VideoWriter, which wrote it before, rounded each side
 * down to even, so 321x241 came out 320x240 beside a calibration for 321x241 (KITTI's own
 * 1241x376 came out 1240x376) and mvod refused the pair. Then mvod bench runs on the pair, as
 * docs/synth.md has it.
 */
static void test_synth_odd_size(void **state)
{
	(void)state;
	enum { N = 6, SW = 321, SH = 241 };
	static const char *const codecs[] = {"ffv1", "raw"};
	char png[512], uri[600], err[512] = "";
	snprintf(png, sizeof(png), "%s", harness_tmp_path("odd_png"));
	harness_synth(png, "turn", N, "png", "--size", "321x241", NULL);
	struct mvod_source *src[3] = {NULL, NULL, NULL};
	struct mvod_capture *cap[3] = {NULL, NULL, NULL};
	char dir[2][512];
	for (int k = 0; k < 3; k++) {
		if (k < 2) {
			char name[16];
			snprintf(name, sizeof(name), "odd_%s", codecs[k]);
			snprintf(dir[k], sizeof(dir[k]), "%s", harness_tmp_path(name));
			harness_synth(dir[k], "turn", N, "mkv", "--size", "321x241", "--codec",
				      codecs[k], NULL);
			char calib[600];
			snprintf(calib, sizeof(calib), "%s/calib.json", dir[k]);
			struct mvod_camera cam;
			if (mvod_calib_load(calib, &cam, err, sizeof(err)))
				fail_msg("%s: %s", calib, err);
			assert_int_equal(cam.width, SW);
			assert_int_equal(cam.height, SH);
			snprintf(uri, sizeof(uri), "file:%s/video.mkv", dir[k]);
		} else {
			snprintf(uri, sizeof(uri), "images:%s/images", png);
		}
		if (mvod_source_open(uri, &src[k], err, sizeof(err)))
			fail_msg("%s: %s", uri, err);
		assert_int_equal(mvod_capture_start(src[k], uri, &cap[k]), 0);
	}
	for (int i = 0; i < N; i++) {
		struct mvod_frame f[3];
		for (int k = 0; k < 3; k++) {
			next_frame(cap[k], &f[k]);
			assert_int_equal(f[k].index, i);
			if (f[k].img.w != SW || f[k].img.h != SH)
				fail_msg("%s frame %d is %dx%d, not 321x241",
					 k < 2 ? codecs[k] : "png", i, f[k].img.w, f[k].img.h);
			assert_int_equal(f[k].img.fmt, MVOD_PIX_GREY);
		}
		for (int k = 0; k < 2; k++)
			for (int y = 0; y < SH; y++)
				if (memcmp(f[k].img.data + y * f[k].img.stride,
					   f[2].img.data + y * f[2].img.stride, SW))
					fail_msg("%s frame %d row %d differs from the PNG",
						 codecs[k], i, y);
	}
	for (int k = 0; k < 3; k++)
		mvod_capture_stop(cap[k]);
	char video[600], calib[600], gt[600];
	snprintf(video, sizeof(video), "file:%s/video.mkv", dir[0]);
	snprintf(calib, sizeof(calib), "%s/calib.json", dir[0]);
	snprintf(gt, sizeof(gt), "%s/gt.tum", dir[0]);
	char *bench[] = {(char *)harness_bin("MVOD"), "bench", "--source", video, "--calib", calib,
			 "--gt", gt, NULL};
	struct run_result r;
	assert_int_equal(harness_run(bench, &r), 0);
	if (!r.exited || r.status != 0)
		fail_msg("mvod bench on mvod-synth's own 321x241 pair: %s", r.err);
}

/*
 * The same arguments and seed give the same video.mkv, byte for byte, for both codecs
 * (docs/synth.md says so of mvod-synth's output): before, Matroska's random segment and track
 * UIDs made 44 bytes of every file differ between two runs.
 */
static void test_synth_same_bytes(void **state)
{
	(void)state;
	static const char *const codecs[] = {"ffv1", "raw"};
	for (int k = 0; k < 2; k++) {
		char dir[2][512];
		size_t n[2];
		char *data[2];
		for (int run = 0; run < 2; run++) {
			char name[32];
			snprintf(name, sizeof(name), "bytes_%s_%d", codecs[k], run);
			snprintf(dir[run], sizeof(dir[run]), "%s", harness_tmp_path(name));
			harness_synth(dir[run], "turn", 3, "mkv", "--size", "65x49", "--codec",
				      codecs[k], NULL);
			data[run] = harness_slurp(dir[run], "video.mkv", &n[run]);
		}
		if (n[0] != n[1] || memcmp(data[0], data[1], n[0]) != 0)
			fail_msg("%s: video.mkv differs between two runs with the same seed",
				 codecs[k]);
		free(data[0]);
		free(data[1]);
	}
}

/* --codec names one of two codecs, for video.mkv only: anything else is a usage error. */
static void test_synth_codec_usage(void **state)
{
	(void)state;
	char *png[] = {(char *)harness_bin("MVOD_SYNTH"), "--out", (char *)harness_tmp_path("codec_png"),
		       "--format", "png", "--codec", "raw", NULL};
	char *h264[] = {(char *)harness_bin("MVOD_SYNTH"), "--out", (char *)harness_tmp_path("codec_h264"),
			"--codec", "h264", NULL};
	char **argvs[] = {png, h264};
	for (int k = 0; k < 2; k++) {
		struct run_result r;
		assert_int_equal(harness_run(argvs[k], &r), 0);
		assert_true(r.exited && r.status == 2);
		assert_non_null(strstr(r.err, "--codec"));
	}
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_grey),
		cmocka_unit_test(test_yuv),
		cmocka_unit_test(test_colour),
		cmocka_unit_test(test_synth_raw),
		cmocka_unit_test(test_synth_odd_size),
		cmocka_unit_test(test_synth_same_bytes),
		cmocka_unit_test(test_synth_codec_usage),
	};
	return cmocka_run_group_tests(tests, NULL, harness_teardown);
}
