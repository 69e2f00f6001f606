/*
 * Map mode's windowed bundle adjustment without Ceres (ba_lm.h): Ceres's trust-region
 * Levenberg-Marquardt as mvod's window uses it (DENSE_SCHUR, Jacobi scaling, Huber loss),
 * written for this one problem, on buffers sized at create time.
 *
 * Why: Ceres spent about 8e6 instructions a frame on KITTI 06 (callgrind, --scale gt) on
 * windows of 2-7 keyframes, 100-250 points and 2-3 steps, most of it in its general
 * machinery (problem build, program reduction and ordering, block-sparse bookkeeping and
 * allocation: about 3 800 allocations a frame). The same steps here cost about a quarter of
 * that (BENCHMARKS.md, mapspeed3).
 *
 * What it follows of Ceres 2.1 (TrustRegionMinimizer, LevenbergMarquardtStrategy,
 * SchurEliminator): the cost 0.5 sum rho(|r|^2); Huber's rho'' <= 0, so residuals and
 * Jacobians are scaled by sqrt(rho') (Ceres's Corrector then); Jacobi scaling of the columns
 * by 1 / (1 + |column|) fixed at the start; the step solves (J^T J + D^2 / mu) y = -J^T r with
 * D^2 the diagonal of J^T J clamped to [1e-6, 1e32]; mu starts at 1e4, an accepted step
 * (relative decrease > 1e-3) divides it by max(1/3, 1 - (2 rho - 1)^3), a refused one
 * multiplies it by 1/2, 1/4, 1/8, ...; a candidate whose point goes behind a camera is
 * refused; the stops (iterations, gradient 1e-10, parameter 1e-8, function tolerance: the
 * candidate within tolerance is not taken). The floating-point order is not Ceres's, so
 * results agree with Ceres's to rounding, not bit for bit.
 */
#include "ba_lm.h"

#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* lm_step keeps one point's blocks on the stack: a window of at most this many poses. */
#define LM_POSE_CAP 64
#define LM_RADIUS0 1e4
#define LM_MAX_RADIUS 1e16
#define LM_MIN_RADIUS 1e-32
#define LM_MIN_DIAGONAL 1e-6
#define LM_MAX_DIAGONAL 1e32
#define LM_MIN_RELATIVE_DECREASE 1e-3
#define LM_GRADIENT_TOLERANCE 1e-10
#define LM_PARAMETER_TOLERANCE 1e-8
#define LM_FUNCTION_TOLERANCE 1e-6 /* Ceres's default, when the options give 0 */

/* One observation's corrected residual and Jacobians (scaled columns): 2x6 pose, 2x3 point. */
struct lm_obs {
	double r[2], Jp[12], Jx[6];
};

struct mvod_ba_lm {
	int pose_cap, point_cap, obs_cap;
	struct lm_obs *o;      /* [obs_cap] */
	int *by_point;         /* [obs_cap] active observations grouped by point */
	int *start;            /* [point_cap + 1] */
	int *free_idx;         /* [pose_cap] pose -> column block, -1 held or unobserved */
	double *sc_pose;       /* [pose_cap * 6] Jacobi scaling */
	double *sc_pt;         /* [point_cap * 3] */
	double *V;             /* [point_cap * 9] point blocks, then their inverses */
	double *gx;            /* [point_cap * 3] J^T r, points */
	double *yx;            /* [point_cap * 3] step, points (scaled) */
	double *dpt;           /* [point_cap * 3] point diagonal (undamped) */
	double *S, *Sd;        /* [(6 pose_cap)^2], reduced camera matrix; [6 pose_cap] its diagonal */
	double *gc, *yc;       /* [6 pose_cap] */
	double *WV;            /* [LM_POSE_CAP * 18] W_i V^-1 of one point */
	double *cand_poses;    /* [pose_cap * 6] */
	double *cand_pts;      /* [point_cap * 3] */
	uint8_t *pt_used;      /* [point_cap] */
	double *rot;           /* [pose_cap * 36] per pose R (9), then dR/d aa_k (27, k-major) */
};

int mvod_ba_lm_create(int pose_cap, int point_cap, int obs_cap, struct mvod_ba_lm **out)
{
	*out = NULL;
	if (pose_cap < 1 || pose_cap > LM_POSE_CAP || point_cap < 1 || obs_cap < 1)
		return -EINVAL;
	struct mvod_ba_lm *b = calloc(1, sizeof(*b));
	if (!b)
		return -ENOMEM;
	size_t nk = (size_t)pose_cap, np = (size_t)point_cap, no = (size_t)obs_cap, nc = 6 * nk;
	b->pose_cap = pose_cap;
	b->point_cap = point_cap;
	b->obs_cap = obs_cap;
	b->o = calloc(no, sizeof(*b->o));
	b->by_point = calloc(no, sizeof(int));
	b->start = calloc(np + 1, sizeof(int));
	b->free_idx = calloc(nk, sizeof(int));
	b->sc_pose = calloc(nk * 6, sizeof(double));
	b->sc_pt = calloc(np * 3, sizeof(double));
	b->V = calloc(np * 9, sizeof(double));
	b->gx = calloc(np * 3, sizeof(double));
	b->yx = calloc(np * 3, sizeof(double));
	b->dpt = calloc(np * 3, sizeof(double));
	b->S = calloc(nc * nc, sizeof(double));
	b->Sd = calloc(nc, sizeof(double));
	b->gc = calloc(nc, sizeof(double));
	b->yc = calloc(nc, sizeof(double));
	b->WV = calloc(LM_POSE_CAP * 18, sizeof(double));
	b->cand_poses = calloc(nk * 6, sizeof(double));
	b->cand_pts = calloc(np * 3, sizeof(double));
	b->pt_used = calloc(np, 1);
	b->rot = calloc(nk * 36, sizeof(double));
	if (!b->o || !b->by_point || !b->start || !b->free_idx || !b->sc_pose || !b->sc_pt ||
	    !b->V || !b->gx || !b->yx || !b->dpt || !b->S || !b->Sd || !b->gc || !b->yc ||
	    !b->WV || !b->cand_poses || !b->cand_pts || !b->pt_used ||
	    !b->rot) {
		mvod_ba_lm_destroy(b);
		return -ENOMEM;
	}
	*out = b;
	return 0;
}

void mvod_ba_lm_destroy(struct mvod_ba_lm *b)
{
	if (!b)
		return;
	free(b->o);
	free(b->by_point);
	free(b->start);
	free(b->free_idx);
	free(b->sc_pose);
	free(b->sc_pt);
	free(b->V);
	free(b->gx);
	free(b->yx);
	free(b->dpt);
	free(b->S);
	free(b->Sd);
	free(b->gc);
	free(b->yc);
	free(b->WV);
	free(b->cand_poses);
	free(b->cand_pts);
	free(b->pt_used);
	free(b->rot);
	free(b);
}

/*
 * R(aa) X as ceres::AngleAxisRotatePoint (the small-angle branch below epsilon), with the
 * derivatives with respect to aa when asked (dr, 3x3 row-major: dr[3 i + k] = d q_i / d aa_k).
 */
static void rotate(const double aa[3], const double X[3], double q[3], double *dr)
{
	const double theta2 = aa[0] * aa[0] + aa[1] * aa[1] + aa[2] * aa[2];
	if (theta2 > DBL_EPSILON) {
		const double th = sqrt(theta2), c = cos(th), s = sin(th), ti = 1.0 / th;
		const double w[3] = {aa[0] * ti, aa[1] * ti, aa[2] * ti};
		const double wx[3] = {w[1] * X[2] - w[2] * X[1], w[2] * X[0] - w[0] * X[2],
				      w[0] * X[1] - w[1] * X[0]};
		const double dot = w[0] * X[0] + w[1] * X[1] + w[2] * X[2], omc = 1.0 - c;
		for (int i = 0; i < 3; i++)
			q[i] = X[i] * c + wx[i] * s + w[i] * dot * omc;
		if (dr) {
			/* d th / d aa_k = w_k; d w_i / d aa_k = (delta_ik - w_i w_k) / th */
			double w_r[3][3];
			for (int i = 0; i < 3; i++)
				for (int k = 0; k < 3; k++)
					w_r[i][k] = ((i == k ? 1.0 : 0.0) - w[i] * w[k]) * ti;
			for (int i = 0; i < 3; i++) {
				const int j = (i + 1) % 3, l = (i + 2) % 3;
				for (int k = 0; k < 3; k++) {
					const double wx_r = w_r[j][k] * X[l] - w_r[l][k] * X[j];
					const double dot_r = w_r[0][k] * X[0] + w_r[1][k] * X[1] +
							     w_r[2][k] * X[2];
					dr[3 * i + k] = -X[i] * s * w[k] + wx_r * s + wx[i] * c * w[k] +
							w_r[i][k] * dot * omc + w[i] * dot_r * omc +
							w[i] * dot * s * w[k];
				}
			}
		}
	} else {
		for (int i = 0; i < 3; i++) {
			const int j = (i + 1) % 3, l = (i + 2) % 3;
			q[i] = X[i] + (aa[j] * X[l] - aa[l] * X[j]);
			if (dr)
				for (int k = 0; k < 3; k++)
					dr[3 * i + k] = (k == j ? X[l] : 0.0) - (k == l ? X[j] : 0.0);
		}
	}
}

/*
 * Each pose's rotation R(aa) and, with deriv, its derivatives dR/d aa_k, column by column
 * through rotate() (R(aa) X is linear in X): an observation then costs a matrix product
 * instead of a sine and cosine. rot[36 k]: R row-major, then dR/d aa_0, _1, _2 row-major.
 */
static void rotations(struct mvod_ba_lm *b, const double *poses, int n, bool deriv)
{
	for (int k = 0; k < n; k++) {
		double *R = b->rot + 36 * k;
		for (int m = 0; m < 3; m++) {
			const double e[3] = {m == 0, m == 1, m == 2};
			double q[3], dr[9];
			rotate(poses + 6 * k, e, q, deriv ? dr : NULL);
			for (int i = 0; i < 3; i++) {
				R[3 * i + m] = q[i];
				for (int a = 0; deriv && a < 3; a++)
					R[9 + 9 * a + 3 * i + m] = dr[3 * i + a];
			}
		}
	}
}

/*
 * Observation o's residual in sigma units at pose (its rotation in rot, rotations()) and X;
 * with Jp and Jx its Jacobians (2x6, 2x3; rot's derivatives needed). False when the point is
 * at or behind the camera.
 */
static bool residual(const struct mvod_ba_problem *p, const struct mvod_ba_obs *o,
		     const double *rot, const double *pose, const double *X, double r[2],
		     double *Jp, double *Jx)
{
	double q[3];
	for (int i = 0; i < 3; i++)
		q[i] = rot[3 * i] * X[0] + rot[3 * i + 1] * X[1] + rot[3 * i + 2] * X[2] + pose[3 + i];
	const double z = q[2];
	if (!(z > 0))
		return false;
	const double iz = 1.0 / z, is = 1.0 / o->sigma, f[2] = {p->fx, p->fy},
		     c[2] = {p->cx, p->cy}, m[2] = {o->u, o->v};
	double dr[9]; /* d(R X)_i / d aa_k */
	if (Jp)
		for (int i = 0; i < 3; i++)
			for (int k = 0; k < 3; k++) {
				const double *D = rot + 9 + 9 * k + 3 * i;
				dr[3 * i + k] = D[0] * X[0] + D[1] * X[1] + D[2] * X[2];
			}
	for (int i = 0; i < 2; i++) {
		const double proj = f[i] * q[i] * iz;
		r[i] = (proj + c[i] - m[i]) * is;
		if (!Jp)
			continue;
		/* d r_i = (f_i d p_i - proj d p_2) / z / sigma */
		const double a = f[i] * iz * is, bb = proj * iz * is;
		for (int k = 0; k < 3; k++) {
			Jp[6 * i + k] = a * dr[3 * i + k] - bb * dr[6 + k];
			Jp[6 * i + 3 + k] = (k == i ? a : 0.0) - (k == 2 ? bb : 0.0);
			Jx[3 * i + k] = a * rot[3 * i + k] - bb * rot[6 + k];
		}
	}
	return true;
}

/* Huber's rho(s) and sqrt(rho'(s)) for s = |r|^2. */
static double huber(double s, double d, double *sqrt_rho1)
{
	const double d2 = d * d;
	if (s <= d2) {
		if (sqrt_rho1)
			*sqrt_rho1 = 1.0;
		return s;
	}
	const double rs = sqrt(s);
	if (sqrt_rho1)
		*sqrt_rho1 = sqrt(d / rs);
	return 2.0 * d * rs - d2;
}

/* The cost 0.5 sum rho at poses/points, or DBL_MAX when a point is at or behind a camera. */
static double cost_at(struct mvod_ba_lm *b, const struct mvod_ba_problem *p,
		      const struct mvod_ba_options *op, const double *poses, const double *points)
{
	double c = 0;
	rotations(b, poses, p->n_poses, false);
	for (int i = 0; i < p->n_obs; i++) {
		if (p->outlier[i])
			continue;
		const struct mvod_ba_obs *o = &p->obs[i];
		double r[2];
		if (!residual(p, o, b->rot + 36 * o->pose, poses + 6 * o->pose, points + 3 * o->point,
			      r, NULL, NULL))
			return DBL_MAX;
		c += huber(r[0] * r[0] + r[1] * r[1], op->huber, NULL);
	}
	return 0.5 * c;
}

/*
 * Observation i's corrected residual and Jacobians into b->o (Huber's sqrt(rho') applied) and
 * its share of the unscaled gradient and, at the first call (first), of the Jacobi scaling.
 * False when its point is behind its camera.
 */
static bool linearize_obs(struct mvod_ba_lm *b, const struct mvod_ba_problem *p,
			  const struct mvod_ba_options *op, bool first, int i)
{
	const struct mvod_ba_obs *o = &p->obs[i];
	struct lm_obs *e = &b->o[i];
	if (!residual(p, o, b->rot + 36 * o->pose, p->poses + 6 * o->pose,
		      p->points + 3 * o->point, e->r, e->Jp, e->Jx))
		return false;
	double k;
	huber(e->r[0] * e->r[0] + e->r[1] * e->r[1], op->huber, &k);
	if (k != 1.0) {
		e->r[0] *= k;
		e->r[1] *= k;
		for (int c = 0; c < 12; c++)
			e->Jp[c] *= k;
		for (int c = 0; c < 6; c++)
			e->Jx[c] *= k;
	}
	const bool freep = b->free_idx[o->pose] >= 0;
	for (int c = 0; c < 6 && freep; c++) {
		b->gc[6 * o->pose + c] += e->Jp[c] * e->r[0] + e->Jp[6 + c] * e->r[1];
		if (first)
			b->sc_pose[6 * o->pose + c] += e->Jp[c] * e->Jp[c] + e->Jp[6 + c] * e->Jp[6 + c];
	}
	for (int c = 0; c < 3; c++) {
		b->gx[3 * o->point + c] += e->Jx[c] * e->r[0] + e->Jx[3 + c] * e->r[1];
		if (first)
			b->sc_pt[3 * o->point + c] += e->Jx[c] * e->Jx[c] + e->Jx[3 + c] * e->Jx[3 + c];
	}
	return true;
}

/*
 * The unscaled gradient's largest entry; at the first call the Jacobi scaling from the sums;
 * then the Jacobians' columns and the gradients scaled.
 */
static double scale_columns(struct mvod_ba_lm *b, const struct mvod_ba_problem *p, bool first)
{
	double g = 0;
	for (int c = 0; c < 6 * p->n_poses; c++)
		g = fmax(g, fabs(b->gc[c]));
	for (int c = 0; c < 3 * p->n_points; c++)
		g = fmax(g, fabs(b->gx[c]));
	if (first) {
		for (int c = 0; c < 6 * p->n_poses; c++)
			b->sc_pose[c] = 1.0 / (1.0 + sqrt(b->sc_pose[c]));
		for (int c = 0; c < 3 * p->n_points; c++)
			b->sc_pt[c] = 1.0 / (1.0 + sqrt(b->sc_pt[c]));
	}
	for (int i = 0; i < p->n_obs; i++) {
		if (p->outlier[i])
			continue;
		const struct mvod_ba_obs *o = &p->obs[i];
		struct lm_obs *e = &b->o[i];
		for (int c = 0; c < 6; c++) {
			e->Jp[c] *= b->sc_pose[6 * o->pose + c];
			e->Jp[6 + c] *= b->sc_pose[6 * o->pose + c];
		}
		for (int c = 0; c < 3; c++) {
			e->Jx[c] *= b->sc_pt[3 * o->point + c];
			e->Jx[3 + c] *= b->sc_pt[3 * o->point + c];
		}
	}
	/* scaled gradients for the step */
	for (int c = 0; c < 6 * p->n_poses; c++)
		b->gc[c] *= b->sc_pose[c];
	for (int c = 0; c < 3 * p->n_points; c++)
		b->gx[c] *= b->sc_pt[c];
	return g;
}

/*
 * Corrected residuals and Jacobians at the problem's poses/points into b->o; at the first
 * call (first) the Jacobi scaling from them; then the Jacobians' columns scaled. The
 * unscaled gradient's largest entry into *gmax. False when a point is behind a camera.
 */
static bool linearize(struct mvod_ba_lm *b, const struct mvod_ba_problem *p,
		      const struct mvod_ba_options *op, bool first, double *gmax)
{
	if (first) {
		memset(b->sc_pose, 0, sizeof(double) * 6 * (size_t)p->n_poses);
		memset(b->sc_pt, 0, sizeof(double) * 3 * (size_t)p->n_points);
	}
	memset(b->gc, 0, sizeof(double) * 6 * (size_t)p->n_poses);
	memset(b->gx, 0, sizeof(double) * 3 * (size_t)p->n_points);
	rotations(b, p->poses, p->n_poses, true);
	for (int i = 0; i < p->n_obs; i++)
		if (!p->outlier[i] && !linearize_obs(b, p, op, first, i))
			return false;
	*gmax = scale_columns(b, p, first);
	return true;
}

static double clamp_diag(double d)
{
	return fmin(fmax(d, LM_MIN_DIAGONAL), LM_MAX_DIAGONAL);
}

/* In-place inverse of a symmetric positive definite 3x3; false when it is not. */
static bool inv3(double *A)
{
	const double a = A[0], b = A[1], c = A[2], d = A[4], e = A[5], f = A[8];
	const double c00 = d * f - e * e, c01 = c * e - b * f, c02 = b * e - c * d;
	const double det = a * c00 + b * c01 + c * c02;
	if (!(det > 0) || !(a > 0))
		return false;
	const double id = 1.0 / det;
	A[0] = c00 * id;
	A[1] = A[3] = c01 * id;
	A[2] = A[6] = c02 * id;
	A[4] = (a * f - c * c) * id;
	A[5] = A[7] = (b * c - a * e) * id;
	A[8] = (a * d - b * b) * id;
	return true;
}

/* Cholesky solve of the n x n (row-major, leading dimension ld) system A y = g, in place. */
static bool chol_solve(double *A, int n, int ld, double *y)
{
	for (int j = 0; j < n; j++) {
		double d = A[ld * j + j];
		for (int k = 0; k < j; k++)
			d -= A[ld * j + k] * A[ld * j + k];
		if (!(d > 0))
			return false;
		d = sqrt(d);
		A[ld * j + j] = d;
		for (int i = j + 1; i < n; i++) {
			double s = A[ld * i + j];
			for (int k = 0; k < j; k++)
				s -= A[ld * i + k] * A[ld * j + k];
			A[ld * i + j] = s / d;
		}
	}
	for (int i = 0; i < n; i++) {
		double s = y[i];
		for (int k = 0; k < i; k++)
			s -= A[ld * i + k] * y[k];
		y[i] = s / A[ld * i + i];
	}
	for (int i = n - 1; i >= 0; i--) {
		double s = y[i];
		for (int k = i + 1; k < n; k++)
			s -= A[ld * k + i] * y[k];
		y[i] = s / A[ld * i + i];
	}
	return true;
}

/*
 * The reduced camera system's start: S (nc x nc, leading dimension ld) holds the free poses'
 * blocks U = sum Jp^T Jp (upper triangle), damped by their diagonal D^2 / mu; rhs = -g_c.
 */
static void camera_blocks(struct mvod_ba_lm *b, const struct mvod_ba_problem *p, int nf,
			  double mu, double *rhs)
{
	const int nc = 6 * nf, ld = 6 * b->pose_cap;
	for (int i = 0; i < nc; i++)
		memset(b->S + (size_t)ld * i, 0, sizeof(double) * (size_t)nc);
	memset(rhs, 0, sizeof(double) * (size_t)nc);
	for (int i = 0; i < p->n_obs; i++) {
		if (p->outlier[i])
			continue;
		const int f = b->free_idx[p->obs[i].pose];
		if (f < 0)
			continue;
		const struct lm_obs *e = &b->o[i];
		double *U = b->S + (size_t)ld * 6 * f + 6 * f;
		for (int r = 0; r < 6; r++)
			for (int c = r; c < 6; c++)
				U[ld * r + c] += e->Jp[r] * e->Jp[c] + e->Jp[6 + r] * e->Jp[6 + c];
	}
	for (int k = 0; k < p->n_poses; k++) {
		const int f = b->free_idx[k];
		if (f < 0)
			continue;
		for (int c = 0; c < 6; c++) {
			double *d = &b->S[(size_t)ld * (6 * f + c) + 6 * f + c];
			*d += clamp_diag(*d) / mu;
			rhs[6 * f + c] = -b->gc[6 * k + c];
		}
	}
}

/*
 * Point pt's blocks: V = sum Jx^T Jx + D^2 / mu, inverted into b->V, and W (6x3, columns
 * contiguous: W[a][6 * k + r] is row r, column k) of each observation of a free pose, whose
 * column block goes into wf; *nw of them. False when V is not positive definite.
 */
static bool point_blocks(struct mvod_ba_lm *b, const struct mvod_ba_problem *p, int pt,
			 double mu, double W[][18], int *wf, int *nw)
{
	double V[9] = {0};
	*nw = 0;
	for (int s = b->start[pt]; s < b->start[pt + 1]; s++) {
		const int i = b->by_point[s];
		const struct lm_obs *e = &b->o[i];
		for (int r = 0; r < 3; r++)
			for (int c = r; c < 3; c++)
				V[3 * r + c] += e->Jx[r] * e->Jx[c] + e->Jx[3 + r] * e->Jx[3 + c];
		const int f = b->free_idx[p->obs[i].pose];
		if (f < 0)
			continue;
		wf[*nw] = f;
		for (int r = 0; r < 6; r++)
			for (int c = 0; c < 3; c++)
				W[*nw][6 * c + r] = e->Jp[r] * e->Jx[c] + e->Jp[6 + r] * e->Jx[3 + c];
		(*nw)++;
	}
	for (int c = 0; c < 3; c++)
		V[4 * c] += clamp_diag(V[4 * c]) / mu;
	V[3] = V[1];
	V[6] = V[2];
	V[7] = V[5];
	if (!inv3(V))
		return false;
	memcpy(b->V + 9 * pt, V, sizeof(V));
	return true;
}

/* Point pt eliminated: WV_a = W_a V^-1 (6x3); rhs_a -= WV_a (-g); S_ab -= WV_a W_b^T. */
static void eliminate(struct mvod_ba_lm *b, int pt, double W[][18], const int *wf, int nw,
		      double *rhs)
{
	const int ld = 6 * b->pose_cap;
	const double *V = b->V + 9 * pt, *g = b->gx + 3 * pt;
	for (int a = 0; a < nw; a++) {
		double *wv = b->WV + 18 * a;
		for (int r = 0; r < 6; r++)
			for (int c = 0; c < 3; c++)
				wv[3 * r + c] = W[a][r] * V[c] + W[a][6 + r] * V[3 + c] +
						W[a][12 + r] * V[6 + c];
		for (int r = 0; r < 6; r++)
			rhs[6 * wf[a] + r] += wv[3 * r] * g[0] + wv[3 * r + 1] * g[1] +
					      wv[3 * r + 2] * g[2];
		/*
		 * The upper triangle of S: a block on its diagonal from c = r, a block above it
		 * whole. No test in the inner loop, W's columns contiguous: lm_step 453e6 -> 418e6
		 * instructions over the KITTI 07 clip, the sums the same, term by term and in
		 * order (BENCHMARKS.md).
		 */
		for (int c2 = 0; c2 < nw; c2++) {
			if (wf[c2] < wf[a])
				continue;
			double *B = b->S + (size_t)ld * 6 * wf[a] + 6 * wf[c2];
			const double *w = W[c2];
			for (int r = 0; r < 6; r++) {
				const double x = wv[3 * r], y = wv[3 * r + 1], z = wv[3 * r + 2];
				for (int c = wf[c2] == wf[a] ? r : 0; c < 6; c++)
					B[ld * r + c] -= x * w[c] + y * w[6 + c] + z * w[12 + c];
			}
		}
	}
}

/* The points' step from the cameras': y_x = V^-1 (-g_x - sum W^T y_c), W^T y = Jx^T (Jp y). */
static void back_substitute(struct mvod_ba_lm *b, const struct mvod_ba_problem *p)
{
	for (int pt = 0; pt < p->n_points; pt++) {
		if (!b->pt_used[pt])
			continue;
		double t[3] = {-b->gx[3 * pt], -b->gx[3 * pt + 1], -b->gx[3 * pt + 2]};
		for (int s = b->start[pt]; s < b->start[pt + 1]; s++) {
			const int i = b->by_point[s];
			const int k = p->obs[i].pose;
			if (b->free_idx[k] < 0)
				continue;
			const struct lm_obs *e = &b->o[i];
			double jy[2] = {0, 0};
			for (int c = 0; c < 6; c++) {
				jy[0] += e->Jp[c] * b->yc[6 * k + c];
				jy[1] += e->Jp[6 + c] * b->yc[6 * k + c];
			}
			for (int c = 0; c < 3; c++)
				t[c] -= e->Jx[c] * jy[0] + e->Jx[3 + c] * jy[1];
		}
		const double *Vi = b->V + 9 * pt;
		for (int c = 0; c < 3; c++)
			b->yx[3 * pt + c] = Vi[3 * c] * t[0] + Vi[3 * c + 1] * t[1] + Vi[3 * c + 2] * t[2];
	}
}

/* The model's cost change for the step: -(m . (r + m / 2)), m = J y. */
static double model_change(const struct mvod_ba_lm *b, const struct mvod_ba_problem *p)
{
	double mc = 0;
	for (int i = 0; i < p->n_obs; i++) {
		if (p->outlier[i])
			continue;
		const struct mvod_ba_obs *o = &p->obs[i];
		const struct lm_obs *e = &b->o[i];
		const double *yc = b->yc + 6 * o->pose, *yx = b->yx + 3 * o->point;
		double m[2] = {0, 0};
		for (int c = 0; c < 6; c++) {
			m[0] += e->Jp[c] * yc[c];
			m[1] += e->Jp[6 + c] * yc[c];
		}
		for (int c = 0; c < 3; c++) {
			m[0] += e->Jx[c] * yx[c];
			m[1] += e->Jx[3 + c] * yx[c];
		}
		mc -= m[0] * (e->r[0] + 0.5 * m[0]) + m[1] * (e->r[1] + 0.5 * m[1]);
	}
	return mc;
}

/*
 * The damped step (J^T J + D^2 / mu) y = -J^T r by the Schur complement on the points, in
 * scaled coordinates (b->yc by pose index, b->yx), with the model's cost change. The
 * undamped diagonals are this linearization's, as Ceres's across refused steps. False when
 * a system is not positive definite.
 */
static bool lm_step(struct mvod_ba_lm *b, const struct mvod_ba_problem *p, int nf, double mu,
		    double *model)
{
	const int nc = 6 * nf, ld = 6 * b->pose_cap;
	double rhs[6 * LM_POSE_CAP];
	camera_blocks(b, p, nf, mu, rhs);
	for (int pt = 0; pt < p->n_points; pt++) {
		double W[LM_POSE_CAP][18];
		int wf[LM_POSE_CAP], nw;
		if (!b->pt_used[pt])
			continue;
		if (!point_blocks(b, p, pt, mu, W, wf, &nw))
			return false;
		eliminate(b, pt, W, wf, nw, rhs);
	}
	/* symmetric: the upper triangle is filled, copy it down */
	for (int r = 0; r < nc; r++)
		for (int c = 0; c < r; c++)
			b->S[(size_t)ld * r + c] = b->S[(size_t)ld * c + r];
	if (nc > 0 && !chol_solve(b->S, nc, ld, rhs))
		return false;
	for (int k = 0; k < p->n_poses; k++) {
		const int f = b->free_idx[k];
		for (int c = 0; c < 6; c++)
			b->yc[6 * k + c] = f < 0 ? 0.0 : rhs[6 * f + c];
	}
	back_substitute(b, p);
	*model = model_change(b, p);
	return true;
}

static void flag_outliers(struct mvod_ba_lm *b, const struct mvod_ba_problem *p, double chi2,
			  int *n)
{
	*n = 0;
	rotations(b, p->poses, p->n_poses, false);
	for (int i = 0; i < p->n_obs; i++) {
		const struct mvod_ba_obs *o = &p->obs[i];
		if (!p->outlier[i]) {
			double r[2];
			p->outlier[i] = !residual(p, o, b->rot + 36 * o->pose, p->poses + 6 * o->pose,
						  p->points + 3 * o->point, r, NULL, NULL) ||
					r[0] * r[0] + r[1] * r[1] > chi2;
		}
		*n += p->outlier[i];
	}
}

static bool valid(const struct mvod_ba_lm *b, const struct mvod_ba_problem *p)
{
	if (p->n_poses < 0 || p->n_points < 0 || p->n_obs < 0 || !(p->fx > 0) || !(p->fy > 0) ||
	    p->n_poses > b->pose_cap || p->n_points > b->point_cap || p->n_obs > b->obs_cap)
		return false;
	for (int i = 0; i < p->n_obs; i++) {
		const struct mvod_ba_obs *o = &p->obs[i];
		if (o->pose < 0 || o->pose >= p->n_poses || o->point < 0 || o->point >= p->n_points ||
		    !(o->sigma > 0) || !isfinite(o->u) || !isfinite(o->v))
			return false;
	}
	return true;
}

/*
 * One block of the candidate: cand = x + y * sc (the step unscaled from Jacobi's columns), its
 * squared norm into *dn and the parameters' into *xn.
 */
static void candidate(int dim, const double *x, const double *y, const double *sc, double *cand,
		      double *dn, double *xn)
{
	for (int c = 0; c < dim; c++) {
		double d = y[c] * sc[c];
		cand[c] = x[c] + d;
		*dn += d * d;
		*xn += x[c] * x[c];
	}
}

/*
 * The observations behind their camera leave (flagged); the rest are grouped by point
 * (b->start, b->by_point), their points used and their poses observed; the free poses (observed,
 * not held) numbered into b->free_idx (-1: none). Returns how many are free, or -EINVAL when a
 * point has more observations than lm_step's blocks hold. *n_active: the observations kept.
 */
static int group(struct mvod_ba_lm *b, const struct mvod_ba_problem *p, int *n_active)
{
	memset(b->start, 0, sizeof(int) * ((size_t)p->n_points + 1));
	memset(b->pt_used, 0, (size_t)p->n_points);
	for (int k = 0; k < p->n_poses; k++)
		b->free_idx[k] = -1;
	*n_active = 0;
	rotations(b, p->poses, p->n_poses, false);
	for (int i = 0; i < p->n_obs; i++) {
		const struct mvod_ba_obs *o = &p->obs[i];
		double r[2];
		p->outlier[i] = !residual(p, o, b->rot + 36 * o->pose, p->poses + 6 * o->pose,
					  p->points + 3 * o->point, r, NULL, NULL);
		if (p->outlier[i])
			continue;
		(*n_active)++;
		b->start[o->point + 1]++;
		b->pt_used[o->point] = 1;
		b->free_idx[o->pose] = -2; /* observed */
	}
	for (int pt = 0; pt < p->n_points; pt++)
		if (b->start[pt + 1] > LM_POSE_CAP) /* lm_step's blocks of one point */
			return -EINVAL;
	int nf = 0;
	for (int k = 0; k < p->n_poses; k++)
		b->free_idx[k] = b->free_idx[k] == -2 && !(p->fixed && p->fixed[k]) ? nf++ : -1;
	for (int pt = 0; pt < p->n_points; pt++)
		b->start[pt + 1] += b->start[pt];
	/* by_point[--start[pt + 1]] fills each range from its end, leaving start[pt + 1] at the
	 * range's beginning: shift back by one */
	for (int i = p->n_obs - 1; i >= 0; i--)
		if (!p->outlier[i])
			b->by_point[--b->start[p->obs[i].point + 1]] = i;
	for (int pt = 0; pt < p->n_points; pt++)
		b->start[pt] = b->start[pt + 1];
	b->start[p->n_points] = *n_active;
	return nf;
}

/*
 * The candidate x + y (unscaled) of the step just solved into b->cand_*, the blocks it does
 * not move copied; true when the step is too small against the parameters to go on (Ceres's
 * parameter tolerance).
 */
static bool make_candidate(struct mvod_ba_lm *b, const struct mvod_ba_problem *p)
{
	double dn = 0, xn = 0;
	for (int k = 0; k < p->n_poses; k++)
		if (b->free_idx[k] >= 0)
			candidate(6, p->poses + 6 * k, b->yc + 6 * k, b->sc_pose + 6 * k,
				  b->cand_poses + 6 * k, &dn, &xn);
	for (int pt = 0; pt < p->n_points; pt++)
		if (b->pt_used[pt])
			candidate(3, p->points + 3 * pt, b->yx + 3 * pt, b->sc_pt + 3 * pt,
				  b->cand_pts + 3 * pt, &dn, &xn);
	if (sqrt(dn) <= LM_PARAMETER_TOLERANCE * (sqrt(xn) + LM_PARAMETER_TOLERANCE))
		return true;
	for (int k = 0; k < p->n_poses; k++)
		if (b->free_idx[k] < 0)
			memcpy(b->cand_poses + 6 * k, p->poses + 6 * k, 6 * sizeof(double));
	for (int pt = 0; pt < p->n_points; pt++)
		if (!b->pt_used[pt])
			memcpy(b->cand_pts + 3 * pt, p->points + 3 * pt, 3 * sizeof(double));
	return false;
}

/* The candidate becomes the problem's state. */
static void take_candidate(struct mvod_ba_lm *b, const struct mvod_ba_problem *p)
{
	for (int k = 0; k < p->n_poses; k++)
		if (b->free_idx[k] >= 0)
			memcpy(p->poses + 6 * k, b->cand_poses + 6 * k, 6 * sizeof(double));
	for (int pt = 0; pt < p->n_points; pt++)
		if (b->pt_used[pt])
			memcpy(p->points + 3 * pt, b->cand_pts + 3 * pt, 3 * sizeof(double));
}

/*
 * Levenberg-Marquardt from the problem's state (cost, linearised, gmax its gradient's largest
 * entry): steps taken while they decrease the cost as their model says, the radius mu grown
 * after each, shrunk after each refusal. 0, or -EIO.
 */
static int iterate(struct mvod_ba_lm *b, const struct mvod_ba_problem *p,
		   const struct mvod_ba_options *op, int nf, double cost, double gmax,
		   struct mvod_ba_result *res)
{
	const double ftol = op->function_tolerance > 0 ? op->function_tolerance
						       : LM_FUNCTION_TOLERANCE;
	double mu = LM_RADIUS0, decrease = 2.0, model;
	int it = 0;
	bool converged = gmax <= LM_GRADIENT_TOLERANCE;
	while (!converged && it < op->max_iterations && mu >= LM_MIN_RADIUS) {
		it++;
		if (lm_step(b, p, nf, mu, &model) && model > 0) {
			double cand = 0, change = 0;
			bool small = make_candidate(b, p);
			if (!small) {
				cand = cost_at(b, p, op, b->cand_poses, b->cand_pts);
				change = cost - cand;
				small = fabs(change) <= ftol * cost;
			}
			if (small) {
				converged = true;
				it--; /* Ceres does not count the iteration that stops */
				break;
			}
			const double rho = change / model;
			if (rho > LM_MIN_RELATIVE_DECREASE) {
				take_candidate(b, p);
				cost = cand;
				const double t = 2.0 * rho - 1.0;
				mu = fmin(LM_MAX_RADIUS, mu / fmax(1.0 / 3.0, 1.0 - t * t * t));
				decrease = 2.0;
				if (!linearize(b, p, op, false, &gmax))
					return -EIO;
				converged = gmax <= LM_GRADIENT_TOLERANCE;
				continue;
			}
		}
		mu /= decrease;
		decrease *= 2.0;
	}
	res->final_cost = cost;
	res->iterations = it;
	res->converged = converged;
	return 0;
}

int mvod_ba_lm_solve(struct mvod_ba_lm *b, const struct mvod_ba_problem *p,
		     const struct mvod_ba_options *op, struct mvod_ba_result *res)
{
	memset(res, 0, sizeof(*res));
	if (!valid(b, p) || !(op->huber > 0) || op->max_iterations < 1 ||
	    !(op->function_tolerance >= 0))
		return -EINVAL;
	int n_active, nf = group(b, p, &n_active);
	if (nf < 0)
		return nf;
	if (n_active > 0) {
		double cost = cost_at(b, p, op, p->poses, p->points), gmax;
		res->initial_cost = cost;
		bool ok = linearize(b, p, op, true, &gmax);
		if (!ok || cost == DBL_MAX)
			return -EIO;
		int ret = iterate(b, p, op, nf, cost, gmax, res);
		if (ret)
			return ret;
	}
	flag_outliers(b, p, op->chi2_outlier, &res->n_outliers);
	return 0;
}
