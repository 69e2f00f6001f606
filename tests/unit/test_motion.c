/* Essential matrix, its decomposition, cheirality and relative scale on exact synthetic data. */
#include <errno.h>
#include <stdbool.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "mvod/geom.h"
#include "vo/geom/essential_shim.h"
#include "vo/geom/motion.h"
#include "util/linalg.h"

#define N 200

/* Deterministic points in front of camera 1, seen by camera 2 at X2 = R X1 + t. */
static void scene(const double R[9], const double t[3], double *X, double *x1, double *x2)
{
	unsigned s = 12345;
	for (int i = 0; i < N; i++) {
		double *P = X + 3 * i;
		s = s * 1103515245u + 12345u;
		P[0] = ((s >> 8) % 2000) / 100.0 - 10;
		s = s * 1103515245u + 12345u;
		P[1] = ((s >> 8) % 1000) / 100.0 - 5;
		s = s * 1103515245u + 12345u;
		P[2] = 5 + ((s >> 8) % 2500) / 100.0;
		double Q[3];
		mvod_mat3_vec(R, P, Q);
		for (int k = 0; k < 3; k++)
			Q[k] += t[k];
		x1[2 * i] = P[0] / P[2];
		x1[2 * i + 1] = P[1] / P[2];
		x2[2 * i] = Q[0] / Q[2];
		x2[2 * i + 1] = Q[1] / Q[2];
	}
}

static void motion(double R[9], double t[3])
{
	double w[3] = {0.02, -0.15, 0.01};
	mvod_rot_exp(w, R);
	t[0] = 0.2;
	t[1] = -0.05;
	t[2] = -0.97;
	double n = mvod_vec3_norm(t);
	for (int k = 0; k < 3; k++)
		t[k] /= n;
}

static void test_decompose_and_cheirality(void **state)
{
	(void)state;
	double R[9], t[3], X[3 * N], x1[2 * N], x2[2 * N];
	motion(R, t);
	scene(R, t, X, x1, x2);
	/* E = [t]x R exactly; the decomposition loses the sign of t and the twisted pair. */
	double tx[9] = {0, -t[2], t[1], t[2], 0, -t[0], -t[1], t[0], 0}, E[9];
	mvod_mat3_mul(tx, R, E);
	double R1[9], R2[9], tu[3], Rb[9], tb[3], depth[N];
	assert_int_equal(mvod_essential_decompose(E, R1, R2, tu), 0);
	uint8_t mask[N];
	memset(mask, 1, sizeof(mask));
	int runner_up = -1;
	int front = mvod_motion_cheirality(R1, R2, tu, x1, x2, mask, N, Rb, tb, depth, &runner_up);
	assert_int_equal(front, N);
	/* Exact data: every other candidate puts some point behind a camera. */
	assert_true(runner_up < N);
	for (int k = 0; k < 9; k++)
		assert_true(fabs(Rb[k] - R[k]) < 1e-9);
	for (int k = 0; k < 3; k++)
		assert_true(fabs(tb[k] - t[k]) < 1e-9);
	/* Depths along ray 1 are the true z with |t| = 1. */
	for (int i = 0; i < N; i++)
		assert_true(fabs(depth[i] - X[3 * i + 2]) < 1e-6 * X[3 * i + 2]);
}

/* The motion and scene above, every fifth correspondence garbage. */
static void scene_with_outliers(double R[9], double t[3], double *X, double *x1, double *x2)
{
	motion(R, t);
	scene(R, t, X, x1, x2);
	for (int i = 0; i < N; i += 5) {
		x2[2 * i] += 0.05 * ((i % 3) - 1) + 0.03;
		x2[2 * i + 1] -= 0.04;
	}
}

static void robust_with_outliers(bool magsac)
{
	double R[9], t[3], X[3 * N], x1[2 * N], x2[2 * N];
	scene_with_outliers(R, t, X, x1, x2);
	double E[9], R1[9], R2[9], tu[3], Rb[9], tb[3];
	uint8_t mask[N];
	int inl = 0;
	/* Normalised coordinates, 1 px at f = 500. */
	assert_int_equal(mvod_essential_find(x1, x2, N, magsac, 1.0 / 500, 0.999, E, mask, &inl), 0);
	assert_int_equal(inl, N - N / 5);
	for (int i = 0; i < N; i += 5)
		assert_int_equal(mask[i], 0);
	assert_int_equal(mvod_essential_decompose(E, R1, R2, tu), 0);
	int front = mvod_motion_cheirality(R1, R2, tu, x1, x2, mask, N, Rb, tb, NULL, NULL);
	assert_int_equal(front, inl);
	double dR[9];
	mvod_mat3_mul_bt(Rb, R, dR);
	assert_true(mvod_rot_angle(dR) < 1e-6);
	assert_true(mvod_vec3_angle(tb, t) < 1e-5);
}

static void test_ransac_with_outliers(void **state)
{
	(void)state;
	robust_with_outliers(false);
}

static void test_magsac_with_outliers(void **state)
{
	(void)state;
	robust_with_outliers(true);
}

static void test_midpoint_parallel_rays(void **state)
{
	(void)state;
	double R[9], t[3] = {0, 0, 0}, d1, d2;
	double w[3] = {0, 0, 0};
	mvod_rot_exp(w, R);
	double x[2] = {0.1, 0.2};
	assert_false(mvod_triangulate_midpoint(R, t, x, x, &d1, &d2));
}

static void test_relative_scale(void **state)
{
	(void)state;
	/* The same structure at 2.5 times the size: s = 2.5 exactly, despite 20 % outliers. */
	double prev[3 * N], cur[3 * N], scratch[N];
	for (int i = 0; i < N; i++) {
		for (int k = 0; k < 3; k++)
			cur[3 * i + k] = sin(i * 1.7 + k) * 4 + (k == 2 ? 10 : 0);
		for (int k = 0; k < 3; k++)
			prev[3 * i + k] = 2.5 * cur[3 * i + k];
		if (i % 5 == 0)
			prev[3 * i] += 7 + i;
	}
	double s = 0;
	assert_int_equal(mvod_motion_relative_scale(prev, cur, N, 10, scratch, &s), 0);
	assert_true(fabs(s - 2.5) < 1e-12);
	assert_int_equal(mvod_motion_relative_scale(prev, cur, 8, 10, scratch, &s), -ENODATA);
}

static void test_rotation_only(void **state)
{
	(void)state;
	double R[9], t[3] = {0, 0, 0}, X[3 * N], x1[2 * N], x2[2 * N], Rb[9];
	double w[3] = {0.01, 0.2, -0.03};
	mvod_rot_exp(w, R);
	scene(R, t, X, x1, x2);
	uint8_t mask[N];
	memset(mask, 1, sizeof(mask));
	assert_int_equal(mvod_motion_rotation_only(x1, x2, mask, N, Rb), 0);
	double dR[9];
	mvod_mat3_mul_bt(Rb, R, dR);
	assert_true(mvod_rot_angle(dR) < 1e-9);
}

static void test_median(void **state)
{
	(void)state;
	double v[] = {5, 1, 4, 2, 3};
	assert_true(mvod_median(v, 5) == 3);
	double w[] = {7, 7, 7, 1};
	assert_true(mvod_median(w, 4) == 7);
}

/*
 * twoview.c's refinement for ORB: from a motion 0.6 deg and 3 deg off, fitted on half the good
 * matches (MAGSAC's mask is its sample's support, not every inlier), the inliers chosen under
 * that fit are exactly the good matches (a fifth are garbage), and the fit on them is the truth.
 */
static void test_refine(void **state)
{
	(void)state;
	double R[9], t[3], X[3 * N], x1[2 * N], x2[2 * N];
	scene_with_outliers(R, t, X, x1, x2);
	double w0[3] = {0.01, 0.0, 0.0}, dR0[9], Rs[9], ts[3] = {t[0] + 0.05, t[1], t[2]};
	mvod_rot_exp(w0, dR0);
	mvod_mat3_mul(dR0, R, Rs);
	uint8_t mask[N];
	for (int i = 0; i < N; i++)
		mask[i] = i % 5 != 0 && i % 2 == 0;
	const double k = 1.0 / 500; /* 1 px at f = 500, as robust_with_outliers */
	assert_true(mvod_motion_refine(Rs, ts, x1, x2, NULL, mask, N, k, 10) > 0);
	assert_true(fabs(mvod_vec3_norm(ts) - 1.0) < 1e-12);
	assert_int_equal(mvod_motion_epipolar_inliers(Rs, ts, x1, x2, NULL, N, k, mask), N - N / 5);
	for (int i = 0; i < N; i++)
		assert_int_equal(mask[i], i % 5 != 0);
	mvod_motion_refine(Rs, ts, x1, x2, NULL, mask, N, k, 10);
	double dR[9];
	mvod_mat3_mul_bt(Rs, R, dR);
	/* Exact data: the minimum is the truth, to the forward differences' 1e-7 and rounding. */
	assert_true(mvod_rot_angle(dR) < 1e-7);
	assert_true(mvod_vec3_angle(ts, t) < 1e-6);
	double depth[N];
	assert_int_equal(mvod_motion_depths(Rs, ts, x1, x2, mask, N, depth), N - N / 5);
	for (int i = 0; i < N; i++)
		assert_true(mask[i] ? fabs(depth[i] - X[3 * i + 2]) < 1e-5 * X[3 * i + 2]
				    : depth[i] == 0.0);
	/* From the truth it stays there (steps may still lower the cost's rounding). */
	memcpy(Rs, R, sizeof(Rs));
	memcpy(ts, t, sizeof(ts));
	assert_true(mvod_motion_refine(Rs, ts, x1, x2, NULL, mask, N, k, 10) >= 0);
	mvod_mat3_mul_bt(Rs, R, dR);
	assert_true(mvod_rot_angle(dR) < 1e-9);
	assert_true(mvod_vec3_angle(ts, t) < 1e-9);
	double t0[3] = {0, 0, 0};
	assert_int_equal(mvod_motion_refine(Rs, t0, x1, x2, NULL, mask, N, k, 10), -EINVAL);
}

/*
 * The weights: a match moved 2.5 px off its epipolar line in image 2 (a Sampson distance of
 * about 2.5 / sqrt(2) = 1.8 px: the distance shares the error between both images) is no
 * inlier at 1 px and sigma 1, and is one at sigma 2.
 */
static void test_epipolar_inliers_weights(void **state)
{
	(void)state;
	double R[9], t[3], X[3 * N], x1[2 * N], x2[2 * N], w[N];
	motion(R, t);
	scene(R, t, X, x1, x2);
	/* Moved along the normal of its epipolar line l = E x1 (in the image plane). */
	double tx[9] = {0, -t[2], t[1], t[2], 0, -t[0], -t[1], t[0], 0}, E[9];
	mvod_mat3_mul(tx, R, E);
	const double p1[3] = {x1[0], x1[1], 1.0};
	double l[3];
	mvod_mat3_vec(E, p1, l);
	double ln = hypot(l[0], l[1]);
	x2[0] += 2.5 / 500 * l[0] / ln;
	x2[1] += 2.5 / 500 * l[1] / ln;
	uint8_t mask[N];
	for (int i = 0; i < N; i++)
		w[i] = 1.0;
	assert_int_equal(mvod_motion_epipolar_inliers(R, t, x1, x2, w, N, 1.0 / 500, mask), N - 1);
	assert_int_equal(mask[0], 0);
	w[0] = 0.5;
	assert_int_equal(mvod_motion_epipolar_inliers(R, t, x1, x2, w, N, 1.0 / 500, mask), N);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_decompose_and_cheirality),
		cmocka_unit_test(test_ransac_with_outliers),
		cmocka_unit_test(test_magsac_with_outliers),
		cmocka_unit_test(test_midpoint_parallel_rays),
		cmocka_unit_test(test_relative_scale),
		cmocka_unit_test(test_rotation_only),
		cmocka_unit_test(test_median),
		cmocka_unit_test(test_refine),
		cmocka_unit_test(test_epipolar_inliers_weights),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
