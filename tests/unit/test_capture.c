/*
 * Frame sources: URI dispatch, the images: and kitti: backends on fixtures written at test
 * time (PNM by hand, since tests do not link OpenCV), and the file: backend's open errors.
 * Decoding real videos is left to the integration tests.
 */
#include <errno.h>
#include <ftw.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmocka.h>

#include "harness.h"

#include "mvod/capture.h"

static char dir[64];

static int setup(void **state)
{
	(void)state;
	strcpy(dir, "/tmp/mvod-test-capture-XXXXXX");
	return mkdtemp(dir) ? 0 : -1;
}

static int remove_entry(const char *path, const struct stat *st, int flag, struct FTW *ftw)
{
	(void)st;
	(void)flag;
	(void)ftw;
	return remove(path);
}

static int teardown(void **state)
{
	(void)state;
	return nftw(dir, remove_entry, 16, FTW_DEPTH | FTW_PHYS);
}

/* dir/name, in one of a few rotating buffers so that a test can hold several at once. */
static const char *path_of(const char *name)
{
	static char paths[4][256];
	static int next;
	char *p = paths[next++ % 4];
	snprintf(p, sizeof(paths[0]), "%s/%s", dir, name);
	return p;
}

static void make_dir(const char *name)
{
	assert_int_equal(mkdir(path_of(name), 0755), 0);
}

static void write_bytes(const char *name, const void *data, size_t len)
{
	FILE *f = fopen(path_of(name), "wb");
	assert_non_null(f);
	assert_int_equal(fwrite(data, 1, len, f), len);
	assert_int_equal(fclose(f), 0);
}

static void write_text(const char *name, const char *text)
{
	write_bytes(name, text, strlen(text));
}

/*
 * A binary PNM: channels 1 writes P5 with every sample = v, channels 3 writes P6 with every
 * pixel = (r, g, b) = (v, v/2, v/3). maxval above 255 makes 16-bit big-endian samples.
 */
static void write_pnm(const char *name, int channels, int w, int h, int maxval, int v)
{
	static uint8_t buf[1 << 16];
	int n = snprintf((char *)buf, 64, "P%d\n%d %d\n%d\n", channels == 1 ? 5 : 6, w, h, maxval);
	int rgb[3] = {v, v / 2, v / 3};
	for (int i = 0; i < w * h * channels; i++) {
		int s = channels == 1 ? v : rgb[i % 3];
		if (maxval > 255)
			buf[n++] = (uint8_t)(s >> 8);
		buf[n++] = (uint8_t)s;
	}
	write_bytes(name, buf, (size_t)n);
}

static void write_grey(const char *name, int w, int h, int v)
{
	write_pnm(name, 1, w, h, 255, v);
}

static int open_uri(const char *scheme, const char *location, struct mvod_source **src,
		    char *err, size_t errlen)
{
	char uri[512];
	snprintf(uri, sizeof(uri), "%s:%s", scheme, location);
	return mvod_source_open(uri, src, err, errlen);
}

static struct mvod_source *open_ok(const char *scheme, const char *location)
{
	struct mvod_source *src = NULL;
	char err[512] = "";
	int ret = open_uri(scheme, location, &src, err, sizeof(err));
	if (ret)
		fail_msg("%s:%s: %d %s", scheme, location, ret, err);
	return src;
}

static void test_registry(void **state)
{
	(void)state;
	static const char *const schemes[] = {"file", "images", "kitti", "kitti-raw", "euroc",
					      "tum", "v4l2", "libcamera"};
	size_t n = 0;
	for (; mvod_source_backends[n]; n++) {
		const struct mvod_source_ops *ops = mvod_source_backends[n];
		assert_true(n < 8);
		assert_string_equal(ops->scheme, schemes[n]);
		assert_non_null(ops->summary);
		assert_true(ops->open && ops->read && ops->info && ops->close);
	}
	assert_int_equal(n, 8);
}

static void test_unknown_scheme(void **state)
{
	(void)state;
	harness_source_open_fails("rtsp://cam/stream", -EPROTONOSUPPORT, "\"rtsp\"");
	harness_source_open_fails("rtsp://cam/stream", -EPROTONOSUPPORT, "known: file, images, kitti");
}

static void test_plain_path(void **state)
{
	(void)state;
	harness_source_open_fails("clip.mkv", -EPROTONOSUPPORT, "file:clip.mkv");
	harness_source_open_fails("./odd:name.mkv", -EPROTONOSUPPORT, "file:./odd:name.mkv");
	char uri[128];
	snprintf(uri, sizeof(uri), "images:%s", dir);
	harness_source_open_fails(dir, -EPROTONOSUPPORT, uri);
}

static void test_close_null(void **state)
{
	(void)state;
	mvod_source_close(NULL);
}

static void read_value(struct mvod_source *src, int64_t index, int value)
{
	struct mvod_frame f;
	assert_int_equal(mvod_source_read(src, &f), 0);
	assert_int_equal(f.index, index);
	assert_int_equal(f.img.fmt, MVOD_PIX_GREY);
	assert_true(f.img.stride >= f.img.w);
	assert_int_equal(f.img.data[0], value);
	assert_int_equal(f.img.data[(f.img.h - 1) * f.img.stride + f.img.w - 1], value);
}

/* Numeric names in numeric order, any case of extension, non-images and hidden files skipped. */
static void test_images_sorted(void **state)
{
	(void)state;
	write_grey("10.pgm", 8, 4, 10);
	write_grey("2.pgm", 8, 4, 2);
	write_grey("1.pgm", 8, 4, 1);
	write_grey("3.PGM", 8, 4, 3);
	write_grey(".hidden.pgm", 8, 4, 99);
	write_text("notes.txt", "not an image");
	write_text("times.txt", "0\n1\n2\n3\n");
	struct mvod_source *src = open_ok("images", dir);
	struct mvod_source_info info;
	mvod_source_info(src, &info);
	assert_int_equal(info.width, 8);
	assert_int_equal(info.height, 4);
	assert_int_equal(info.frames, 4);
	static const int values[] = {1, 2, 3, 10};
	for (int i = 0; i < 4; i++)
		read_value(src, i, values[i]);
	mvod_source_close(src);
}

static void test_images_times(void **state)
{
	(void)state;
	for (int i = 0; i < 3; i++) {
		char name[16];
		snprintf(name, sizeof(name), "%06d.pgm", i);
		write_grey(name, 8, 4, i);
	}
	/* First token only; blank lines skipped; extra lines past the images ignored. */
	write_text("times.txt", "1.000000e+00 first\n\n  1.103862\r\n1.2071 x\n9\n");
	struct mvod_source *src = open_ok("images", dir);
	static const int64_t expect[] = {1000000, 1103862, 1207100};
	struct mvod_frame f;
	for (int i = 0; i < 3; i++) {
		assert_int_equal(mvod_source_read(src, &f), 0);
		assert_int_equal(f.utime, expect[i]);
	}
	struct mvod_source_info info;
	mvod_source_info(src, &info);
	assert_true(info.fps > 9.657 && info.fps < 9.658); /* 2 frames in 0.2071 s */
	mvod_source_close(src);
}

static void test_images_default_10hz(void **state)
{
	(void)state;
	for (int i = 0; i < 3; i++) {
		char name[16];
		snprintf(name, sizeof(name), "%d.pgm", i);
		write_grey(name, 8, 4, i);
	}
	struct mvod_source *src = open_ok("images", dir);
	struct mvod_frame f;
	for (int i = 0; i < 3; i++) {
		assert_int_equal(mvod_source_read(src, &f), 0);
		assert_int_equal(f.utime, i * 100000);
	}
	struct mvod_source_info info;
	mvod_source_info(src, &info);
	assert_true(info.fps == 10.0);
	mvod_source_close(src);
}

static void test_images_too_few_times(void **state)
{
	(void)state;
	write_grey("0.pgm", 8, 4, 0);
	write_grey("1.pgm", 8, 4, 1);
	write_grey("2.pgm", 8, 4, 2);
	write_text("times.txt", "0.0\n0.1\n");
	char uri[128];
	snprintf(uri, sizeof(uri), "images:%s", dir);
	harness_source_open_fails(uri, -EINVAL, "2 timestamps for 3 images");
}

static void test_images_bad_time(void **state)
{
	(void)state;
	write_grey("0.pgm", 8, 4, 0);
	write_grey("1.pgm", 8, 4, 1);
	write_text("times.txt", "0.0\n0.1s\n");
	char uri[128];
	snprintf(uri, sizeof(uri), "images:%s", dir);
	harness_source_open_fails(uri, -EINVAL, "times.txt line 2: \"0.1s\"");
}

static void test_images_empty_dir(void **state)
{
	(void)state;
	write_text("times.txt", "0.0\n");
	char uri[128];
	snprintf(uri, sizeof(uri), "images:%s", dir);
	harness_source_open_fails(uri, -ENOENT, "no images in");
	harness_source_open_fails("images:/nonexistent/mvod", -ENOENT, "cannot open image directory");
}

static void test_images_end_of_stream(void **state)
{
	(void)state;
	write_grey("0.pgm", 8, 4, 0);
	write_grey("1.pgm", 8, 4, 1);
	struct mvod_source *src = open_ok("images", dir);
	struct mvod_frame f;
	assert_int_equal(mvod_source_read(src, &f), 0);
	assert_int_equal(mvod_source_read(src, &f), 0);
	for (int i = 0; i < 3; i++)
		assert_int_equal(mvod_source_read(src, &f), -ENODATA);
	mvod_source_close(src);
}

/* A wrong-sized or undecodable frame is -EINVAL (callers skip it); the sequence goes on. */
static void test_images_bad_frames(void **state)
{
	(void)state;
	write_grey("0.pgm", 8, 4, 0);
	write_grey("1.pgm", 6, 4, 1);
	write_text("2.pgm", "P5 truncated");
	write_grey("3.pgm", 8, 4, 3);
	struct mvod_source *src = open_ok("images", dir);
	struct mvod_frame f;
	read_value(src, 0, 0);
	assert_int_equal(mvod_source_read(src, &f), -EINVAL);
	assert_int_equal(f.index, 1);
	assert_int_equal(mvod_source_read(src, &f), -EINVAL);
	assert_int_equal(f.index, 2);
	read_value(src, 3, 3);
	mvod_source_close(src);
}

static void test_images_first_undecodable(void **state)
{
	(void)state;
	write_text("0.png", "not a png");
	char uri[128];
	snprintf(uri, sizeof(uri), "images:%s", dir);
	harness_source_open_fails(uri, -EINVAL, "cannot decode image");
}

/* 16-bit samples become their high byte. */
static void test_images_16bit(void **state)
{
	(void)state;
	write_pnm("0.pgm", 1, 8, 4, 65535, 0x1234);
	struct mvod_source *src = open_ok("images", dir);
	read_value(src, 0, 0x12);
	mvod_source_close(src);
}

/* The first image fixes the format: colour then grey gives BGR throughout, and back. */
static void test_images_format_follows_first(void **state)
{
	(void)state;
	make_dir("colour");
	write_pnm("colour/0.ppm", 3, 8, 4, 255, 90);
	write_grey("colour/1.pgm", 8, 4, 50);
	struct mvod_source *src = open_ok("images", path_of("colour"));
	struct mvod_frame f;
	assert_int_equal(mvod_source_read(src, &f), 0);
	assert_int_equal(f.img.fmt, MVOD_PIX_BGR);
	assert_true(f.img.stride >= 3 * f.img.w);
	assert_memory_equal(f.img.data, ((uint8_t[]){30, 45, 90}), 3);
	assert_int_equal(mvod_source_read(src, &f), 0);
	assert_int_equal(f.img.fmt, MVOD_PIX_BGR);
	assert_memory_equal(f.img.data, ((uint8_t[]){50, 50, 50}), 3);
	mvod_source_close(src);

	make_dir("grey");
	write_grey("grey/0.pgm", 8, 4, 50);
	write_pnm("grey/1.ppm", 3, 8, 4, 255, 90);
	src = open_ok("images", path_of("grey"));
	assert_int_equal(mvod_source_read(src, &f), 0);
	assert_int_equal(mvod_source_read(src, &f), 0);
	assert_int_equal(f.img.fmt, MVOD_PIX_GREY);
	/* 0.299 R + 0.587 G + 0.114 B of (90, 45, 30) */
	assert_in_range(f.img.data[0], 56, 57);
	mvod_source_close(src);
}

static void test_images_no_camera(void **state)
{
	(void)state;
	write_grey("0.pgm", 8, 4, 0);
	struct mvod_source *src = open_ok("images", dir);
	struct mvod_camera cam;
	assert_int_equal(mvod_source_camera(src, &cam), -ENOENT);
	mvod_source_close(src);
}

#define KITTI_P0 "7.070912e+02 0 6.018873e+02 0 0 7.070912e+02 1.831104e+02 0 0 0 1 0"

static void make_kitti(int frames, bool with_calib, bool with_times)
{
	make_dir("image_0");
	for (int i = 0; i < frames; i++) {
		char name[32];
		snprintf(name, sizeof(name), "image_0/%06d.pgm", i);
		write_grey(name, 12, 5, i);
	}
	if (with_calib)
		write_text("calib.txt", "P0: " KITTI_P0 "\n"
					"P1: 7.070912e+02 0 6.018873e+02 -3.798145e+02 0 "
					"7.070912e+02 1.831104e+02 0 0 0 1 0\n");
	if (with_times)
		write_text("times.txt", "0.000000e+00\n1.036200e-01\n2.072400e-01\n");
}

static void test_kitti(void **state)
{
	(void)state;
	make_kitti(3, true, true);
	struct mvod_source *src = open_ok("kitti", dir);
	struct mvod_camera cam;
	assert_int_equal(mvod_source_camera(src, &cam), 0);
	assert_true(cam.fx == 707.0912 && cam.fy == 707.0912);
	assert_true(cam.cx == 601.8873 && cam.cy == 183.1104);
	assert_int_equal(cam.width, 12);
	assert_int_equal(cam.height, 5);
	assert_int_equal(cam.n_dist, 0);
	static const int64_t expect[] = {0, 103620, 207240};
	struct mvod_frame f;
	for (int i = 0; i < 3; i++) {
		assert_int_equal(mvod_source_read(src, &f), 0);
		assert_int_equal(f.index, i);
		assert_int_equal(f.utime, expect[i]);
		assert_int_equal(f.img.data[0], i);
	}
	assert_int_equal(mvod_source_read(src, &f), -ENODATA);
	mvod_source_close(src);
}

static void test_kitti_no_times(void **state)
{
	(void)state;
	make_kitti(2, true, false);
	struct mvod_source *src = open_ok("kitti", dir);
	struct mvod_frame f;
	assert_int_equal(mvod_source_read(src, &f), 0);
	assert_int_equal(mvod_source_read(src, &f), 0);
	assert_int_equal(f.utime, 100000);
	mvod_source_close(src);
}

static void test_kitti_no_calib(void **state)
{
	(void)state;
	make_kitti(2, false, true);
	char uri[128];
	snprintf(uri, sizeof(uri), "kitti:%s", dir);
	harness_source_open_fails(uri, -ENOENT, "calib.txt");
}

static void test_kitti_no_images(void **state)
{
	(void)state;
	make_kitti(0, true, true);
	char uri[128];
	snprintf(uri, sizeof(uri), "kitti:%s", dir);
	harness_source_open_fails(uri, -ENOENT, "no images in");
}

static void test_file_missing(void **state)
{
	(void)state;
	char uri[128];
	snprintf(uri, sizeof(uri), "file:%s/none.mkv", dir);
	harness_source_open_fails(uri, -ENOENT, "no such file");
}

static void test_file_not_a_video(void **state)
{
	(void)state;
	write_text("clip.mkv", "this is text, not Matroska\n");
	char uri[128];
	snprintf(uri, sizeof(uri), "file:%s/clip.mkv", dir);
	harness_source_open_fails(uri, -EINVAL, "cannot decode video");
	snprintf(uri, sizeof(uri), "file:%s", dir);
	harness_source_open_fails(uri, -EISDIR, "images:");
}

#define T(f) cmocka_unit_test_setup_teardown(f, setup, teardown)

int main(void)
{
	const struct CMUnitTest tests[] = {
		T(test_registry),
		T(test_unknown_scheme),
		T(test_plain_path),
		T(test_close_null),
		T(test_images_sorted),
		T(test_images_times),
		T(test_images_default_10hz),
		T(test_images_too_few_times),
		T(test_images_bad_time),
		T(test_images_empty_dir),
		T(test_images_end_of_stream),
		T(test_images_bad_frames),
		T(test_images_first_undecodable),
		T(test_images_16bit),
		T(test_images_format_follows_first),
		T(test_images_no_camera),
		T(test_kitti),
		T(test_kitti_no_times),
		T(test_kitti_no_calib),
		T(test_kitti_no_images),
		T(test_file_missing),
		T(test_file_not_a_video),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
