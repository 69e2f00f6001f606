/*
 * The Hamming distance of ORB descriptors (vo/match.h), the inner loop of matching, against a
 * bit-by-bit count: on every architecture mvod builds for, whatever popcount the compiler picks
 * (popcnt or the baseline on x86-64, NEON cnt on arm64). make cross-arm64 runs it under qemu.
 * Needs nothing but the header, so it builds where OpenCV and LCM are not installed.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "vo/core/hamming.h"
#include "vo/frontend/match.h"

/* xorshift64: the same descriptors on every machine. */
static uint64_t next_word(uint64_t *s)
{
	*s ^= *s << 13;
	*s ^= *s >> 7;
	*s ^= *s << 17;
	return *s;
}

static int bits_differing(const uint8_t *a, const uint8_t *b, int bytes)
{
	int n = 0;
	for (int i = 0; i < bytes * 8; i++)
		n += ((a[i / 8] >> (i % 8)) & 1) != ((b[i / 8] >> (i % 8)) & 1);
	return n;
}

static void test_random_pairs(void **state)
{
	(void)state;
	uint64_t seed = 0x9e3779b97f4a7c15u;
	for (int k = 0; k < 2000; k++) {
		uint64_t x[4], y[4];
		for (int w = 0; w < 4; w++) {
			x[w] = next_word(&seed);
			/* Equal, complementary and unrelated words: distances 0, 256 and around 128. */
			y[w] = k % 5 == 0 ? x[w] : k % 7 == 0 ? ~x[w] : next_word(&seed);
		}
		int want = bits_differing((const uint8_t *)x, (const uint8_t *)y, 32);
		assert_int_equal(mvod_hamming_words(x, y), want);
		assert_int_equal(mvod_hamming256((const uint8_t *)x, (const uint8_t *)y), want);
	}
}

/* The extremes, and descriptors at an odd address (matching by projection reads those). */
static void test_edges(void **state)
{
	(void)state;
	uint64_t zero[4] = {0}, ones[4] = {~0ull, ~0ull, ~0ull, ~0ull}, one[4] = {0, 0, 0, 1ull << 63};
	assert_int_equal(mvod_hamming_words(zero, zero), 0);
	assert_int_equal(mvod_hamming_words(zero, ones), 256);
	assert_int_equal(mvod_hamming_words(zero, one), 1);
	uint8_t buf[2 * 32 + 1];
	for (int i = 0; i < (int)sizeof(buf); i++)
		buf[i] = (uint8_t)(i * 37 + 11);
	assert_int_equal(mvod_hamming256(buf + 1, buf + 33), bits_differing(buf + 1, buf + 33, 32));
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_random_pairs),
		cmocka_unit_test(test_edges),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
