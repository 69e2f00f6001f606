/*
 * The pixel kernels of util/kernels.h: the vector path this build compiled (SSE2 on x86-64, NEON
 * on arm64, plain C elsewhere) gives exactly what the plain C gives, on random, binary and ramp
 * images, and the plain C gives the values worked out by hand. Needs only the C library and
 * cmocka, so make cross-arm64 builds it for arm64 and runs it under qemu (the NEON path).
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "util/kernels.h"

/* xorshift64: the same images on every machine. */
static uint64_t next_word(uint64_t *s)
{
	*s ^= *s << 13;
	*s ^= *s >> 7;
	*s ^= *s << 17;
	return *s;
}

enum { W = 64, H = 32 };

/*
 * Every window position an image allows (4 pixels from the edges, as klt.c's inside()), each
 * image filled by fill(): the vector score must equal the plain one bit for bit.
 */
static void compare_all_windows(uint8_t img[H][W])
{
	for (int y = 4; y <= H - 5; y++)
		for (int x = 4; x <= W - 5; x++) {
			float v = mvod_harris7(&img[y][x], W), p = mvod_harris7_plain(&img[y][x], W);
			if (memcmp(&v, &p, sizeof v))
				fail_msg("harris at (%d, %d): vector %.9g, plain %.9g", x, y, v, p);
		}
}

static void test_harris_vector_equals_plain(void **state)
{
	(void)state;
	static uint8_t img[H][W];
	uint64_t seed = 0x2545f4914f6cdd1du;
	for (int k = 0; k < 200; k++) {
		/* Random bytes: every difference from -255 to 255 turns up. */
		for (int y = 0; y < H; y++)
			for (int x = 0; x < W; x++)
				img[y][x] = (uint8_t)next_word(&seed);
		compare_all_windows(img);
		/* Binary 0/255: the largest products, the sums' worst case. */
		for (int y = 0; y < H; y++)
			for (int x = 0; x < W; x++)
				img[y][x] = next_word(&seed) & 1 ? 255 : 0;
		compare_all_windows(img);
	}
	/* Ramps in both directions and a saddle: structured sums of one sign or mixed. */
	for (int y = 0; y < H; y++)
		for (int x = 0; x < W; x++)
			img[y][x] = (uint8_t)(3 * x + 5 * y);
	compare_all_windows(img);
	for (int y = 0; y < H; y++)
		for (int x = 0; x < W; x++)
			img[y][x] = (uint8_t)((x - W / 2) * (y - H / 2) / 4 + 128);
	compare_all_windows(img);
}

/*
 * A vertical step from 0 to 255 between columns 31 and 32: the horizontal differences are 255
 * at columns 31 and 32 (two columns of seven rows in the window), the vertical ones 0, so
 * a = 14 * 255^2, b = c = 0 and the score is -0.04 a^2.
 */
static void test_harris_step_edge_by_hand(void **state)
{
	(void)state;
	static uint8_t img[H][W];
	for (int y = 0; y < H; y++)
		for (int x = 0; x < W; x++)
			img[y][x] = x >= 32 ? 255 : 0;
	float a = 14.0f * 255.0f * 255.0f;
	float want = 0.0f * 0.0f - 0.0f * 0.0f - 0.04f * (a + 0.0f) * (a + 0.0f);
	assert_true(mvod_harris7_plain(&img[16][32], W) == want);
	assert_true(mvod_harris7(&img[16][32], W) == want);
	/* Centred 4 columns away from the step, the window's differences are all zero. */
	assert_true(mvod_harris7_plain(&img[16][36], W) == 0.0f);
	assert_true(mvod_harris7(&img[16][36], W) == 0.0f);
	/* A checkerboard corner: both gradients, score above zero (a corner, not an edge). */
	for (int y = 0; y < H; y++)
		for (int x = 0; x < W; x++)
			img[y][x] = (x >= 32) == (y >= 16) ? 255 : 0;
	assert_true(mvod_harris7_plain(&img[16][32], W) > 0.0f);
}

static void test_png_sub_vector_equals_plain(void **state)
{
	(void)state;
	uint8_t s[300], v[300], p[300];
	uint64_t seed = 0x9e3779b97f4a7c15u;
	/* Every width from 1 to 299: no 16-byte block, one, several, and every remainder. */
	for (int k = 0; k < 20; k++)
		for (int w = 1; w < 300; w++) {
			for (int x = 0; x < w; x++)
				s[x] = (uint8_t)next_word(&seed);
			memset(v, 0xaa, sizeof v);
			memset(p, 0x55, sizeof p);
			mvod_png_sub(v, s, w);
			mvod_png_sub_plain(p, s, w);
			if (memcmp(v, p, (size_t)w))
				fail_msg("png sub, width %d: vector and plain differ", w);
			/* Nothing written past the row. */
			assert_int_equal(v[w], 0xaa);
		}
}

/* All ones: d[x] = x + 1 modulo 256, across blocks and past the wrap at 256. */
static void test_png_sub_by_hand(void **state)
{
	(void)state;
	uint8_t s[300], d[300];
	memset(s, 1, sizeof s);
	mvod_png_sub_plain(d, s, 300);
	for (int x = 0; x < 300; x++)
		assert_int_equal(d[x], (x + 1) % 256);
	mvod_png_sub(d, s, 300);
	for (int x = 0; x < 300; x++)
		assert_int_equal(d[x], (x + 1) % 256);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_harris_vector_equals_plain),
		cmocka_unit_test(test_harris_step_edge_by_hand),
		cmocka_unit_test(test_png_sub_vector_equals_plain),
		cmocka_unit_test(test_png_sub_by_hand),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
