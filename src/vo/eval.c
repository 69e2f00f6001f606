#include "mvod/eval.h"

#include <errno.h>
#include <math.h>
#include <string.h>

#include "cv_shim.h"

#define RAD2DEG (180.0 / M_PI)

static double det3(const double A[9])
{
	return A[0] * (A[4] * A[8] - A[5] * A[7]) - A[1] * (A[3] * A[8] - A[5] * A[6]) +
	       A[2] * (A[3] * A[7] - A[4] * A[6]);
}

static void centroid(const double *p, int n, double c[3])
{
	c[0] = c[1] = c[2] = 0;
	for (int i = 0; i < n; i++)
		for (int k = 0; k < 3; k++)
			c[k] += p[3 * i + k] / n;
}

int mvod_umeyama(const double *src, const double *dst, int n, bool with_scale, double R[9],
		 double t[3], double *s)
{
	if (n < 3)
		return -EINVAL;
	double ms[3], md[3], C[9] = {0}, var = 0;
	centroid(src, n, ms);
	centroid(dst, n, md);
	for (int i = 0; i < n; i++) {
		double a[3], b[3];
		for (int k = 0; k < 3; k++) {
			a[k] = src[3 * i + k] - ms[k];
			b[k] = dst[3 * i + k] - md[k];
		}
		var += (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]) / n;
		for (int r = 0; r < 3; r++)
			for (int c = 0; c < 3; c++)
				C[3 * r + c] += b[r] * a[c] / n;
	}
	if (var < 1e-18)
		return -EINVAL;
	double U[9], D[3], Vt[9];
	int ret = mvod_cv_svd3(C, U, D, Vt);
	if (ret)
		return ret;
	double S[3] = {1, 1, det3(U) * det3(Vt) < 0 ? -1 : 1};
	for (int r = 0; r < 3; r++)
		for (int c = 0; c < 3; c++)
			R[3 * r + c] = U[3 * r] * S[0] * Vt[c] + U[3 * r + 1] * S[1] * Vt[3 + c] +
				       U[3 * r + 2] * S[2] * Vt[6 + c];
	*s = with_scale ? (D[0] * S[0] + D[1] * S[1] + D[2] * S[2]) / var : 1.0;
	double Rm[3];
	mvod_mat3_vec(R, ms, Rm);
	for (int k = 0; k < 3; k++)
		t[k] = md[k] - *s * Rm[k];
	return 0;
}

double mvod_ate_rmse(const double *src, const double *dst, int n, const double R[9],
		     const double t[3], double s)
{
	double sum = 0;
	for (int i = 0; i < n; i++) {
		double p[3];
		mvod_mat3_vec(R, src + 3 * i, p);
		for (int k = 0; k < 3; k++) {
			double d = s * p[k] + t[k] - dst[3 * i + k];
			sum += d * d;
		}
	}
	return n ? sqrt(sum / n) : 0.0;
}

/* Relative motion from pose a to pose b, expressed in a's frame: a^-1 b. */
static void relative(const struct mvod_pose *a, const struct mvod_pose *b, struct mvod_pose *out)
{
	struct mvod_pose ia;
	mvod_pose_inverse(a, &ia);
	mvod_pose_compose(&ia, b, out);
}

void mvod_rpe_add(struct mvod_rpe *acc, const struct mvod_pose *e0, const struct mvod_pose *e1,
		  const struct mvod_pose *g0, const struct mvod_pose *g1)
{
	struct mvod_pose de, dg;
	relative(e0, e1, &de);
	relative(g0, g1, &dg);
	double dR[9];
	mvod_mat3_mul_bt(de.R, dg.R, dR);
	double rot = mvod_rot_angle(dR) * RAD2DEG;
	acc->rot_deg_mean += rot;
	if (rot > acc->rot_deg_max)
		acc->rot_deg_max = rot;
	acc->n++;
	/* Direction only where both steps are measurable (a held or static frame has none). */
	if (mvod_vec3_norm(dg.t) > 1e-3 && mvod_vec3_norm(de.t) > 1e-9) {
		double dir = mvod_vec3_angle(de.t, dg.t) * RAD2DEG;
		acc->dir_deg_mean += dir;
		if (dir > acc->dir_deg_max)
			acc->dir_deg_max = dir;
		acc->n_dir++;
	}
}

void mvod_rpe_finish(struct mvod_rpe *acc)
{
	if (acc->n)
		acc->rot_deg_mean /= acc->n;
	if (acc->n_dir)
		acc->dir_deg_mean /= acc->n_dir;
}
