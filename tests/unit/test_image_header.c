/*
 * Image sizes from headers (capture/image_header.h): every format a frame folder holds, as
 * OpenCV writes it, gives its true size; headers cut short, of no size or of no known format
 * give -EINVAL; a bomb's header (30000x30000) is read as what it says, without decoding.
 */
#include <errno.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "harness.h"

#include "capture/image_header.h"
#include "util/image_file.h"

static void expect_size(const uint8_t *b, size_t len, int w, int h)
{
	int gw = 0, gh = 0;
	assert_int_equal(mvod_image_header_size(b, len, &gw, &gh), 0);
	assert_int_equal(gw, w);
	assert_int_equal(gh, h);
}

static void expect_none(const void *b, size_t len)
{
	int w, h;
	assert_int_equal(mvod_image_header_size(b, len, &w, &h), -EINVAL);
}

/* Every extension images: takes, written by OpenCV, grey and colour, odd sizes. */
static void test_opencv_files(void **state)
{
	(void)state;
	static const char *const exts[] = {".png", ".jpg", ".pgm", ".ppm", ".bmp", ".tif"};
	static uint8_t px[37 * 23 * 3];
	for (size_t i = 0; i < sizeof(px); i++)
		px[i] = (uint8_t)(i * 7);
	for (size_t e = 0; e < sizeof(exts) / sizeof(exts[0]); e++) {
		bool colour = strcmp(exts[e], ".ppm") == 0 || strcmp(exts[e], ".bmp") == 0;
		struct mvod_image img = {.w = 37, .h = 23, .stride = colour ? 111 : 37,
					 .fmt = colour ? MVOD_PIX_BGR : MVOD_PIX_GREY, .data = px};
		char name[32];
		snprintf(name, sizeof(name), "f%s", exts[e]);
		const char *path = harness_tmp_path(name);
		assert_int_equal(mvod_image_file_write(path, exts[e], &img, 0), 0);
		size_t len;
		uint8_t *b = (uint8_t *)harness_slurp(harness_tmpdir(), name, &len);
		expect_size(b, len, 37, 23);
		/* Cut before the size: PNG, JPEG and BMP state it in their first 26 bytes. */
		bool text = exts[e][1] == 'p' && exts[e][3] == 'm'; /* PNM: "P5\n37 23" is whole */
		for (size_t cut = 0; cut < 16 && !text && exts[e][1] != 't'; cut++)
			expect_none(b, cut);
		free(b);
	}
}

/* Headers made by hand: the cases a writer may produce and a bomb. */
static void test_crafted(void **state)
{
	(void)state;
	static const uint8_t png[] = "\x89PNG\r\n\x1a\n\0\0\0\x0dIHDR\0\0\x75\x30\0\0\x75\x30\x08\0";
	expect_size(png, sizeof(png) - 1, 30000, 30000);
	static const uint8_t png0[] = "\x89PNG\r\n\x1a\n\0\0\0\x0dIHDR\0\0\0\0\0\0\x75\x30\x08\0";
	expect_none(png0, sizeof(png0) - 1);
	/* JPEG: fill bytes, an APP1 of 300 bytes, then SOF2 (progressive). */
	static uint8_t jpg[400] = {0xFF, 0xD8, 0xFF, 0xFF, 0xE1, 0x01, 0x2C};
	memcpy(jpg + 3 + 2 + 300, "\xFF\xC2\x00\x11\x08\x01\xE0\x02\x80", 9);
	expect_size(jpg, sizeof(jpg), 640, 480);
	expect_none(jpg, 312); /* the size cut off */
	jpg[306] = 0xDA;       /* a scan before any frame */
	expect_none(jpg, sizeof(jpg));
	static const char pgm[] = "P5\n# made by hand\n# 2\n 640\t480 255\n";
	expect_size((const uint8_t *)pgm, sizeof(pgm) - 1, 640, 480);
	expect_none("P5 640", 6);
	expect_none("P5 99999999999 480", 18);
	static const uint8_t bmp[26] = {'B', 'M', [14] = 40, [18] = 0x80, 0x02, [22] = 0x20, 0xFE,
					0xFF, 0xFF}; /* height -480: top-down */
	expect_size(bmp, sizeof(bmp), 640, 480);
	static const uint8_t tiff_be[] = {'M', 'M', 0, '*', 0, 0, 0, 8, 0, 2,
					  1, 0, 0, 3, 0, 0, 0, 1, 2, 0x80, 0, 0,
					  1, 1, 0, 4, 0, 0, 0, 1, 0, 0, 1, 0xE0};
	expect_size(tiff_be, sizeof(tiff_be), 640, 480);
	expect_none(tiff_be, sizeof(tiff_be) - 12); /* no ImageLength */
	expect_none("GIF89a\x80\x02\xe0\x01", 10);
	expect_none("", 0);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_opencv_files),
		cmocka_unit_test(test_crafted),
	};
	return cmocka_run_group_tests(tests, NULL, harness_teardown);
}
