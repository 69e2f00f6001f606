/* Quaternion and rotation conversions, pose algebra. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>

#include <cmocka.h>

#include "mvod/geom.h"

static void assert_mat_near(const double *a, const double *b, int n, double tol)
{
	for (int i = 0; i < n; i++)
		assert_true(fabs(a[i] - b[i]) <= tol);
}

static void test_quat_round_trip(void **state)
{
	(void)state;
	/* Angles up to and past 180 deg, so every branch of Shepperd's method runs. */
	const double axes[][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 2, 3}, {-2, 0.5, 1}};
	const double angles[] = {0, 1e-6, 0.3, 1.5, 3.0, M_PI - 1e-9, M_PI};
	for (size_t a = 0; a < 5; a++) {
		for (size_t k = 0; k < 7; k++) {
			double n = sqrt(axes[a][0] * axes[a][0] + axes[a][1] * axes[a][1] +
					axes[a][2] * axes[a][2]);
			double w[3] = {axes[a][0] / n * angles[k], axes[a][1] / n * angles[k],
				       axes[a][2] / n * angles[k]};
			double R[9], q[4], R2[9];
			mvod_rot_exp(w, R);
			mvod_rot_to_quat(R, q);
			assert_true(q[0] >= 0);
			assert_true(fabs(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3] - 1) < 1e-12);
			mvod_quat_to_rot(q, R2);
			assert_mat_near(R, R2, 9, 1e-9);
			assert_true(fabs(mvod_rot_angle(R) - angles[k]) < 1e-7);
			/* The log gives w back (at exactly pi, -w is as right: same rotation). */
			double w2[3], R3[9];
			mvod_rot_log(R, w2);
			mvod_rot_exp(w2, R3);
			assert_mat_near(R, R3, 9, 1e-9);
			if (angles[k] < 3.1)
				assert_mat_near(w, w2, 3, 1e-9);
		}
	}
}

/*
 * A quarter turn about each axis, against values worked out by hand: q = (cos 45, sin 45 along
 * the axis), and the turn carries the next axis into the one after (x to y, y to z, z to x).
 */
static void test_quat_known_value(void **state)
{
	(void)state;
	for (int a = 0; a < 3; a++) {
		double w[3] = {0, 0, 0}, R[9], q[4], from[3] = {0, 0, 0}, to[3];
		w[a] = M_PI / 2;
		mvod_rot_exp(w, R);
		mvod_rot_to_quat(R, q);
		assert_true(fabs(q[0] - M_SQRT1_2) < 1e-12);
		for (int k = 0; k < 3; k++)
			assert_true(fabs(q[1 + k] - (k == a ? M_SQRT1_2 : 0)) < 1e-12);
		from[(a + 1) % 3] = 1;
		mvod_mat3_vec(R, from, to);
		for (int k = 0; k < 3; k++)
			assert_true(fabs(to[k] - (k == (a + 2) % 3 ? 1 : 0)) < 1e-12);
		/* And back: the hand-made quaternion gives the same matrix. */
		double qh[4] = {M_SQRT1_2, 0, 0, 0}, Rh[9];
		qh[1 + a] = M_SQRT1_2;
		mvod_quat_to_rot(qh, Rh);
		assert_mat_near(R, Rh, 9, 1e-12);
	}
}

static void test_pose_inverse_compose(void **state)
{
	(void)state;
	struct mvod_pose a, ai, id;
	double w[3] = {0.1, -0.4, 0.25};
	mvod_rot_exp(w, a.R);
	a.t[0] = 1;
	a.t[1] = -2;
	a.t[2] = 3.5;
	mvod_pose_inverse(&a, &ai);
	mvod_pose_compose(&a, &ai, &id);
	struct mvod_pose I;
	mvod_pose_identity(&I);
	assert_mat_near(id.R, I.R, 9, 1e-12);
	assert_mat_near(id.t, I.t, 3, 1e-12);
	/* Composition applies b first: a * b maps p to a(b(p)). */
	struct mvod_pose b = a, ab;
	mvod_pose_compose(&a, &b, &ab);
	double p[3] = {0.3, 0.2, -1}, bp[3], abp[3], ref[3];
	mvod_mat3_vec(b.R, p, bp);
	for (int k = 0; k < 3; k++)
		bp[k] += b.t[k];
	mvod_mat3_vec(a.R, bp, ref);
	for (int k = 0; k < 3; k++)
		ref[k] += a.t[k];
	mvod_mat3_vec(ab.R, p, abp);
	for (int k = 0; k < 3; k++)
		abp[k] += ab.t[k];
	assert_mat_near(abp, ref, 3, 1e-12);
}

static void test_vec_angle(void **state)
{
	(void)state;
	double a[3] = {1, 0, 0}, b[3] = {1, 1, 0}, z[3] = {0, 0, 0};
	assert_true(fabs(mvod_vec3_angle(a, b) - M_PI / 4) < 1e-12);
	assert_true(mvod_vec3_angle(a, z) == 0.0);
}

/* Frobenius norm of R^T R - I. */
static double ortho_error(const double R[9])
{
	double e = 0;
	for (int r = 0; r < 3; r++)
		for (int c = 0; c < 3; c++) {
			double d = R[r] * R[c] + R[3 + r] * R[3 + c] + R[6 + r] * R[6 + c] - (r == c);
			e += d * d;
		}
	return sqrt(e);
}

/*
 * A rotation within the tolerance is left bit for bit. One stretched 0.16 off orthonormal (R0
 * times I + E, E symmetric: no rotation in the stretch, so R0 is the nearest rotation; map
 * mode's unprojected chain of predictions got to 0.23: mapvo.c, ROT_ORTHO_TOL) comes back to
 * a rotation, to rounding (1e-14), near R0: the quaternion read off the stretched matrix is
 * not exactly the nearest rotation, it moved R0 by 0.013 rad here; bound twice that.
 */
static void test_rot_reorthonormalise(void **state)
{
	(void)state;
	double w[3] = {0.3, -0.2, 0.5}, R[9], R0[9], bent[9], D[9];
	const double E[9] = {0.05, 0.02, -0.01, 0.02, -0.03, 0.015, -0.01, 0.015, 0.04};
	mvod_rot_exp(w, R);
	for (int i = 0; i < 9; i++)
		R0[i] = R[i];
	assert_false(mvod_rot_reorthonormalise(R, 1e-9));
	for (int i = 0; i < 9; i++)
		assert_true(R[i] == R0[i]);
	for (int r = 0; r < 3; r++) /* R0 (I + E) */
		for (int c = 0; c < 3; c++)
			bent[3 * r + c] = R0[3 * r + c] + R0[3 * r] * E[c] + R0[3 * r + 1] * E[3 + c] +
					  R0[3 * r + 2] * E[6 + c];
	assert_true(ortho_error(bent) > 0.15);
	assert_true(mvod_rot_reorthonormalise(bent, 1e-9));
	assert_true(ortho_error(bent) < 1e-14);
	assert_true(mvod_mat3_det(bent) > 0.999);
	for (int r = 0; r < 3; r++) /* R0^T bent: its angle is how far the projection moved R0 */
		for (int c = 0; c < 3; c++)
			D[3 * r + c] = R0[r] * bent[c] + R0[3 + r] * bent[3 + c] + R0[6 + r] * bent[6 + c];
	assert_true(mvod_rot_angle(D) < 0.026);
}

/* A system with a known solution (one row swap needed: A[0][0] = 0), and a singular one. */
static void test_linsolve(void **state)
{
	(void)state;
	double A[9] = {0, 2, 1, 1, 1, 1, 2, 1, 3}, x[3] = {1, 2, 3};
	double b[3] = {0, 0, 0};
	for (int r = 0; r < 3; r++)
		for (int c = 0; c < 3; c++)
			b[r] += A[3 * r + c] * x[c];
	assert_true(mvod_linsolve(A, b, 3));
	for (int i = 0; i < 3; i++) /* integers through a few divisions: 1e-12 is rounding */
		assert_true(fabs(b[i] - x[i]) < 1e-12);
	double S[4] = {1, 2, 2, 4}, y[2] = {1, 1};
	assert_false(mvod_linsolve(S, y, 2));
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_linsolve),
		cmocka_unit_test(test_quat_round_trip),
		cmocka_unit_test(test_quat_known_value),
		cmocka_unit_test(test_pose_inverse_compose),
		cmocka_unit_test(test_vec_angle),
		cmocka_unit_test(test_rot_reorthonormalise),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
