/* The local map: ids and stale ids, observations on both sides, culling, eviction, capacity. */
#include <errno.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "vo/map/map.h"

#define KP 16

static struct mvod_map_kp kps[KP];
static uint8_t descs[KP * MVOD_MAP_DESC_BYTES];

static struct mvod_map *new_map(int kf_cap, int point_cap)
{
	struct mvod_map_params p;
	mvod_map_params_default(&p);
	p.kf_cap = kf_cap;
	p.kp_cap = KP;
	p.point_cap = point_cap;
	struct mvod_map *m = NULL;
	assert_int_equal(mvod_map_create(&m, &p), 0);
	return m;
}

static mvod_map_id add_kf(struct mvod_map *m, struct mvod_map_stats *st)
{
	struct mvod_map_kf_in in = {.utime = 1000, .Rcw = {1, 0, 0, 0, 1, 0, 0, 0, 1}, .n = KP,
				    .kp = kps, .desc = descs};
	for (int k = 0; k < KP; k++)
		kps[k] = (struct mvod_map_kp){(float)k, (float)(2 * k), 1.0f, k % 4};
	mvod_map_id id = MVOD_MAP_NONE;
	assert_int_equal(mvod_map_add_keyframe(m, &in, &id, st), 0);
	assert_true(id != MVOD_MAP_NONE);
	return id;
}

static mvod_map_id add_pt(struct mvod_map *m, mvod_map_id kf)
{
	static const double pos[3] = {1, 2, 3};
	static const uint8_t d[MVOD_MAP_DESC_BYTES] = {0xab};
	mvod_map_id id = MVOD_MAP_NONE;
	assert_int_equal(mvod_map_add_point(m, pos, d, kf, &id), 0);
	return id;
}

static void test_bad_params(void **state)
{
	(void)state;
	struct mvod_map_params p;
	mvod_map_params_default(&p);
	p.kf_cap = 1; /* a window of one keyframe has no baseline */
	struct mvod_map *m = (struct mvod_map *)1;
	assert_int_equal(mvod_map_create(&m, &p), -EINVAL);
	assert_null(m);
	mvod_map_destroy(NULL);
}

static void test_ids_and_stale_ids(void **state)
{
	(void)state;
	struct mvod_map *m = new_map(3, 2);
	mvod_map_id kf = add_kf(m, NULL);
	mvod_map_id a = add_pt(m, kf), b = add_pt(m, kf);
	assert_true(a != b);
	assert_non_null(mvod_map_point(m, a));
	assert_true(mvod_map_point(m, a)->id == a);
	assert_null(mvod_map_point(m, MVOD_MAP_NONE));
	assert_int_equal(mvod_map_erase_point(m, a), 0);
	assert_null(mvod_map_point(m, a));
	/* The freed slot is reused: same slot, new generation, so the old id stays stale. */
	mvod_map_id c = add_pt(m, kf);
	assert_true((c & 0xffffffffu) == (a & 0xffffffffu));
	assert_true(c != a);
	assert_null(mvod_map_point(m, a));
	assert_non_null(mvod_map_point(m, c));
	assert_int_equal(mvod_map_erase_point(m, a), -ENOENT);
	assert_int_equal(mvod_map_add_obs(m, a, kf, 0), -ENOENT);
	assert_int_equal(mvod_map_check(m), 0);
	mvod_map_destroy(m);
}

static void test_capacity_full(void **state)
{
	(void)state;
	struct mvod_map *m = new_map(2, 3);
	mvod_map_id kf = add_kf(m, NULL), ids[4];
	for (int i = 0; i < 3; i++)
		ids[i] = add_pt(m, kf);
	const double pos[3] = {0};
	const uint8_t d[MVOD_MAP_DESC_BYTES] = {0};
	ids[3] = 77;
	assert_int_equal(mvod_map_add_point(m, pos, d, kf, &ids[3]), -ENOSPC);
	assert_true(ids[3] == 77); /* nothing written, nothing changed */
	assert_int_equal(mvod_map_n_points(m), 3);
	assert_int_equal(mvod_map_points(m, ids, 4), 3);
	assert_int_equal(mvod_map_check(m), 0);
	/* Too many keypoints for a keyframe is the caller's error. */
	struct mvod_map_kf_in in = {.n = KP + 1, .kp = kps, .desc = descs};
	mvod_map_id k2;
	assert_int_equal(mvod_map_add_keyframe(m, &in, &k2, NULL), -EINVAL);
	assert_int_equal(mvod_map_n_keyframes(m), 1);
	mvod_map_destroy(m);
}

static void test_observations(void **state)
{
	(void)state;
	struct mvod_map *m = new_map(3, 8);
	mvod_map_id k1 = add_kf(m, NULL), k2 = add_kf(m, NULL);
	mvod_map_id a = add_pt(m, k1), b = add_pt(m, k1);
	assert_int_equal(mvod_map_add_obs(m, a, k1, 3), 0);
	assert_int_equal(mvod_map_add_obs(m, a, k2, 5), 0);
	assert_int_equal(mvod_map_add_obs(m, b, k1, 3), -EEXIST); /* keypoint taken */
	assert_int_equal(mvod_map_add_obs(m, a, k1, 4), -EEXIST); /* k1 already sees a */
	assert_int_equal(mvod_map_add_obs(m, b, k1, KP), -EINVAL);
	assert_int_equal(mvod_map_add_obs(m, b, k1, 4), 0);
	assert_int_equal(mvod_map_add_obs(m, b, k2, 6), 0);
	assert_true(mvod_map_keyframe(m, k1)->pt[3] == a);
	assert_int_equal(mvod_map_point(m, a)->n_obs, 2);
	assert_int_equal(mvod_map_check(m), 0);
	assert_int_equal(mvod_map_remove_obs(m, a, k1), 0);
	assert_true(mvod_map_keyframe(m, k1)->pt[3] == MVOD_MAP_NONE);
	assert_int_equal(mvod_map_remove_obs(m, a, k1), -ENOENT);
	assert_int_equal(mvod_map_check(m), 0);
	/* Fuse b into a: a already has k2 (keypoint 5), so b's k2 keypoint 6 is freed. */
	assert_int_equal(mvod_map_count(m, a, 4, 3), 0);
	assert_int_equal(mvod_map_count(m, b, 2, 1), 0);
	assert_int_equal(mvod_map_fuse(m, a, b), 0);
	assert_null(mvod_map_point(m, b));
	const struct mvod_map_point *pa = mvod_map_point(m, a);
	assert_int_equal(pa->n_obs, 2);
	assert_int_equal(pa->visible, 6);
	assert_int_equal(pa->found, 4);
	assert_true(mvod_map_keyframe(m, k1)->pt[4] == a);
	assert_true(mvod_map_keyframe(m, k2)->pt[6] == MVOD_MAP_NONE);
	assert_int_equal(mvod_map_fuse(m, a, a), -EINVAL);
	assert_int_equal(mvod_map_check(m), 0);
	/* Erasing a point frees its keypoints in every keyframe. */
	assert_int_equal(mvod_map_erase_point(m, a), 0);
	assert_true(mvod_map_keyframe(m, k2)->pt[5] == MVOD_MAP_NONE);
	assert_int_equal(mvod_map_check(m), 0);
	mvod_map_destroy(m);
}

/* The checker itself must notice a broken map, or the tests above prove nothing. */
static void test_checker_notices(void **state)
{
	(void)state;
	struct mvod_map *m = new_map(2, 4);
	mvod_map_id k1 = add_kf(m, NULL), a = add_pt(m, k1);
	assert_int_equal(mvod_map_add_obs(m, a, k1, 2), 0);
	struct mvod_map_keyframe *k = (struct mvod_map_keyframe *)mvod_map_keyframe(m, k1);
	k->pt[2] = MVOD_MAP_NONE; /* one side only */
	assert_int_equal(mvod_map_check(m), -EUCLEAN);
	k->pt[2] = a;
	assert_int_equal(mvod_map_check(m), 0);
	k->pt[7] = a; /* a keypoint naming a point that does not list it */
	assert_int_equal(mvod_map_check(m), -EUCLEAN);
	mvod_map_destroy(m);
}

static void test_eviction(void **state)
{
	(void)state;
	struct mvod_map *m = new_map(3, 8);
	mvod_map_id k[4];
	struct mvod_map_stats st;
	for (int i = 0; i < 3; i++)
		k[i] = add_kf(m, &st);
	assert_int_equal(st.evicted_kf, 0);
	/* a: seen by k0 and k1 (left with one after k0 leaves: erased);
	 * b: seen by k0, k1, k2 (keeps two: survives); c: k1 and k2 only (untouched). */
	mvod_map_id a = add_pt(m, k[0]), b = add_pt(m, k[0]), c = add_pt(m, k[1]);
	assert_int_equal(mvod_map_add_obs(m, a, k[0], 0), 0);
	assert_int_equal(mvod_map_add_obs(m, a, k[1], 0), 0);
	for (int i = 0; i < 3; i++)
		assert_int_equal(mvod_map_add_obs(m, b, k[i], 1), 0);
	assert_int_equal(mvod_map_add_obs(m, c, k[1], 2), 0);
	assert_int_equal(mvod_map_add_obs(m, c, k[2], 2), 0);
	k[3] = add_kf(m, &st);
	assert_int_equal(st.evicted_kf, 1);
	assert_int_equal(st.erased_points, 1);
	assert_null(mvod_map_keyframe(m, k[0]));
	assert_null(mvod_map_point(m, a));
	assert_true(mvod_map_keyframe(m, k[1])->pt[0] == MVOD_MAP_NONE);
	assert_int_equal(mvod_map_point(m, b)->n_obs, 2);
	assert_int_equal(mvod_map_point(m, c)->n_obs, 2);
	/* The ring reuses k0's slot for k3 under a new generation; oldest first is k1, k2, k3. */
	assert_true((k[3] & 0xffffffffu) == (k[0] & 0xffffffffu));
	mvod_map_id ids[3];
	assert_int_equal(mvod_map_keyframes(m, ids, 3), 3);
	assert_true(ids[0] == k[1] && ids[1] == k[2] && ids[2] == k[3]);
	assert_int_equal(mvod_map_keyframe(m, k[3])->seq, 3);
	assert_int_equal(mvod_map_check(m), 0);
	mvod_map_destroy(m);
}

static void test_culling(void **state)
{
	(void)state;
	struct mvod_map *m = new_map(5, 8);
	mvod_map_id k0 = add_kf(m, NULL), k1 = add_kf(m, NULL);
	/* rare: found 1 of 5 times predicted (ratio 0.2 < 0.25); often: 2 of 5 (0.4). */
	mvod_map_id rare = add_pt(m, k0), often = add_pt(m, k0), young = add_pt(m, k1);
	assert_int_equal(mvod_map_count(m, rare, 5, 1), 0);
	assert_int_equal(mvod_map_count(m, often, 5, 2), 0);
	struct mvod_map_stats st;
	assert_int_equal(mvod_map_cull(m, &st), 0);
	assert_int_equal(st.erased_points, 1);
	assert_null(mvod_map_point(m, rare));
	/* Two keyframes after creation a point needs 3 observations; often has 2, young has 0
	 * but is only one keyframe old. */
	mvod_map_id k2 = add_kf(m, NULL);
	assert_int_equal(mvod_map_add_obs(m, often, k0, 0), 0);
	assert_int_equal(mvod_map_add_obs(m, often, k1, 0), 0);
	assert_int_equal(mvod_map_cull(m, &st), 0);
	assert_int_equal(st.erased_points, 1);
	assert_null(mvod_map_point(m, often));
	assert_non_null(mvod_map_point(m, young));
	/* Out of probation (3 keyframes old) a point is kept whatever its counts. */
	mvod_map_id old = add_pt(m, k0);
	assert_int_equal(mvod_map_count(m, old, 100, 0), 0);
	assert_int_equal(mvod_map_add_obs(m, old, k2, 1), 0);
	add_kf(m, NULL);
	assert_int_equal(mvod_map_cull(m, &st), 0);
	assert_non_null(mvod_map_point(m, old));
	assert_null(mvod_map_point(m, young)); /* 2 keyframes old now, 0 observations */
	assert_int_equal(mvod_map_check(m), 0);
	mvod_map_destroy(m);
}

static void test_representative_descriptor(void **state)
{
	(void)state;
	struct mvod_map *m = new_map(4, 8);
	/* Keypoint 0 of three keyframes: A, A with one bit flipped, and B far from both. */
	mvod_map_id k[3];
	for (int i = 0; i < 3; i++) {
		memset(descs, i == 2 ? 0xff : 0x00, MVOD_MAP_DESC_BYTES);
		descs[0] = i == 1 ? 0x01 : descs[0];
		k[i] = add_kf(m, NULL);
	}
	mvod_map_id a = add_pt(m, k[0]);
	for (int i = 2; i >= 0; i--) /* B first, so the choice is not the first observation */
		assert_int_equal(mvod_map_add_obs(m, a, k[i], 0), 0);
	assert_int_equal(mvod_map_update_desc(m, a), 0);
	/* Medians: A 1, A' 1, B 255: one of the A pair (the first of them in the list, A'). */
	const uint8_t *d = mvod_map_point(m, a)->desc;
	assert_int_equal(d[0], 0x01);
	for (int b = 1; b < MVOD_MAP_DESC_BYTES; b++)
		assert_int_equal(d[b], 0);
	memset(descs, 0, sizeof(descs));
	mvod_map_destroy(m);
}

/*
 * Reset (map mode's loss of tracking): every keyframe and point leaves, even points with many
 * observations that eviction alone would keep; old ids are stale; the pools are whole again.
 */
static void test_reset(void **state)
{
	(void)state;
	struct mvod_map *m = new_map(3, 4);
	mvod_map_id a = add_kf(m, NULL), b = add_kf(m, NULL);
	mvod_map_id p = add_pt(m, a), q = add_pt(m, b);
	assert_int_equal(mvod_map_add_obs(m, p, a, 0), 0);
	assert_int_equal(mvod_map_add_obs(m, p, b, 0), 0);
	mvod_map_reset(m);
	assert_int_equal(mvod_map_check(m), 0);
	assert_int_equal(mvod_map_n_keyframes(m), 0);
	assert_int_equal(mvod_map_n_points(m), 0);
	assert_null(mvod_map_keyframe(m, a));
	assert_null(mvod_map_point(m, p));
	assert_null(mvod_map_point(m, q));
	/* All four point slots are free again, and the ring takes three keyframes. */
	mvod_map_id k = add_kf(m, NULL);
	for (int i = 0; i < 4; i++)
		add_pt(m, k);
	add_kf(m, NULL);
	add_kf(m, NULL);
	assert_int_equal(mvod_map_n_keyframes(m), 3);
	assert_int_equal(mvod_map_check(m), 0);
	mvod_map_destroy(m);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_bad_params),
		cmocka_unit_test(test_ids_and_stale_ids),
		cmocka_unit_test(test_capacity_full),
		cmocka_unit_test(test_observations),
		cmocka_unit_test(test_checker_notices),
		cmocka_unit_test(test_eviction),
		cmocka_unit_test(test_culling),
		cmocka_unit_test(test_representative_descriptor),
		cmocka_unit_test(test_reset),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
