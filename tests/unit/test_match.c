/*
 * The matchers: nearest neighbours, the ratio test, the cross-check and the best-N cut, exactly,
 * on mvod's Hamming table (ORB) and on OpenCV's L2 brute force and FLANN (SIFT-sized floats).
 */
#include <errno.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "vo/frontend/match.h"

#define CAP 8

struct set {
	struct mvod_keypoint kp[CAP];
	uint8_t desc[CAP * MVOD_SIFT_DESC_BYTES];
	struct mvod_features f;
};

/* ORB descriptor i of a set: all zero except the first `ones` bits set. */
static void set_bits(struct set *s, int i, int ones)
{
	uint8_t *d = s->desc + i * MVOD_ORB_DESC_BYTES;
	memset(d, 0, MVOD_ORB_DESC_BYTES);
	for (int b = 0; b < ones; b++)
		d[b / 8] |= (uint8_t)(1u << (b % 8));
}

/* SIFT descriptor i of a set: v in the first of its 128 floats, zero elsewhere. */
static void set_float(struct set *s, int i, float v)
{
	float d[128] = {0};
	d[0] = v;
	memcpy(s->desc + i * MVOD_SIFT_DESC_BYTES, d, sizeof(d));
}

static void init(struct set *s, int n, int desc_bytes)
{
	memset(s, 0, sizeof(*s));
	s->f = (struct mvod_features){
		.n = n, .cap = CAP, .desc_bytes = desc_bytes, .kp = s->kp, .desc = s->desc};
}

/* Matches a to b with a fresh matcher of the given kind; returns the count. */
static int match(enum mvod_matcher_kind kind, enum mvod_detector det, double ratio, int best_n,
		 const struct set *a, const struct set *b, struct mvod_match *out, int cap)
{
	struct mvod_match_params p = {kind, det, ratio, best_n};
	struct mvod_matcher *m;
	assert_int_equal(mvod_matcher_create(&p, CAP, &m), 0);
	int n = -1;
	assert_int_equal(mvod_match(m, &a->f, &b->f, out, cap, &n), 0);
	mvod_matcher_destroy(m);
	return n;
}

/* Distances are differences in bit counts: a = {0, 100, 200}, b = {10, 95, 250}. */
static void orb_sets(struct set *a, struct set *b)
{
	init(a, 3, MVOD_ORB_DESC_BYTES);
	init(b, 3, MVOD_ORB_DESC_BYTES);
	set_bits(a, 0, 0);
	set_bits(a, 1, 100);
	set_bits(a, 2, 200);
	set_bits(b, 0, 10);
	set_bits(b, 1, 95);
	set_bits(b, 2, 250);
}

static void test_nearest_ratio_and_cross_check(void **state)
{
	(void)state;
	struct set a, b;
	orb_sets(&a, &b);
	struct mvod_match out[CAP];
	const enum mvod_detector orb = MVOD_DETECTOR_ORB;
	/* No filter: every a gets its nearest b (a2 -> b2 at 50, b1 at 105). */
	assert_int_equal(match(MVOD_MATCHER_BF_RATIO, orb, 1.0, 0, &a, &b, out, CAP), 3);
	assert_int_equal(out[0].b, 0);
	assert_int_equal(out[1].b, 1);
	assert_int_equal(out[2].b, 2);
	assert_true(out[2].dist == 50);
	/* Ratio 0.45: a0 (10 vs 95) and a1 (5 vs 90) pass, a2 (50 vs 105) fails. */
	assert_int_equal(match(MVOD_MATCHER_BF_RATIO, orb, 0.45, 0, &a, &b, out, CAP), 2);
	assert_int_equal(out[0].a, 0);
	assert_int_equal(out[1].a, 1);
	/* Cross-check: b2's nearest a is a2 (50), so a2 -> b2 is mutual; all three are. */
	assert_int_equal(match(MVOD_MATCHER_BF, orb, 1.0, 0, &a, &b, out, CAP), 3);
	/* Make a0 and a1 both prefer b1: only the mutual one (a1) survives the cross-check. */
	set_bits(&a, 0, 80);
	assert_int_equal(match(MVOD_MATCHER_BF, orb, 1.0, 0, &a, &b, out, CAP), 2);
	assert_int_equal(out[0].a, 1);
	assert_int_equal(out[0].b, 1);
	assert_int_equal(out[1].a, 2);
	/* Both filters: a1 (5 vs 90) passes 0.45 and is mutual; a2 fails the ratio. */
	assert_int_equal(match(MVOD_MATCHER_BF, orb, 0.45, 0, &a, &b, out, CAP), 1);
	assert_int_equal(out[0].a, 1);
	/* The output cap is honoured. */
	assert_int_equal(match(MVOD_MATCHER_BF_RATIO, orb, 1.0, 0, &a, &b, out, 1), 1);
}

static void test_best_n_keeps_the_closest(void **state)
{
	(void)state;
	struct set a, b;
	init(&a, 6, MVOD_ORB_DESC_BYTES);
	init(&b, 6, MVOD_ORB_DESC_BYTES);
	/* Pairs i <-> i at distances 18, 5, 14, 0, 9, 3: under half the 40-bit spacing, mutual. */
	const int off[6] = {18, 5, 14, 0, 9, 3};
	for (int i = 0; i < 6; i++) {
		set_bits(&a, i, 40 * i);
		set_bits(&b, i, 40 * i + off[i]);
	}
	struct mvod_match out[CAP];
	/* The ratio is ignored by bf-cross: 0.1 would reject every pair here. */
	assert_int_equal(match(MVOD_MATCHER_BF_CROSS, MVOD_DETECTOR_ORB, 0.1, 3, &a, &b, out, CAP),
			 3);
	int seen = 0;
	for (int k = 0; k < 3; k++) {
		assert_int_equal(out[k].a, out[k].b);
		seen |= 1 << out[k].a;
	}
	/* The three closest: pairs 3 (0 bits), 5 (3) and 1 (5). */
	assert_int_equal(seen, (1 << 3) | (1 << 5) | (1 << 1));
	/* 0 keeps every mutual pair. */
	assert_int_equal(match(MVOD_MATCHER_BF_CROSS, MVOD_DETECTOR_ORB, 1, 0, &a, &b, out, CAP), 6);
}

/* SIFT-sized float descriptors through OpenCV: brute-force L2 and the kd-tree FLANN. */
static void test_float_descriptors(void **state)
{
	(void)state;
	struct set a, b;
	init(&a, 3, MVOD_SIFT_DESC_BYTES);
	init(&b, 3, MVOD_SIFT_DESC_BYTES);
	/* The ORB case in one dimension: a = {0, 100, 200}, b = {10, 95, 250}. */
	const float va[3] = {0, 100, 200}, vb[3] = {10, 95, 250};
	for (int i = 0; i < 3; i++) {
		set_float(&a, i, va[i]);
		set_float(&b, i, vb[i]);
	}
	struct mvod_match out[CAP];
	const enum mvod_detector sift = MVOD_DETECTOR_SIFT;
	assert_int_equal(match(MVOD_MATCHER_BF_RATIO, sift, 0.45, 0, &a, &b, out, CAP), 2);
	assert_int_equal(out[1].a, 1);
	assert_int_equal(out[1].b, 1);
	assert_true(out[1].dist == 5);
	assert_int_equal(match(MVOD_MATCHER_BF, sift, 1.0, 0, &a, &b, out, CAP), 3);
	/* Three points are few enough for the kd-trees to find the exact neighbours. */
	assert_int_equal(match(MVOD_MATCHER_FLANN_RATIO, sift, 0.45, 0, &a, &b, out, CAP), 2);
	assert_int_equal(match(MVOD_MATCHER_FLANN, sift, 0.45, 0, &a, &b, out, CAP), 3);
	assert_int_equal(out[2].b, 2);
}

static void test_limits(void **state)
{
	(void)state;
	struct set a, b;
	init(&a, CAP, MVOD_ORB_DESC_BYTES);
	init(&b, 1, MVOD_ORB_DESC_BYTES);
	struct mvod_match_params p = {MVOD_MATCHER_BF_RATIO, MVOD_DETECTOR_ORB, 1.0, 0};
	struct mvod_matcher *m;
	assert_int_equal(mvod_matcher_create(&p, 4, &m), 0);
	struct mvod_match out[CAP];
	int n = 7;
	assert_int_equal(mvod_match(m, &a.f, &b.f, out, CAP, &n), -EINVAL);
	a.f.n = 3;
	assert_int_equal(mvod_match(m, &a.f, &b.f, out, CAP, &n), 0);
	assert_int_equal(n, 0); /* one feature cannot pass a ratio test: nothing to match */
	/* SIFT descriptors handed to an ORB matcher are refused, not misread. */
	init(&b, 3, MVOD_SIFT_DESC_BYTES);
	assert_int_equal(mvod_match(m, &a.f, &b.f, out, CAP, &n), -EINVAL);
	mvod_matcher_destroy(m);
	mvod_matcher_destroy(NULL);
	p.kind = MVOD_MATCHER_COUNT;
	assert_int_equal(mvod_matcher_create(&p, 4, &m), -EINVAL);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_nearest_ratio_and_cross_check),
		cmocka_unit_test(test_best_n_keeps_the_closest),
		cmocka_unit_test(test_float_descriptors),
		cmocka_unit_test(test_limits),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
