/*
 * 8-bit grey PNGs decoded by capture/png_grey.c, on PNGs built here by hand (zlib, one row per
 * filter type), checked pixel for pixel; through the image decoder (video_shim.h) against
 * OpenCV's own decoding of the same PNG in colour; and every malformed PNG refused or left to
 * OpenCV, never read past its end.
 */
#include <errno.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>
#include <zlib.h>

#include "harness.h"

#include "capture/png_grey.h"
#include "capture/video_shim.h"

#define W 37
#define H 11
#define CAP 8192

static uint8_t pixels[H][W];

/* The row filtered with filter f against the row above (PNG's definitions, bpp 1). */
static void filter_row(int y, int f, uint8_t *out)
{
	for (int x = 0; x < W; x++) {
		int a = x ? pixels[y][x - 1] : 0, b = y ? pixels[y - 1][x] : 0;
		int c = x && y ? pixels[y - 1][x - 1] : 0, p = a + b - c;
		int pa = abs(p - a), pb = abs(p - b), pc = abs(p - c);
		int pred[5] = {0, a, b, (a + b) / 2, pa <= pb && pa <= pc ? a : pb <= pc ? b : c};
		out[x] = (uint8_t)(pixels[y][x] - pred[f]);
	}
}

static size_t put_chunk(uint8_t *png, size_t at, const char *type, const uint8_t *data,
			size_t n)
{
	png[at] = (uint8_t)(n >> 24);
	png[at + 1] = (uint8_t)(n >> 16);
	png[at + 2] = (uint8_t)(n >> 8);
	png[at + 3] = (uint8_t)n;
	memcpy(png + at + 4, type, 4);
	if (n)
		memcpy(png + at + 8, data, n);
	uLong crc = crc32(crc32(0, (const Bytef *)type, 4), data, (uInt)n);
	for (int i = 0; i < 4; i++)
		png[at + 8 + n + (size_t)i] = (uint8_t)(crc >> (24 - 8 * i));
	return at + 12 + n;
}

/*
 * A W x H PNG of pixels (colour type ct, row y with filter y % 5) into png; its IDAT split in
 * two chunks as encoders do. Returns its length.
 */
static size_t make_png(uint8_t *png, int ct)
{
	static const uint8_t sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
	uint8_t ihdr[13] = {0, 0, 0, W, 0, 0, 0, H, 8, (uint8_t)ct, 0, 0, 0};
	uint8_t raw[H * (W + 1)], z[CAP];
	for (int y = 0; y < H; y++) {
		raw[y * (W + 1)] = (uint8_t)(y % 5);
		filter_row(y, y % 5, raw + y * (W + 1) + 1);
	}
	uLongf zn = sizeof(z);
	assert_int_equal(compress2(z, &zn, raw, sizeof(raw), 9), Z_OK);
	memcpy(png, sig, 8);
	size_t at = put_chunk(png, 8, "IHDR", ihdr, 13);
	at = put_chunk(png, at, "tEXt", (const uint8_t *)"a\0b", 3); /* ancillary: skipped */
	at = put_chunk(png, at, "IDAT", z, zn / 2);
	at = put_chunk(png, at, "IDAT", z + zn / 2, zn - zn / 2);
	return put_chunk(png, at, "IEND", NULL, 0);
}

static int fill(void **state)
{
	(void)state;
	srand(13); /* fixed seed */
	for (int y = 0; y < H; y++)
		for (int x = 0; x < W; x++)
			pixels[y][x] = (uint8_t)(rand() & 0xff);
	return 0;
}

/* Every filter type (rows 0..4 and again) decodes to the exact pixels, into a wider stride. */
static void test_filters_exact(void **state)
{
	(void)state;
	uint8_t png[CAP], out[H][W + 3];
	size_t n = make_png(png, 0);
	struct mvod_png *p;
	int w, h;
	assert_int_equal(mvod_png_create(&p), 0);
	assert_int_equal(mvod_png_grey_size(png, n, &w, &h), 0);
	assert_int_equal(w, W);
	assert_int_equal(h, H);
	assert_int_equal(mvod_png_grey_decode(p, png, n, &out[0][0], W + 3), 0);
	for (int y = 0; y < H; y++)
		assert_memory_equal(out[y], pixels[y], W);
	mvod_png_destroy(p);
	mvod_png_destroy(NULL);
}

/* Anything but 8-bit grey is left to OpenCV; a broken grey PNG is refused, inside its length. */
static void test_malformed(void **state)
{
	(void)state;
	uint8_t png[CAP], out[H * W];
	struct mvod_png *p;
	int w, h;
	assert_int_equal(mvod_png_create(&p), 0);
	size_t n = make_png(png, 2); /* RGB */
	assert_int_equal(mvod_png_grey_size(png, n, &w, &h), -ENOTSUP);
	assert_int_equal(mvod_png_grey_decode(p, png, n, out, W), -ENOTSUP);
	n = make_png(png, 0);
	for (size_t cut = 0; cut < n; cut++) { /* every truncation: no IEND, or no header */
		int ret = mvod_png_grey_decode(p, png, cut, out, W);
		assert_true(ret == -EINVAL || ret == -ENOTSUP);
	}
	/* A header claiming 65535 x 1025 (over 64 Mpixel; no CRC is checked) is left to OpenCV. */
	uint8_t big[CAP];
	memcpy(big, png, n);
	memcpy(big + 16, (const uint8_t[]){0, 0, 0xff, 0xff, 0, 0, 4, 1}, 8);
	assert_int_equal(mvod_png_grey_size(big, n, &w, &h), -ENOTSUP);
	big[22] = 3; /* 65535 x 769: 50 Mpixel, accepted */
	assert_int_equal(mvod_png_grey_size(big, n, &w, &h), 0);
	assert_int_equal(w, 65535);
	assert_int_equal(h, 769);
	png[8 + 12 + 13 + 12 + 3 + 8 + 2] ^= 0x55; /* inside the zlib stream: Adler-32 or worse */
	assert_int_equal(mvod_png_grey_decode(p, png, n, out, W), -EINVAL);
	mvod_png_destroy(p);
}

/* A grey PNG through the image decoder gives the exact pixels, as one grey plane. */
static void test_imgdec(void **state)
{
	(void)state;
	uint8_t png[CAP];
	size_t n = make_png(png, 0);
	struct mvod_imgdec *d;
	struct mvod_image img;
	assert_int_equal(mvod_imgdec_create(&d), 0);
	for (int round = 0; round < 2; round++) { /* the second into the kept buffer */
		assert_int_equal(mvod_imgdec_decode(d, png, n, &img), 0);
		assert_int_equal(img.fmt, MVOD_PIX_GREY);
		assert_int_equal(img.w, W);
		assert_int_equal(img.h, H);
		for (int y = 0; y < H; y++)
			assert_memory_equal(img.data + (size_t)y * (size_t)img.stride, pixels[y], W);
	}
	mvod_imgdec_destroy(d);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test_setup(test_filters_exact, fill),
		cmocka_unit_test_setup(test_malformed, fill),
		cmocka_unit_test_setup(test_imgdec, fill),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
