#include "posefit.h"

#include <errno.h>
#include <math.h>
#include <string.h>

#include "lsq.h"
#include "motion.h"
#include "mvod/geom.h"

/* The pose moved by d = (w, tau) on the left: R' = exp(w) R, t' = exp(w) t + tau. */
static void perturb(const double R[9], const double t[3], const double d[6], double Ro[9],
		    double to[3])
{
	double dR[9];
	mvod_rot_exp(d, dR);
	mvod_mat3_mul(dR, R, Ro);
	mvod_mat3_vec(dR, t, to);
	for (int k = 0; k < 3; k++)
		to[k] += d[3 + k];
}

/* The step from the previous frame to the current R, t (Rr = R Rp^T, tr = t - Rr tp), its E. */
static void relative(const struct mvod_posefit *p, const double R[9], const double t[3],
		     double Rr[9], double tr[3], double E[9])
{
	mvod_motion_between(p->Rp, p->tp, R, t, Rr, tr);
	mvod_motion_essential(Rr, tr, E);
}

static double huber_w(double r, double k)
{
	return r <= k ? 1.0 : k / r;
}

static double huber_c(double r, double k)
{
	return r <= k ? 0.5 * r * r : k * (r - 0.5 * k);
}

/* Map point i's reprojection residual (pixels) and its Jacobian (2 x 6) at R, t; false behind. */
static bool reproject(const struct mvod_posefit *p, const double R[9], const double t[3], int i,
		      double r[2], double J[12])
{
	double c[3];
	mvod_rigid_apply(R, t, p->X + 3 * i, c);
	if (!(c[2] > 1e-9))
		return false;
	double iz = 1.0 / c[2], fx = p->K[0], fy = p->K[1];
	double w = p->pt_sigma ? 1.0 / p->pt_sigma[i] : 1.0;
	r[0] = w * (fx * c[0] * iz + p->K[2] - p->uv[2 * i]);
	r[1] = w * (fy * c[1] * iz + p->K[3] - p->uv[2 * i + 1]);
	if (!J)
		return true;
	fx *= w;
	fy *= w;
	/* d(uv)/dc, then dc/d(w, tau) = [-[c]x | I]. */
	double du[3] = {fx * iz, 0, -fx * c[0] * iz * iz}, dv[3] = {0, fy * iz, -fy * c[1] * iz * iz};
	const double dc[9] = {0, c[2], -c[1], -c[2], 0, c[0], c[1], -c[0], 0};
	for (int q = 0; q < 3; q++) {
		J[q] = du[0] * dc[q] + du[1] * dc[3 + q] + du[2] * dc[6 + q];
		J[6 + q] = dv[0] * dc[q] + dv[1] * dc[3 + q] + dv[2] * dc[6 + q];
		J[3 + q] = du[q];
		J[9 + q] = dv[q];
	}
	return true;
}

/* Track i's Sampson distance in pixels (f) over its sigma: the factor to normalised units. */
static double epi_f(const struct mvod_posefit *p, double f, int i)
{
	return p->epi_sigma ? f / p->epi_sigma[i] : f;
}

/* Robust cost of the whole problem at R, t. */
static double cost(const struct mvod_posefit *p, const double R[9], const double t[3])
{
	double c = 0, r[2], Rr[9], tr[3], E[9], f = 0.5 * (p->K[0] + p->K[1]);
	for (int i = 0; i < p->n_pts; i++)
		if (p->use[i] && reproject(p, R, t, i, r, NULL))
			c += huber_c(hypot(r[0], r[1]), p->huber_px);
	relative(p, R, t, Rr, tr, E);
	for (int i = 0; i < p->n_epi; i++)
		if (p->epi_use[i])
			c += p->epi_weight *
			     huber_c(fabs(epi_f(p, f, i) *
					  mvod_motion_sampson(E, p->x1 + 2 * i, p->x2 + 2 * i)),
				     p->huber_px);
	return c;
}

/* Adds w J^T J and w J^T r of one residual row to A (6 x 6) and g. */
static void accumulate(const double J[6], double r, double w, double A[36], double g[6])
{
	for (int a = 0; a < 6; a++) {
		g[a] += w * J[a] * r;
		for (int b = 0; b < 6; b++)
			A[6 * a + b] += w * J[a] * J[b];
	}
}

/* The map points' normal equations at R, t. */
static void points_normal(const struct mvod_posefit *p, const double R[9], const double t[3],
			  double A[36], double g[6])
{
	double r[2], J[12];
	for (int i = 0; i < p->n_pts; i++) {
		if (!p->use[i] || !reproject(p, R, t, i, r, J))
			continue;
		double w = huber_w(hypot(r[0], r[1]), p->huber_px);
		accumulate(J, r[0], w, A, g);
		accumulate(J + 6, r[1], w, A, g);
	}
}

/* The epipolar tracks' normal equations at R, t (forward differences, 1e-7). */
static void epi_normal(const struct mvod_posefit *p, const double R[9], const double t[3],
		       double A[36], double g[6])
{
	const double h = 1e-7;
	double f = 0.5 * (p->K[0] + p->K[1]), Rr[9], tr[3], E[9], Eq[6][9];
	relative(p, R, t, Rr, tr, E);
	for (int q = 0; q < 6; q++) { /* the step moves as the pose does */
		double d[6] = {0}, Rq[9], tq[3];
		d[q] = h;
		perturb(Rr, tr, d, Rq, tq);
		mvod_motion_essential(Rq, tq, Eq[q]);
	}
	for (int i = 0; i < p->n_epi; i++) {
		if (!p->epi_use[i])
			continue;
		const double *x1 = p->x1 + 2 * i, *x2 = p->x2 + 2 * i;
		double fi = epi_f(p, f, i), r = fi * mvod_motion_sampson(E, x1, x2), J[6];
		for (int q = 0; q < 6; q++)
			J[q] = (fi * mvod_motion_sampson(Eq[q], x1, x2) - r) / h;
		accumulate(J, r, p->epi_weight * huber_w(fabs(r), p->huber_px), A, g);
	}
}

/* The tracks within the gate at the start pose. */
static int select_epi(struct mvod_posefit *p, const double R[9], const double t[3])
{
	double Rr[9], tr[3], E[9], f = 0.5 * (p->K[0] + p->K[1]);
	relative(p, R, t, Rr, tr, E);
	double len = mvod_vec3_norm(tr);
	int k = 0;
	for (int i = 0; i < p->n_epi; i++) {
		double r = fabs(epi_f(p, f, i) * mvod_motion_sampson(E, p->x1 + 2 * i, p->x2 + 2 * i));
		p->epi_use[i] = len > 0 && r <= p->epi_gate_px;
		k += p->epi_use[i];
	}
	return k;
}

/* The pose refinement as mvod_lsq_solve sees it: the state R (9) then t (3). */
static double lsq_cost(void *ctx, const double *x)
{
	return cost(ctx, x, x + 9);
}

static void lsq_normal(void *ctx, const double *x, double *A, double *g)
{
	points_normal(ctx, x, x + 9, A, g);
	epi_normal(ctx, x, x + 9, A, g);
}

static void lsq_move(void *ctx, const double *x, const double *d, double *out)
{
	perturb(x, x + 9, d, out, out + 9);
}

/*
 * Levenberg-Marquardt from PnP's pose, which is close: one try an iteration (a refused step
 * spends it; the next tries with ten times the damping), the damping from 1e-4.
 */
int mvod_posefit_refine(struct mvod_posefit *p, double R[9], double t[3])
{
	int used = select_epi(p, R, t);
	const struct mvod_lsq_problem lp = {6, 12, p, lsq_cost, lsq_normal, lsq_move, NULL};
	const struct mvod_lsq_options o = {.iterations = p->iterations, .tries = 1,
					   .lambda = 1e-4, .lambda_max = INFINITY,
					   .damping = MVOD_LSQ_SCALE};
	double x[12];
	memcpy(x, R, 9 * sizeof(double));
	memcpy(x + 9, t, 3 * sizeof(double));
	bool singular;
	mvod_lsq_solve(&lp, &o, x, &singular);
	memcpy(R, x, 9 * sizeof(double));
	memcpy(t, x + 9, 3 * sizeof(double));
	return singular ? -EINVAL : used;
}
