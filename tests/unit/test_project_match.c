/* Matching by projection on synthetic keypoints and descriptors: right pairs, the radius by
 * octave, the ratio test, one point per keypoint, points out of view. */
#include <errno.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "scene.h"
#include "vo/map/project_match.h"

#define NKP 400
#define NPT 100

static struct mvod_map_kp kp[NKP];
static uint8_t kdesc[NKP * 32], pdesc[NPT * 32];
static double pos[NPT * 3];
static int match[NPT], dist[NPT];
static const double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, t0[3] = {0, 0, 0};
static const double K[4] = {SCENE_F, SCENE_F, SCENE_CX, SCENE_CY};

/* World point at depth z seen by the identity camera at pixel (u, v). */
static void point_at(double u, double v, double z, double X[3])
{
	X[0] = (u - SCENE_CX) / SCENE_F * z;
	X[1] = (v - SCENE_CY) / SCENE_F * z;
	X[2] = z;
}

/* Random keypoints and descriptors; point i (< NPT) sits 3 px from keypoint i with that
 * keypoint's descriptor with 10 bits flipped (a good ORB match is within ~50 bits). */
static void make_frame(uint32_t seed)
{
	uint32_t s = seed;
	for (int i = 0; i < NKP; i++) {
		kp[i] = (struct mvod_map_kp){(float)scene_uniform(&s, 10, SCENE_W - 10),
					   (float)scene_uniform(&s, 10, SCENE_H - 10), 1.0f, i % 4};
		for (int b = 0; b < 32; b++)
			kdesc[32 * i + b] = (uint8_t)scene_uniform(&s, 0, 256);
	}
	for (int i = 0; i < NPT; i++) {
		point_at(kp[i].x + 3, kp[i].y, scene_uniform(&s, 5, 50), pos + 3 * i);
		memcpy(pdesc + 32 * i, kdesc + 32 * i, 32);
		for (int b = 0; b < 10; b++)
			pdesc[32 * i + b] ^= 0x01;
	}
}

static struct mvod_pm *new_pm(void)
{
	struct mvod_pm_params p;
	mvod_pm_params_default(&p);
	struct mvod_pm *pm = NULL;
	assert_int_equal(mvod_pm_create(&p, SCENE_W, SCENE_H, NKP, &pm), 0);
	return pm;
}

static void test_finds_right_keypoints(void **state)
{
	(void)state;
	struct mvod_pm *pm = new_pm();
	make_frame(3);
	assert_int_equal(mvod_pm_set_frame(pm, kp, kdesc, NKP), 0);
	int n = mvod_pm_match(pm, I, t0, K, pos, pdesc, NPT, match, dist);
	assert_int_equal(n, NPT);
	for (int i = 0; i < NPT; i++) {
		assert_int_equal(match[i], i);
		assert_int_equal(dist[i], 10);
	}
	/* A camera turned away sees none of them. */
	double back[9] = {-1, 0, 0, 0, 1, 0, 0, 0, -1};
	assert_int_equal(mvod_pm_match(pm, back, t0, K, pos, pdesc, NPT, match, NULL), 0);
	for (int i = 0; i < NPT; i++)
		assert_int_equal(match[i], MVOD_PM_OUT_OF_VIEW);
	mvod_pm_destroy(pm);
}

/* One keypoint alone, octave o, and one point projected d pixels to its right. */
static int lone_match(struct mvod_pm *pm, int octave, double d)
{
	kp[0] = (struct mvod_map_kp){320, 240, 1.0f, octave};
	assert_int_equal(mvod_pm_set_frame(pm, kp, kdesc, 1), 0);
	point_at(320 + d, 240, 10, pos);
	memcpy(pdesc, kdesc, 32);
	mvod_pm_match(pm, I, t0, K, pos, pdesc, 1, match, NULL);
	return match[0];
}

static void test_radius_grows_with_octave(void **state)
{
	(void)state;
	struct mvod_pm *pm = new_pm();
	/* Default radius 15 px at octave 0, 15 x 1.2^3 = 25.9 px at octave 3. */
	assert_int_equal(lone_match(pm, 0, 14.5), 0);
	assert_int_equal(lone_match(pm, 0, 15.5), MVOD_PM_UNMATCHED);
	assert_int_equal(lone_match(pm, 3, 25.5), 0);
	assert_int_equal(lone_match(pm, 3, 26.5), MVOD_PM_UNMATCHED);
	/* Across a cell border (cells are 32 px): still found. */
	kp[0] = (struct mvod_map_kp){63, 240, 1.0f, 0};
	assert_int_equal(mvod_pm_set_frame(pm, kp, kdesc, 1), 0);
	point_at(70, 240, 10, pos);
	assert_int_equal(mvod_pm_match(pm, I, t0, K, pos, kdesc, 1, match, NULL), 1);
	mvod_pm_destroy(pm);
}

static void test_ratio_distance_and_uniqueness(void **state)
{
	(void)state;
	struct mvod_pm *pm = new_pm();
	/* Two keypoints side by side with descriptors 20 and 22 bits from the point's: the
	 * second best is not 0.8x worse, so the match is ambiguous and refused. */
	memset(kdesc, 0, 64);
	memset(pdesc, 0, 32);
	kdesc[0] = kdesc[1] = 0xff, kdesc[2] = 0x0f;               /* 20 bits */
	kdesc[32] = kdesc[33] = 0xff, kdesc[34] = 0x3f;            /* 22 bits */
	kp[0] = (struct mvod_map_kp){300, 200, 1.0f, 0};
	kp[1] = (struct mvod_map_kp){305, 200, 1.0f, 0};
	assert_int_equal(mvod_pm_set_frame(pm, kp, kdesc, 2), 0);
	point_at(302, 200, 10, pos);
	assert_int_equal(mvod_pm_match(pm, I, t0, K, pos, pdesc, 1, match, NULL), 0);
	assert_int_equal(match[0], MVOD_PM_UNMATCHED);
	/* With the second keypoint 60 bits away the first is clear. */
	memset(kdesc + 32, 0xff, 8);
	assert_int_equal(mvod_pm_match(pm, I, t0, K, pos, pdesc, 1, match, NULL), 1);
	assert_int_equal(match[0], 0);
	/* Over max_dist (100 bits) nothing is a match, however alone. */
	memset(kdesc, 0xff, 14); /* 112 bits */
	assert_int_equal(mvod_pm_set_frame(pm, kp, kdesc, 1), 0);
	assert_int_equal(mvod_pm_match(pm, I, t0, K, pos, pdesc, 1, match, NULL), 0);
	/* Two points wanting the same keypoint: the closer descriptor keeps it. */
	memset(kdesc, 0, 32);
	memset(pdesc, 0, 64);
	pdesc[0] = 0x07;  /* point 0: 3 bits */
	pdesc[32] = 0x01; /* point 1: 1 bit */
	point_at(300, 200, 10, pos);
	point_at(301, 200, 20, pos + 3);
	assert_int_equal(mvod_pm_match(pm, I, t0, K, pos, pdesc, 2, match, dist), 1);
	assert_int_equal(match[0], MVOD_PM_UNMATCHED);
	assert_int_equal(match[1], 0);
	assert_int_equal(dist[1], 1);
	/* And whichever comes first: the closer one first keeps it against a later one. */
	pdesc[0] = 0x01;
	pdesc[32] = 0x07;
	assert_int_equal(mvod_pm_match(pm, I, t0, K, pos, pdesc, 2, match, dist), 1);
	assert_int_equal(match[0], 0);
	assert_int_equal(match[1], MVOD_PM_UNMATCHED);
	mvod_pm_destroy(pm);
}

static void test_bad_input(void **state)
{
	(void)state;
	struct mvod_pm *pm = new_pm();
	kp[0].octave = 8; /* above max_octave 7 */
	assert_int_equal(mvod_pm_set_frame(pm, kp, kdesc, 1), -EINVAL);
	assert_int_equal(mvod_pm_set_frame(pm, kp, kdesc, NKP + 1), -EINVAL);
	mvod_pm_destroy(pm);
	mvod_pm_destroy(NULL);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_finds_right_keypoints),
		cmocka_unit_test(test_radius_grows_with_octave),
		cmocka_unit_test(test_ratio_distance_and_uniqueness),
		cmocka_unit_test(test_bad_input),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
