/*
 * Map mode's windowed bundle adjustment (ba_lm.c) on exact synthetic data: perturbed poses and
 * points come back, a gross outlier is flagged; the BA thread hands the job over and back and
 * solves exactly as the caller's thread would; and the same steps as Ceres's (ba_ceres.cpp),
 * the reference it was written after, where Ceres is installed (else that test is skipped).
 */
#include <errno.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <cmocka.h>

#include "ba_ceres.h"
#include "scene.h"
#include "vo/optim/ba_lm.h"
#include "vo/optim/ba_thread.h"

#define POSES 7
#define MAX_PTS 2000
#define MAX_OBS (POSES * MAX_PTS)

struct window {
	int n_pts, n_obs;
	double truth_poses[POSES * 6], truth_pts[MAX_PTS * 3];
	double poses[POSES * 6], pts[MAX_PTS * 3];
	uint8_t fixed[POSES], outlier[MAX_OBS];
	struct mvod_ba_obs obs[MAX_OBS];
};

static struct window win; /* 1 MB: static, not on the stack */

/* n_pts points each seen by every keyframe whose image holds it (kept when seen >= 2 times). */
static void make_window(int n_pts)
{
	uint32_t s = 42;
	win.n_pts = win.n_obs = 0;
	for (int k = 0; k < POSES; k++)
		scene_pose(k, win.truth_poses + 6 * k);
	while (win.n_pts < n_pts) {
		double *X = win.truth_pts + 3 * win.n_pts, uv[2];
		scene_point(&s, X);
		int first = win.n_obs;
		for (int k = 0; k < POSES; k++) {
			if (!scene_project(win.truth_poses + 6 * k, X, uv))
				continue;
			/* Octave 0-3 gives sigma 1.2^octave, as the detector's pyramid would. */
			double sigma = pow(1.2, (double)(win.n_obs % 4));
			win.obs[win.n_obs++] = (struct mvod_ba_obs){k, win.n_pts, uv[0], uv[1], sigma};
		}
		if (win.n_obs - first >= 2)
			win.n_pts++;
		else
			win.n_obs = first;
	}
}

/* Perturbs every pose but the first two (held: the gauge) and every point, fixed seed. */
static void perturb(double rot_rad, double trans, double pt)
{
	uint32_t s = 7;
	memcpy(win.poses, win.truth_poses, sizeof(win.poses));
	memcpy(win.pts, win.truth_pts, sizeof(double) * 3 * win.n_pts);
	memset(win.fixed, 0, sizeof(win.fixed));
	win.fixed[0] = win.fixed[1] = 1;
	for (int k = 2; k < POSES; k++)
		for (int i = 0; i < 3; i++) {
			win.poses[6 * k + i] += rot_rad * scene_normal(&s);
			win.poses[6 * k + 3 + i] += trans * scene_normal(&s);
		}
	for (int i = 0; i < 3 * win.n_pts; i++)
		win.pts[i] += pt * scene_normal(&s);
}

static struct mvod_ba_problem problem(void)
{
	return (struct mvod_ba_problem){POSES, win.n_pts, win.n_obs, win.poses, win.pts,
					win.fixed, win.obs, win.outlier, SCENE_F, SCENE_F,
					SCENE_CX, SCENE_CY};
}

/* Largest pose (rotation rad, translation) and point error against the truth. */
static void errors(double *rot, double *trans, double *pt)
{
	*rot = *trans = *pt = 0;
	for (int i = 0; i < 6 * POSES; i++) {
		double e = fabs(win.poses[i] - win.truth_poses[i]);
		if (i % 6 < 3)
			*rot = fmax(*rot, e);
		else
			*trans = fmax(*trans, e);
	}
	for (int i = 0; i < 3 * win.n_pts; i++)
		*pt = fmax(*pt, fabs(win.pts[i] - win.truth_pts[i]));
}

static int setup(void **state)
{
	struct mvod_ba_lm *lm = NULL;
	int rc = mvod_ba_lm_create(POSES, MAX_PTS, MAX_OBS, &lm);
	*state = lm;
	return rc;
}

static int teardown(void **state)
{
	mvod_ba_lm_destroy(*state);
	return 0;
}

static void test_recovers_window(void **state)
{
	/* 200 points, poses off by 0.01 rad and 0.1 units (a tenth of a step), points by 0.3. */
	make_window(200);
	perturb(0.01, 0.1, 0.3);
	struct mvod_ba_options o;
	mvod_ba_options_default(&o);
	o.max_iterations = 50;
	struct mvod_ba_problem p = problem();
	struct mvod_ba_result r;
	double e_rot, e_trans, e_pt;
	errors(&e_rot, &e_trans, &e_pt);
	assert_true(e_rot > 0.005 && e_pt > 0.3); /* the start really is wrong */
	assert_int_equal(mvod_ba_lm_solve(*state, &p, &o, &r), 0);
	errors(&e_rot, &e_trans, &e_pt);
	print_message("BA: %d iterations, cost %.3g -> %.3g, errors rot %.2g rad, trans %.2g, "
		      "points %.2g\n", r.iterations, r.initial_cost, r.final_cost, e_rot, e_trans, e_pt);
	/*
	 * Exact observations and the two held poses fix all 7 gauge freedoms (first pose: 6,
	 * second: the scale), so the truth is the only minimum; what is left is the solver's
	 * stopping tolerance (relative cost change 1e-6 of a cost already near 0). Points 40
	 * units away along a 6-unit path are the least constrained: 1e-4 units still is 10^3
	 * times below the perturbation.
	 */
	assert_true(r.converged);
	assert_true(e_rot < 1e-6);
	assert_true(e_trans < 1e-5);
	assert_true(e_pt < 1e-4);
	assert_int_equal(r.n_outliers, 0);
	/* The held poses did not move at all. */
	assert_memory_equal(win.poses, win.truth_poses, sizeof(double) * 12);
}

static void test_flags_outlier(void **state)
{
	make_window(200);
	perturb(0.002, 0.02, 0.05);
	int bad = 137; /* one observation 25 px off: a wrong match */
	win.obs[bad].u += 25;
	struct mvod_ba_options o;
	mvod_ba_options_default(&o);
	o.max_iterations = 50;
	struct mvod_ba_problem p = problem();
	struct mvod_ba_result r;
	assert_int_equal(mvod_ba_lm_solve(*state, &p, &o, &r), 0);
	win.obs[bad].u -= 25;
	assert_int_equal(r.n_outliers, 1);
	assert_int_equal(win.outlier[bad], 1);
	/*
	 * As ORB-SLAM does, solve again without the flagged observation: the exact window comes
	 * back as in test_recovers_window. (The first solve stops on the relative cost change
	 * while the outlier's Huber cost, ~46, dominates: poses measured 0.022 units off then.)
	 */
	win.obs[bad] = win.obs[--win.n_obs];
	p = problem();
	assert_int_equal(mvod_ba_lm_solve(*state, &p, &o, &r), 0);
	assert_int_equal(r.n_outliers, 0);
	double e_rot, e_trans, e_pt;
	errors(&e_rot, &e_trans, &e_pt);
	assert_true(e_rot < 1e-6);
	assert_true(e_trans < 1e-5);
	assert_true(e_pt < 1e-4);
}

static void test_bad_problem(void **state)
{
	make_window(20);
	perturb(0, 0, 0);
	struct mvod_ba_options o;
	mvod_ba_options_default(&o);
	struct mvod_ba_problem p = problem();
	struct mvod_ba_result r;
	win.obs[3].point = win.n_pts; /* out of range */
	assert_int_equal(mvod_ba_lm_solve(*state, &p, &o, &r), -EINVAL);
	win.obs[3].point = 0;
	win.obs[3].sigma = 0;
	assert_int_equal(mvod_ba_lm_solve(*state, &p, &o, &r), -EINVAL);
	win.obs[3].sigma = 1;
	o.function_tolerance = -1e-4;
	assert_int_equal(mvod_ba_lm_solve(*state, &p, &o, &r), -EINVAL);
}

/*
 * function_tolerance (map mode passes 1e-4): a window with noisy observations, so that the
 * cost settles above 0, solved from the same start with Ceres's default (0: 1e-6) and with
 * 1e-2. The looser one stops in fewer iterations (ignoring the option would make them equal)
 * at a cost within 2 % of the default's: each step it skipped would have changed the cost by
 * under 1 %, and Levenberg-Marquardt's steps shrink as it converges.
 */
static void test_function_tolerance(void **state)
{
	int it[2];
	double cost[2];
	for (int v = 0; v < 2; v++) {
		make_window(200);
		for (int i = 0; i < win.n_obs; i++) { /* +-0.5 px, a fixed pattern */
			win.obs[i].u += i % 3 == 0 ? 0.5 : -0.25;
			win.obs[i].v += i % 5 == 0 ? -0.5 : 0.125;
		}
		perturb(0.01, 0.1, 0.3);
		struct mvod_ba_options o;
		mvod_ba_options_default(&o);
		o.max_iterations = 50;
		o.function_tolerance = v ? 1e-2 : 0;
		struct mvod_ba_problem p = problem();
		struct mvod_ba_result r;
		assert_int_equal(mvod_ba_lm_solve(*state, &p, &o, &r), 0);
		it[v] = r.iterations;
		cost[v] = r.final_cost;
	}
	print_message("BA tolerance 1e-6: %d iterations, cost %.6g; 1e-2: %d, %.6g\n", it[0],
		      cost[0], it[1], cost[1]);
	assert_true(cost[0] > 0);
	assert_true(it[1] < it[0]);
	assert_true(cost[1] <= 1.02 * cost[0]);
}

/* The size of a KITTI window (7 keyframes, 2000 points): how long one solve takes. Printed,
 * never asserted (machine speed is no test's business). */
static void test_kitti_sized_window(void **state)
{
	make_window(MAX_PTS);
	perturb(0.002, 0.02, 0.1);
	struct mvod_ba_options o;
	mvod_ba_options_default(&o);
	struct mvod_ba_problem p = problem();
	struct mvod_ba_result r;
	struct timespec t0, t1;
	clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t0);
	assert_int_equal(mvod_ba_lm_solve(*state, &p, &o, &r), 0);
	clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t1);
	double ms = (t1.tv_sec - t0.tv_sec) * 1e3 + (t1.tv_nsec - t0.tv_nsec) / 1e6;
	print_message("BA %d poses, %d points, %d observations: %d iterations, %.1f ms\n", POSES,
		      win.n_pts, win.n_obs, r.iterations, ms);
	double e_rot, e_trans, e_pt;
	errors(&e_rot, &e_trans, &e_pt);
	assert_true(e_trans < 1e-4); /* as in test_recovers_window, with a smaller start error */
}

/*
 * The BA thread's job changes hands as documented (the caller cannot fill it while posted or
 * while its result waits) and its solution is bit for bit the one mvod_ba_lm_solve gives on
 * the caller's thread, so --ba-sync runs are reproducible.
 */
static void test_thread_solves_as_inline(void **state)
{
	struct mvod_ba_thread *t;
	assert_int_equal(mvod_ba_thread_create(POSES, MAX_PTS, &t), 0);
	struct mvod_ba_job *j = mvod_ba_thread_job(t), *done;
	assert_non_null(j);
	assert_false(mvod_ba_thread_take(t, true, &done)); /* nothing posted: no wait, no job */
	make_window(200);
	perturb(0.01, 0.1, 0.3);
	memcpy(j->poses, win.poses, sizeof(win.poses));
	memcpy(j->points, win.pts, sizeof(double) * 3 * win.n_pts);
	memcpy(j->fixed, win.fixed, sizeof(win.fixed));
	memcpy(j->obs, win.obs, sizeof(win.obs[0]) * win.n_obs);
	j->p = (struct mvod_ba_problem){POSES, win.n_pts, win.n_obs, j->poses, j->points,
					j->fixed, j->obs, j->outlier, SCENE_F, SCENE_F,
					SCENE_CX, SCENE_CY};
	mvod_ba_options_default(&j->o);
	mvod_ba_thread_post(t);
	assert_null(mvod_ba_thread_job(t)); /* the BA thread's, or its result's */
	assert_true(mvod_ba_thread_take(t, true, &done));
	assert_ptr_equal(done, j);
	assert_false(mvod_ba_thread_take(t, false, &done)); /* taken once */
	assert_non_null(mvod_ba_thread_job(t));
	struct mvod_ba_problem p = problem();
	struct mvod_ba_result r;
	assert_int_equal(mvod_ba_lm_solve(*state, &p, &j->o, &r), 0);
	assert_int_equal(j->ret, 0);
	assert_int_equal(j->r.iterations, r.iterations);
	assert_memory_equal(j->poses, win.poses, sizeof(win.poses));
	assert_memory_equal(j->points, win.pts, sizeof(double) * 3 * win.n_pts);
	/* Posted and not taken: destroy waits for the solve and stops the thread. */
	mvod_ba_thread_post(t);
	mvod_ba_thread_destroy(t);
	mvod_ba_thread_destroy(NULL);
}

/*
 * ba_lm.c's own Levenberg-Marquardt (map mode's solver) against Ceres from the same start:
 * the same steps, so the same iterations, flags and, to rounding, the same solution. Three
 * windows: exact observations with a large start error and 50 iterations (test_recovers_window's);
 * noisy observations with map mode's options (5 iterations, function tolerance 1e-4), where the
 * solvers stop short of the minimum, so that a different step rule or damping shows; and a
 * 25 px outlier (Huber's linear part, then flagged). The arithmetic is Ceres's in another
 * order (a rotation matrix per pose instead of Rodrigues per point, another Schur
 * elimination), so the solutions differ by rounding carried through a few steps: measured
 * 4e-15 pose and 4e-12 point (points 40 units away are the least constrained), costs equal
 * to 1e-16 relative (1e-21 absolute at window 0's 2e-15). The bounds, 1e-12 / 1e-9 and 1e-9
 * relative cost, are about 1000 times that, and far below what a different step would
 * change (the first step moves poses by about 1e-2 here).
 */
static void test_own_solver_as_ceres(void **state)
{
	if (!ba_ceres_present) {
		print_message("built without Ceres: the reference is not there to compare with\n");
		skip();
	}
	static double start_poses[POSES * 6], start_pts[MAX_PTS * 3], c_poses[POSES * 6],
		c_pts[MAX_PTS * 3];
	static uint8_t c_out[MAX_OBS];
	for (int v = 0; v < 3; v++) {
		make_window(200);
		struct mvod_ba_options o;
		mvod_ba_options_default(&o);
		o.max_iterations = 50;
		if (v == 1) {
			for (int i = 0; i < win.n_obs; i++) { /* as test_function_tolerance */
				win.obs[i].u += i % 3 == 0 ? 0.5 : -0.25;
				win.obs[i].v += i % 5 == 0 ? -0.5 : 0.125;
			}
			o.max_iterations = 5;
			o.function_tolerance = 1e-4;
		}
		if (v == 2)
			win.obs[137].u += 25;
		perturb(v == 2 ? 0.002 : 0.01, v == 2 ? 0.02 : 0.1, v == 2 ? 0.05 : 0.3);
		memcpy(start_poses, win.poses, sizeof(win.poses));
		memcpy(start_pts, win.pts, sizeof(double) * 3 * win.n_pts);
		struct mvod_ba_problem p = problem();
		struct mvod_ba_result rc, ro;
		assert_int_equal(ba_ceres_solve(&p, &o, &rc), 0);
		memcpy(c_poses, win.poses, sizeof(win.poses));
		memcpy(c_pts, win.pts, sizeof(double) * 3 * win.n_pts);
		memcpy(c_out, win.outlier, (size_t)win.n_obs);
		memcpy(win.poses, start_poses, sizeof(win.poses));
		memcpy(win.pts, start_pts, sizeof(double) * 3 * win.n_pts);
		memset(win.outlier, 0, sizeof(win.outlier));
		assert_int_equal(mvod_ba_lm_solve(*state, &p, &o, &ro), 0);
		double dp = 0, dx = 0;
		for (int i = 0; i < 6 * POSES; i++)
			dp = fmax(dp, fabs(win.poses[i] - c_poses[i]));
		for (int i = 0; i < 3 * win.n_pts; i++)
			dx = fmax(dx, fabs(win.pts[i] - c_pts[i]));
		print_message("window %d: Ceres %d iterations, cost %.10g -> %.10g; own %d, %.10g -> "
			      "%.10g; largest difference pose %.2g, point %.2g\n",
			      v, rc.iterations, rc.initial_cost, rc.final_cost, ro.iterations,
			      ro.initial_cost, ro.final_cost, dp, dx);
		assert_true(rc.iterations >= 2); /* a solve, not a start already at the minimum */
		assert_int_equal(ro.iterations, rc.iterations);
		assert_int_equal(ro.converged, rc.converged);
		assert_true(fabs(ro.initial_cost - rc.initial_cost) <= 1e-12 * rc.initial_cost);
		assert_true(fabs(ro.final_cost - rc.final_cost) <= 1e-9 * rc.final_cost + 1e-18);
		assert_true(dp < 1e-12);
		assert_true(dx < 1e-9);
		assert_int_equal(ro.n_outliers, rc.n_outliers);
		assert_memory_equal(win.outlier, c_out, (size_t)win.n_obs);
		assert_int_equal(ro.n_outliers, v == 2); /* the 25 px one, in window 2 only */
		assert_memory_equal(win.poses, start_poses, sizeof(double) * 12); /* held */
	}
}

/* The solver's buffers bound its problems. */
static void test_own_solver_bad_problem(void **state)
{
	(void)state;
	struct mvod_ba_lm *lm;
	assert_int_equal(mvod_ba_lm_create(65, 10, 10, &lm), -EINVAL); /* above 64 poses */
	assert_null(lm);
	assert_int_equal(mvod_ba_lm_create(POSES, 20, 20 * POSES, &lm), 0);
	make_window(21);
	perturb(0, 0, 0);
	struct mvod_ba_options o;
	mvod_ba_options_default(&o);
	struct mvod_ba_problem p = problem();
	struct mvod_ba_result r;
	assert_int_equal(mvod_ba_lm_solve(lm, &p, &o, &r), -EINVAL); /* 21 points, room for 20 */
	make_window(20);
	perturb(0, 0, 0);
	p = problem();
	win.obs[3].point = win.n_pts; /* out of range */
	assert_int_equal(mvod_ba_lm_solve(lm, &p, &o, &r), -EINVAL);
	win.obs[3].point = 0;
	win.obs[3].sigma = 0;
	assert_int_equal(mvod_ba_lm_solve(lm, &p, &o, &r), -EINVAL);
	win.obs[3].sigma = 1;
	assert_int_equal(mvod_ba_lm_solve(lm, &p, &o, &r), 0); /* the exact window: no step */
	assert_int_equal(r.n_outliers, 0);
	mvod_ba_lm_destroy(lm);
	mvod_ba_lm_destroy(NULL);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_recovers_window),
		cmocka_unit_test(test_flags_outlier),
		cmocka_unit_test(test_bad_problem),
		cmocka_unit_test(test_function_tolerance),
		cmocka_unit_test(test_kitti_sized_window),
		cmocka_unit_test(test_thread_solves_as_inline),
		cmocka_unit_test(test_own_solver_as_ceres),
		cmocka_unit_test(test_own_solver_bad_problem),
	};
	return cmocka_run_group_tests(tests, setup, teardown);
}
