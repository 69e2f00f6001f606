/* Alignment, per-frame, drift and KITTI segment errors on hand-made trajectories with known answers. */
#include <errno.h>
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

/* Every consecutive pair of an n-frame run through one accumulator. */
static void rpe_run(const struct mvod_pose *e, const struct mvod_pose *g, int n, struct mvod_rpe *r)
{
	*r = (struct mvod_rpe){0};
	for (int i = 1; i < n; i++)
		mvod_rpe_add(r, &e[i - 1], &e[i], &g[i - 1], &g[i]);
	mvod_rpe_finish(r);
}

static void test_rpe_pure_yaw_error(void **state)
{
	(void)state;
	/* The estimate turns 0.5 deg per step more than the truth; positions are identical. */
	struct mvod_pose g[10], e[10];
	straight(g, 10, 0);
	straight(e, 10, 0.5 * M_PI / 180);
	struct mvod_rpe r;
	rpe_run(e, g, 10, &r);
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
	struct mvod_rpe r;
	rpe_run(e, g, 5, &r);
	assert_true(r.rot_deg_max < 1e-12);
	assert_int_equal(r.n_dir, 4);
	assert_true(fabs(r.dir_deg_mean - 45) < 1e-9);
	/* Each step is off by 1 m sideways: 100 % of the 1 m ground-truth step. */
	assert_int_equal(r.n_pct, 4);
	assert_true(fabs(r.trans_pct_mean - 100) < 1e-9);
}

/*
 * An estimate that never moves while the truth does: no direction at all, which must not read
 * as a perfect one (it would let a motionless VO pass every direction bound).
 */
static void test_rpe_held_estimate(void **state)
{
	(void)state;
	struct mvod_pose g[5], e[5];
	straight(g, 5, 0);
	straight(e, 5, 0);
	for (int i = 0; i < 5; i++)
		e[i].t[2] = 0;
	struct mvod_rpe r;
	rpe_run(e, g, 5, &r);
	assert_int_equal(r.n_dir, 4);
	assert_true(r.dir_deg_mean == 90 && r.dir_deg_max == 90);
	assert_true(fabs(r.trans_pct_mean - 100) < 1e-9);
}

static void test_euler_y_sign_and_range(void **state)
{
	(void)state;
	double R[9];
	const double wy[3] = {0, 0.3, 0}, wy_neg[3] = {0, -0.3, 0}, wx[3] = {0.3, 0, 0};
	const double wz[3] = {0, 0, 0.3}, wy_far[3] = {0, 2.0, 0};
	mvod_rot_exp(wy, R);
	assert_true(fabs(mvod_rot_euler_y(R) - 0.3) < 1e-12);
	mvod_rot_exp(wy_neg, R);
	assert_true(fabs(mvod_rot_euler_y(R) + 0.3) < 1e-12);
	mvod_rot_exp(wx, R);
	assert_true(fabs(mvod_rot_euler_y(R)) < 1e-15);
	mvod_rot_exp(wz, R);
	assert_true(fabs(mvod_rot_euler_y(R)) < 1e-15);
	/* The range is [-pi/2, pi/2]: at 2 rad, cos < 0 and atan2(sin 2, |cos 2|) = pi - 2. */
	mvod_rot_exp(wy_far, R);
	assert_true(fabs(mvod_rot_euler_y(R) - (M_PI - 2.0)) < 1e-12);
}

static void test_frame_err_pure_yaw(void **state)
{
	(void)state;
	/*
	 * The truth drives straight along z (R = I, 1 m steps); the estimate turns a = 0.5 deg more
	 * per step, R_e,i = Ry(i a), at the same positions. dR_e dR_g^T = Ry(a): r = 0.5 deg.
	 * dt_e = dt_g = (0, 0, 1), but R_g,i R_e,i^T = Ry(-i a) turns the estimated step by the
	 * heading error accumulated so far: Ry(-i a) (0, 0, 1) = (-sin ia, 0, cos ia), so
	 * d_i = |(sin ia, 0, 1 - cos ia)| = sqrt(2 - 2 cos ia) = 2 sin(ia / 2): it grows with i.
	 */
	const double a = 0.5 * M_PI / 180;
	struct mvod_pose g[10], e[10];
	straight(g, 10, 0);
	straight(e, 10, a);
	double e_sum = 0;
	struct mvod_rpe acc = {0};
	for (int i = 1; i < 10; i++) {
		struct mvod_frame_err fe;
		mvod_frame_err(&e[i - 1], &e[i], &g[i - 1], &g[i], &fe);
		/* The accumulator hands back the very pair's error (the bench plots it per frame). */
		struct mvod_frame_err added = mvod_rpe_add(&acc, &e[i - 1], &e[i], &g[i - 1], &g[i]);
		assert_memory_equal(&added, &fe, sizeof(fe));
		double d = 2 * sin(i * a / 2);
		assert_true(fabs(fe.r_deg - 0.5) < 1e-9);
		assert_true(fabs(fe.d_m - d) < 1e-12);
		assert_true(fabs(fe.e - (0.5 + d) / (1.0 + d)) < 1e-9);
		e_sum += fe.e;
	}
	struct mvod_rpe r;
	rpe_run(e, g, 10, &r);
	/* Ten frames: the first one adds e = 0 to the average. */
	assert_true(fabs(r.err_avg - e_sum / 10) < 1e-12);
	double d9 = 2 * sin(9 * a / 2);
	assert_true(fabs(r.err_max - (0.5 + d9) / (1.0 + d9)) < 1e-9);
}

static void test_frame_err_pure_step(void **state)
{
	(void)state;
	/*
	 * Both turn 0.02 rad per step identically; every estimated step is 10 % longer. R_g,i R_e,i^T
	 * = I and dR_e = dR_g, so r = 0, d = 0.1 m per 1 m step and e = 0.1 / 0.6 = 1/6.
	 */
	struct mvod_pose g[10], e[10];
	straight(g, 10, 0.02);
	straight(e, 10, 0.02);
	for (int i = 0; i < 10; i++)
		e[i].t[2] = 1.1 * i;
	struct mvod_frame_err fe;
	mvod_frame_err(&e[4], &e[5], &g[4], &g[5], &fe);
	assert_true(fe.r_deg < 1e-12);
	assert_true(fabs(fe.d_m - 0.1) < 1e-12);
	assert_true(fabs(fe.e - fe.d_m / (0.5 + fe.d_m)) < 1e-15);
	struct mvod_rpe r;
	rpe_run(e, g, 10, &r);
	/* Nine pairs at 1/6 over ten frames, the first at 0: 0.9 / 6 = 0.15. */
	assert_true(fabs(r.err_avg - 0.15) < 1e-12);
	assert_true(fabs(r.err_max - 1.0 / 6) < 1e-12);
	assert_int_equal(r.n_pct, 9);
	assert_true(fabs(r.trans_pct_mean - 10) < 1e-9);
}

static void test_frame_err_pitch_is_not_heading(void **state)
{
	(void)state;
	/*
	 * The estimate pitches 0.5 deg per step more than the truth (about x) at the true
	 * positions: the RPE sees the full 0.5 deg, r (the y Euler angle: heading) sees none. The
	 * accumulated pitch error still tilts the estimated step: d = 2 sin(i a / 2), as for yaw.
	 */
	const double a = 0.5 * M_PI / 180;
	struct mvod_pose g[6], e[6];
	straight(g, 6, 0);
	straight(e, 6, 0);
	for (int i = 0; i < 6; i++) {
		double w[3] = {a * i, 0, 0};
		mvod_rot_exp(w, e[i].R);
	}
	for (int i = 1; i < 6; i++) {
		struct mvod_frame_err fe;
		mvod_frame_err(&e[i - 1], &e[i], &g[i - 1], &g[i], &fe);
		assert_true(fe.r_deg < 1e-9);
		assert_true(fabs(fe.d_m - 2 * sin(i * a / 2)) < 1e-12);
	}
	struct mvod_rpe r;
	rpe_run(e, g, 6, &r);
	assert_true(fabs(r.rot_deg_mean - 0.5) < 1e-9);
}

static void test_frame_err_scaled_copy(void **state)
{
	(void)state;
	/*
	 * Twice the truth's translations, same rotations (turning 0.02 rad per step): every
	 * estimated step is 2 m for a 1 m true one, so d = 1 m, r = 0 and e = 1 / 1.5 on every
	 * frame but the first; the RPE step error is 100 %.
	 */
	struct mvod_pose g[8], e[8];
	straight(g, 8, 0.02);
	straight(e, 8, 0.02);
	for (int i = 0; i < 8; i++)
		e[i].t[2] = 2.0 * i;
	struct mvod_rpe r;
	rpe_run(e, g, 8, &r);
	assert_true(fabs(r.err_max - 1 / 1.5) < 1e-12);
	assert_true(fabs(r.err_avg - 7 * (1 / 1.5) / 8) < 1e-12);
	assert_true(r.rot_deg_max < 1e-9);
	assert_true(fabs(r.trans_pct_mean - 100) < 1e-9);
	/* Scaled down to metres (what the bench does with the Sim(3) scale), nothing is left. */
	for (int i = 0; i < 8; i++)
		e[i].t[2] *= 0.5;
	rpe_run(e, g, 8, &r);
	assert_true(r.err_max < 1e-12);
}

static void test_scaled_copy(void **state)
{
	(void)state;
	/* Twice the truth everywhere: uniform scale, no drift; only Sim(3) can absorb it. */
	double g[3 * N], e[3 * N], R[9], t[3], s, drift;
	gt_path(g);
	for (int k = 0; k < 3 * N; k++)
		e[k] = 2 * g[k];
	assert_int_equal(mvod_scale_drift(e, g, N, &drift), 0);
	assert_true(fabs(drift - 1.0) < 1e-12);
	assert_int_equal(mvod_umeyama(e, g, N, true, R, t, &s), 0);
	assert_true(fabs(s - 0.5) < 1e-9);
	assert_true(mvod_ate_rmse(e, g, N, R, t, s) < 1e-9);
	assert_int_equal(mvod_umeyama(e, g, N, false, R, t, &s), 0);
	assert_true(mvod_ate_rmse(e, g, N, R, t, s) > 1.0);
}

static void test_scale_drift_halved(void **state)
{
	(void)state;
	/* 101 frames, 100 steps of 1 m; the estimate's steps halve after step 50. */
	double g[3 * 101] = {0}, e[3 * 101] = {0}, drift;
	for (int i = 1; i < 101; i++) {
		g[3 * i + 2] = i;
		e[3 * i + 2] = e[3 * i - 1] + (i > 50 ? 0.5 : 1.0);
	}
	/* Windows of steps 1-20, 21-40: 1; 41-60: 0.75; 61-80, 81-100: 0.5. Largest over smallest. */
	assert_int_equal(mvod_scale_drift(e, g, 101, &drift), 0);
	assert_true(fabs(drift - 2.0) < 1e-12);
	/* Only the first three windows (61 frames): 1 / 0.75. A partial window does not count. */
	assert_int_equal(mvod_scale_drift(e, g, 70, &drift), 0);
	assert_true(fabs(drift - 1.0 / 0.75) < 1e-12);
	/* No whole window, or no motion in any: no ratio exists. */
	assert_int_equal(mvod_scale_drift(e, g, 1, &drift), -EINVAL);
	assert_int_equal(mvod_scale_drift(e, g, 20, &drift), -EINVAL);
	double still[3 * 101] = {0};
	assert_int_equal(mvod_scale_drift(e, still, 101, &drift), -EINVAL);
	assert_int_equal(mvod_scale_drift(still, g, 101, &drift), -EINVAL);
	/* The estimate stands through the last window while the truth moves: the scale collapsed. */
	for (int i = 81; i < 101; i++)
		e[3 * i + 2] = e[3 * 80 + 2];
	assert_int_equal(mvod_scale_drift(e, g, 101, &drift), 0);
	assert_true(isinf(drift));
}

#define KN 1001 /* 1000 m at 1 m steps */

/*
 * On a straight 1 m-step line, the devkit ends an L m segment at the first frame *beyond* L, here
 * L + 1 m away, and divides by L: an error proportional to the segment's length comes out times
 * (L + 1) / L. Starts every 10 frames up to 999 - L give 100 - L/10 segments of L = 100k m,
 * 440 in all, and (100 - 10k)(1 + 1/(100k)) = 100 - 10k + 1/k - 0.1, so the mean factor is
 * (440 + H_8 - 0.8) / 440 with H_8 = 1 + 1/2 + ... + 1/8 = 761/280.
 */
static double kitti_overshoot(void)
{
	return (440 + 761.0 / 280 - 0.8) / 440;
}

static void test_kitti_longer_steps(void **state)
{
	(void)state;
	static struct mvod_pose g[KN], e[KN];
	static double dist[KN];
	straight(g, KN, 0);
	straight(e, KN, 0);
	for (int i = 0; i < KN; i++)
		e[i].t[2] = 1.01 * i;
	struct mvod_kitti_rel k;
	mvod_kitti_segments(e, g, KN, dist, &k);
	assert_int_equal(k.n_segments, 440);
	assert_true(fabs(k.t_rel_pct - 1.0 * kitti_overshoot()) < 1e-9);
	assert_true(fabs(k.r_rel_deg_100m) < 1e-12);
}

static void test_kitti_yaw_drift(void **state)
{
	(void)state;
	/*
	 * The estimate turns 0.01 deg per metre at the true positions: a segment's rotation error is
	 * 0.01 deg x (L + 1), i.e. 1 deg per 100 m times the devkit's overshoot factor.
	 */
	static struct mvod_pose g[KN], e[KN];
	static double dist[KN];
	straight(g, KN, 0);
	straight(e, KN, 0.01 * M_PI / 180);
	struct mvod_kitti_rel k;
	mvod_kitti_segments(e, g, KN, dist, &k);
	assert_int_equal(k.n_segments, 440);
	assert_true(fabs(k.r_rel_deg_100m - 1.0 * kitti_overshoot()) < 1e-9);
}

/*
 * A circle of radius KR at 1 m of arc per frame, heading along the tangent. The estimate is the
 * same path moved rigidly (turned 30 deg about y, shifted), its positions then scaled by
 * `scale`: relative poses do not see the rigid motion, so the segment errors are exactly those
 * of the scale, 0.01 of each segment's chord (2 KR |sin(a / 2 KR)| for an arc of a metres).
 */
#define KR 100.0

static void circle(struct mvod_pose *g, struct mvod_pose *e, double scale)
{
	const double w[3] = {0, M_PI / 6, 0}, shift[3] = {5, 0, -3};
	double T[9];
	mvod_rot_exp(w, T);
	for (int i = 0; i < KN; i++) {
		double a = i / KR, yaw[3] = {0, a, 0};
		mvod_rot_exp(yaw, g[i].R);
		g[i].t[0] = KR * (1 - cos(a));
		g[i].t[1] = 0;
		g[i].t[2] = KR * sin(a);
		mvod_mat3_mul(T, g[i].R, e[i].R);
		mvod_mat3_vec(T, g[i].t, e[i].t);
		for (int k = 0; k < 3; k++)
			e[i].t[k] = scale * (e[i].t[k] + shift[k]);
	}
}

static void test_kitti_turning_path(void **state)
{
	(void)state;
	static struct mvod_pose g[KN], e[KN];
	static double dist[KN];
	struct mvod_kitti_rel k;
	circle(g, e, 1.0);
	mvod_kitti_segments(e, g, KN, dist, &k);
	/* The chord of each 1 m step is a hair under 1 m, so segments end where a line's do. */
	assert_int_equal(k.n_segments, 440);
	assert_true(fabs(k.t_rel_pct) < 1e-9 && fabs(k.r_rel_deg_100m) < 1e-9);
	circle(g, e, 1.01);
	mvod_kitti_segments(e, g, KN, dist, &k);
	/* As in kitti_overshoot: 100 - L/10 segments of L = 100k m, each L + 1 m of arc. */
	double want = 0;
	for (int j = 1; j <= 8; j++) {
		double len = 100.0 * j, chord = 2 * KR * fabs(sin((len + 1) / (2 * KR)));
		want += (100 - 10 * j) * 100 * 0.01 * chord / len;
	}
	want /= 440;
	print_message("t_rel on the circle: %.6f %% (expected %.6f %%)\n", k.t_rel_pct, want);
	assert_true(fabs(k.t_rel_pct - want) < 1e-9);
	assert_true(fabs(k.r_rel_deg_100m) < 1e-9);
}

static void test_kitti_short_path(void **state)
{
	(void)state;
	struct mvod_pose g[102];
	double dist[102];
	straight(g, 102, 0);
	struct mvod_kitti_rel k;
	/* Exactly 100 m does not exceed 100 m: no segment, and no score rather than a perfect one. */
	mvod_kitti_segments(g, g, 101, dist, &k);
	assert_int_equal(k.n_segments, 0);
	assert_true(isnan(k.t_rel_pct) && isnan(k.r_rel_deg_100m));
	/* One more metre makes one segment, frames 0 to 101. */
	mvod_kitti_segments(g, g, 102, dist, &k);
	assert_int_equal(k.n_segments, 1);
	assert_true(k.t_rel_pct == 0 && k.r_rel_deg_100m == 0);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_umeyama_recovers_similarity),
		cmocka_unit_test(test_umeyama_degenerate),
		cmocka_unit_test(test_rpe_pure_yaw_error),
		cmocka_unit_test(test_rpe_pure_direction_error),
		cmocka_unit_test(test_rpe_held_estimate),
		cmocka_unit_test(test_euler_y_sign_and_range),
		cmocka_unit_test(test_frame_err_pure_yaw),
		cmocka_unit_test(test_frame_err_pure_step),
		cmocka_unit_test(test_frame_err_pitch_is_not_heading),
		cmocka_unit_test(test_frame_err_scaled_copy),
		cmocka_unit_test(test_scaled_copy),
		cmocka_unit_test(test_scale_drift_halved),
		cmocka_unit_test(test_kitti_longer_steps),
		cmocka_unit_test(test_kitti_yaw_drift),
		cmocka_unit_test(test_kitti_turning_path),
		cmocka_unit_test(test_kitti_short_path),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
