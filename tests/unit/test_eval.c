/* Alignment and relative pose error on hand-made trajectories with known answers. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>

#include <cmocka.h>

#include "mvod/eval.h"

#define N 40

static void gt_path(double *xyz)
{
	for (int i = 0; i < N; i++) {
		xyz[3 * i] = 3 * sin(0.2 * i);
		xyz[3 * i + 1] = 0.1 * i;
		xyz[3 * i + 2] = 0.5 * i;
	}
}

static void test_umeyama_recovers_similarity(void **state)
{
	(void)state;
	double g[3 * N], e[3 * N], Rt[9], w[3] = {0.3, -0.5, 0.2};
	gt_path(g);
	mvod_rot_exp(w, Rt);
	/* e = (Rt^T (g - t0)) / 2.5: g is exactly 2.5 Rt e + t0. */
	const double t0[3] = {1, -2, 3};
	for (int i = 0; i < N; i++) {
		double d[3] = {g[3 * i] - t0[0], g[3 * i + 1] - t0[1], g[3 * i + 2] - t0[2]};
		mvod_mat3_tvec(Rt, d, e + 3 * i);
		for (int k = 0; k < 3; k++)
			e[3 * i + k] /= 2.5;
	}
	double R[9], t[3], s;
	assert_int_equal(mvod_umeyama(e, g, N, true, R, t, &s), 0);
	assert_true(fabs(s - 2.5) < 1e-9);
	for (int k = 0; k < 9; k++)
		assert_true(fabs(R[k] - Rt[k]) < 1e-9);
	assert_true(mvod_ate_rmse(e, g, N, R, t, s) < 1e-9);
	/* Without scale the best rigid fit leaves a real error. */
	assert_int_equal(mvod_umeyama(e, g, N, false, R, t, &s), 0);
	assert_true(s == 1.0);
	assert_true(mvod_ate_rmse(e, g, N, R, t, s) > 0.5);
}

static void test_umeyama_degenerate(void **state)
{
	(void)state;
	double p[3 * N] = {0}, R[9], t[3], s;
	assert_true(mvod_umeyama(p, p, N, true, R, t, &s) < 0);
	assert_true(mvod_umeyama(p, p, 2, true, R, t, &s) < 0);
}

static void straight(struct mvod_pose *p, int n, double yaw_per_step)
{
	for (int i = 0; i < n; i++) {
		double w[3] = {0, yaw_per_step * i, 0};
		mvod_rot_exp(w, p[i].R);
		p[i].t[0] = 0;
		p[i].t[1] = 0;
		p[i].t[2] = i;
	}
}

static void test_rpe_pure_yaw_error(void **state)
{
	(void)state;
	/* The estimate turns 0.5 deg per step more than the truth; positions are identical. */
	struct mvod_pose g[10], e[10];
	straight(g, 10, 0);
	straight(e, 10, 0.5 * M_PI / 180);
	struct mvod_rpe r = {0};
	for (int i = 1; i < 10; i++)
		mvod_rpe_add(&r, &e[i - 1], &e[i], &g[i - 1], &g[i]);
	mvod_rpe_finish(&r);
	assert_int_equal(r.n, 9);
	assert_true(fabs(r.rot_deg_mean - 0.5) < 1e-9);
	assert_true(fabs(r.rot_deg_max - 0.5) < 1e-9);
}

static void test_rpe_pure_direction_error(void **state)
{
	(void)state;
	/* The estimate steps sideways at 45 deg to the truth; orientation identical. */
	struct mvod_pose g[5], e[5];
	straight(g, 5, 0);
	straight(e, 5, 0);
	for (int i = 0; i < 5; i++)
		e[i].t[0] = i;
	struct mvod_rpe r = {0};
	for (int i = 1; i < 5; i++)
		mvod_rpe_add(&r, &e[i - 1], &e[i], &g[i - 1], &g[i]);
	mvod_rpe_finish(&r);
	assert_true(r.rot_deg_max < 1e-12);
	assert_int_equal(r.n_dir, 4);
	assert_true(fabs(r.dir_deg_mean - 45) < 1e-9);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_umeyama_recovers_similarity),
		cmocka_unit_test(test_umeyama_degenerate),
		cmocka_unit_test(test_rpe_pure_yaw_error),
		cmocka_unit_test(test_rpe_pure_direction_error),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
