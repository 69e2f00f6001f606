/* The Hamming matcher: nearest neighbours, the ratio test and the cross-check, exactly. */
#include <errno.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "vo/match.h"

#define CAP 8

struct set {
	struct mvod_keypoint kp[CAP];
	uint8_t desc[CAP * MVOD_ORB_DESC_BYTES];
	struct mvod_features f;
};

/* Descriptor i of a set: all zero except the first `ones` bits set. */
static void set_bits(struct set *s, int i, int ones)
{
	uint8_t *d = s->desc + i * MVOD_ORB_DESC_BYTES;
	memset(d, 0, MVOD_ORB_DESC_BYTES);
	for (int b = 0; b < ones; b++)
		d[b / 8] |= (uint8_t)(1u << (b % 8));
}

static void init(struct set *s, int n)
{
	memset(s, 0, sizeof(*s));
	s->f = (struct mvod_features){.n = n, .cap = CAP, .kp = s->kp, .desc = s->desc};
}

static void test_nearest_ratio_and_cross_check(void **state)
{
	(void)state;
	struct set a, b;
	init(&a, 3);
	init(&b, 3);
	/* Distances are differences in bit counts: a = {0, 100, 200}, b = {10, 95, 250}. */
	set_bits(&a, 0, 0);
	set_bits(&a, 1, 100);
	set_bits(&a, 2, 200);
	set_bits(&b, 0, 10);
	set_bits(&b, 1, 95);
	set_bits(&b, 2, 250);
	struct mvod_matcher *m;
	assert_int_equal(mvod_matcher_create(CAP, &m), 0);
	struct mvod_match out[CAP];
	int n = 0;
	/* No filters: every a gets its nearest b (a2 -> b2 at 50, b1 at 105). */
	assert_int_equal(mvod_match(m, &a.f, &b.f, 1.0, false, out, CAP, &n), 0);
	assert_int_equal(n, 3);
	assert_int_equal(out[0].b, 0);
	assert_int_equal(out[1].b, 1);
	assert_int_equal(out[2].b, 2);
	/* Ratio 0.45: a0 (10 vs 95) and a1 (5 vs 90) pass, a2 (50 vs 105) fails. */
	assert_int_equal(mvod_match(m, &a.f, &b.f, 0.45, false, out, CAP, &n), 0);
	assert_int_equal(n, 2);
	assert_int_equal(out[0].a, 0);
	assert_int_equal(out[1].a, 1);
	/* Cross-check: b2's nearest a is a2 (50), so a2 -> b2 is mutual; all three are. */
	assert_int_equal(mvod_match(m, &a.f, &b.f, 1.0, true, out, CAP, &n), 0);
	assert_int_equal(n, 3);
	/* Make a0 and a1 both prefer b1: only the mutual one (a1) survives the cross-check. */
	set_bits(&a, 0, 80);
	assert_int_equal(mvod_match(m, &a.f, &b.f, 1.0, true, out, CAP, &n), 0);
	assert_int_equal(n, 2);
	assert_int_equal(out[0].a, 1);
	assert_int_equal(out[0].b, 1);
	assert_int_equal(out[1].a, 2);
	/* The output cap is honoured. */
	assert_int_equal(mvod_match(m, &a.f, &b.f, 1.0, false, out, 1, &n), 0);
	assert_int_equal(n, 1);
	mvod_matcher_destroy(m);
}

static void test_limits(void **state)
{
	(void)state;
	struct set a, b;
	init(&a, CAP);
	init(&b, 1);
	struct mvod_matcher *m;
	assert_int_equal(mvod_matcher_create(4, &m), 0);
	struct mvod_match out[CAP];
	int n = 7;
	assert_int_equal(mvod_match(m, &a.f, &b.f, 1.0, false, out, CAP, &n), -EINVAL);
	a.f.n = 3;
	assert_int_equal(mvod_match(m, &a.f, &b.f, 1.0, false, out, CAP, &n), 0);
	assert_int_equal(n, 0); /* one feature cannot pass a ratio test: nothing to match */
	mvod_matcher_destroy(m);
	mvod_matcher_destroy(NULL);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_nearest_ratio_and_cross_check),
		cmocka_unit_test(test_limits),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
