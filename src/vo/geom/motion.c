#include "motion.h"

#include <errno.h>
#include <math.h>
#include <string.h>

#include "lsq.h"
#include "mvod/geom.h"
#include "util/linalg.h"

bool mvod_triangulate_midpoint(const double R[9], const double t[3], const double x1[2],
			       const double x2[2], double *d1, double *d2)
{
	/* min |d1 a - d2 b + t| with a = R x1, b = x2: a 2x2 normal system. */
	const double r1[3] = {x1[0], x1[1], 1.0};
	const double b[3] = {x2[0], x2[1], 1.0};
	double a[3];
	mvod_mat3_vec(R, r1, a);
	double aa = a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
	double bb = b[0] * b[0] + b[1] * b[1] + b[2] * b[2];
	double ab = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
	double at = a[0] * t[0] + a[1] * t[1] + a[2] * t[2];
	double bt = b[0] * t[0] + b[1] * t[1] + b[2] * t[2];
	double det = aa * bb - ab * ab;
	if (det <= 1e-12 * aa * bb)
		return false;
	*d1 = (ab * bt - at * bb) / det;
	*d2 = (aa * bt - ab * at) / det;
	return true;
}

static int count_in_front(const double R[9], const double t[3], const double *x1, const double *x2,
			  const uint8_t *mask, int n, double *depth1)
{
	int count = 0;
	double base = mvod_vec3_norm(t);
	for (int i = 0; i < n; i++) {
		double d1 = 0, d2 = 0;
		bool ok = mask[i] && mvod_triangulate_midpoint(R, t, x1 + 2 * i, x2 + 2 * i, &d1, &d2) &&
			  d1 > 0 && d2 > 0 && d1 <= MVOD_MOTION_MAX_DEPTH * base;
		if (depth1)
			depth1[i] = ok ? d1 : 0.0;
		count += ok;
	}
	return count;
}

int mvod_motion_cheirality(const double R1[9], const double R2[9], const double t[3],
			   const double *x1, const double *x2, const uint8_t *mask, int n,
			   double R[9], double t_out[3], double *depth1, int *runner_up)
{
	const double *Rs[4] = {R1, R1, R2, R2};
	const double sign[4] = {1, -1, 1, -1};
	int best = -1, best_count = -1, second = 0;
	for (int k = 0; k < 4; k++) {
		double tk[3] = {sign[k] * t[0], sign[k] * t[1], sign[k] * t[2]};
		int c = count_in_front(Rs[k], tk, x1, x2, mask, n, NULL);
		if (c > best_count) {
			second = best_count < 0 ? 0 : best_count;
			best_count = c;
			best = k;
		} else if (c > second) {
			second = c;
		}
	}
	if (runner_up)
		*runner_up = second;
	memcpy(R, Rs[best], 9 * sizeof(double));
	for (int i = 0; i < 3; i++)
		t_out[i] = sign[best] * t[i];
	if (depth1)
		count_in_front(R, t_out, x1, x2, mask, n, depth1);
	return best_count;
}

int mvod_motion_relative_scale(const double *prev, const double *cur, int n, int min_pairs,
			       double *scratch, double *s)
{
	/* Pairs (i, i + n/2): each point used once, partners far apart in detection order. */
	int half = n / 2, m = 0;
	for (int i = 0; i < half; i++) {
		int j = i + half;
		double dc = mvod_vec3_dist(cur + 3 * i, cur + 3 * j);
		double dp = mvod_vec3_dist(prev + 3 * i, prev + 3 * j);
		if (dc > 1e-9 && dp > 1e-9 && isfinite(dc) && isfinite(dp))
			scratch[m++] = dp / dc;
	}
	if (m < min_pairs || m == 0)
		return -ENODATA;
	*s = mvod_median(scratch, m);
	return 0;
}

int mvod_motion_rotation_only(const double *x1, const double *x2, const uint8_t *mask, int n,
			      double R[9])
{
	/* Kabsch on unit bearings: C = sum b2 b1^T. */
	double C[9] = {0};
	int used = 0;
	for (int i = 0; i < n; i++) {
		if (!mask[i])
			continue;
		double b1[3] = {x1[2 * i], x1[2 * i + 1], 1.0}, b2[3] = {x2[2 * i], x2[2 * i + 1], 1.0};
		double n1 = mvod_vec3_norm(b1), n2 = mvod_vec3_norm(b2);
		for (int r = 0; r < 3; r++)
			for (int c = 0; c < 3; c++)
				C[3 * r + c] += (b2[r] / n2) * (b1[c] / n1);
		used++;
	}
	if (used < 2)
		return -EINVAL;
	return mvod_nearest_rotation(C, R, NULL);
}

/*
 * R (x1, 1) projected, minus x2, into d: false when it points behind the camera. R (x1, 1) is
 * summed inline, in mvod_mat3_vec's order (the same doubles, no call: the rotation RANSAC's
 * inner loop).
 */
static bool rotation_offset(const double R[9], const double x1[2], const double x2[2],
			    double d[2])
{
	double pz = R[6] * x1[0] + R[7] * x1[1] + R[8];
	if (pz <= 1e-9)
		return false;
	d[0] = (R[0] * x1[0] + R[1] * x1[1] + R[2]) / pz - x2[0];
	d[1] = (R[3] * x1[0] + R[4] * x1[1] + R[5]) / pz - x2[1];
	return true;
}

double mvod_motion_rotation_residual(const double R[9], const double x1[2], const double x2[2])
{
	double d[2];
	return rotation_offset(R, x1, x2, d) ? hypot(d[0], d[1]) : INFINITY;
}

/*
 * Whether R explains x1 -> x2 within thresh (normalised units; thresh2 its square): the
 * squared distance against thresh2 instead of mvod_motion_rotation_residual's hypot against
 * thresh: the same decision but for a distance within rounding of thresh (KITTI 06/07
 * trajectories identical), and with rotation_inliers' early stop the rotation RANSAC costs
 * 26.7e6 instead of 43.6e6 instructions over 20 KITTI 06 frames (callgrind).
 */
static bool rotation_inlier(const double R[9], const double x1[2], const double x2[2],
			    double thresh2)
{
	double d[2];
	return rotation_offset(R, x1, x2, d) && d[0] * d[0] + d[1] * d[1] < thresh2;
}

/*
 * Inliers of R among the n matches, into mask when not NULL. Without a mask the count stops
 * as soon as it cannot exceed beat (the RANSAC's best so far, which only a larger count
 * replaces) and is then at most beat.
 */
static int rotation_inliers(const double *x1, const double *x2, int n, const double R[9],
			    double thresh, uint8_t *mask, int beat)
{
	int count = 0;
	double thresh2 = thresh * thresh;
	for (int i = 0; i < n; i++) {
		if (!mask && count + (n - i) <= beat)
			return count;
		uint8_t in = rotation_inlier(R, x1 + 2 * i, x2 + 2 * i, thresh2);
		if (mask)
			mask[i] = in;
		count += in;
	}
	return count;
}

int mvod_motion_rotation_ransac(const double *x1, const double *x2, int n, double thresh,
				int iterations, uint8_t *mask, double R[9])
{
	if (n < 2)
		return 0;
	uint32_t state = 0x9e3779b9u;
	int best = 0;
	for (int it = 0; it < iterations; it++) {
		state = state * 1664525u + 1013904223u;
		int i = (int)((state >> 8) % (uint32_t)n);
		state = state * 1664525u + 1013904223u;
		int j = (int)((state >> 8) % (uint32_t)n);
		if (i == j)
			continue;
		const double a[4] = {x1[2 * i], x1[2 * i + 1], x1[2 * j], x1[2 * j + 1]};
		const double b[4] = {x2[2 * i], x2[2 * i + 1], x2[2 * j], x2[2 * j + 1]};
		const uint8_t both[2] = {1, 1};
		double Rs[9];
		if (mvod_motion_rotation_only(a, b, both, 2, Rs) != 0)
			continue;
		int c = rotation_inliers(x1, x2, n, Rs, thresh, NULL, best);
		if (c > best) {
			best = c;
			memcpy(R, Rs, sizeof(Rs));
		}
	}
	for (int pass = 0; best >= 2 && pass < 2; pass++) {
		rotation_inliers(x1, x2, n, R, thresh, mask, 0);
		if (mvod_motion_rotation_only(x1, x2, mask, n, R) != 0)
			break;
	}
	return best >= 2 ? rotation_inliers(x1, x2, n, R, thresh, mask, 0) : 0;
}

double mvod_motion_sampson(const double E[9], const double x1[2], const double x2[2])
{
	double a[3] = {E[0] * x1[0] + E[1] * x1[1] + E[2], E[3] * x1[0] + E[4] * x1[1] + E[5],
		       E[6] * x1[0] + E[7] * x1[1] + E[8]};
	double b0 = E[0] * x2[0] + E[3] * x2[1] + E[6], b1 = E[1] * x2[0] + E[4] * x2[1] + E[7];
	double num = x2[0] * a[0] + x2[1] * a[1] + a[2];
	double den = a[0] * a[0] + a[1] * a[1] + b0 * b0 + b1 * b1;
	return den > 1e-30 ? num / sqrt(den) : 0.0;
}

void mvod_motion_essential(const double R[9], const double t[3], double E[9])
{
	const double tx[9] = {0, -t[2], t[1], t[2], 0, -t[0], -t[1], t[0], 0};
	mvod_mat3_mul(tx, R, E);
}

/* A basis u, v of the plane orthogonal to unit t. */
static void tangent(const double t[3], double u[3], double v[3])
{
	double e[3] = {0, 0, 0};
	int k = fabs(t[0]) < fabs(t[1]) ? (fabs(t[0]) < fabs(t[2]) ? 0 : 2)
					 : (fabs(t[1]) < fabs(t[2]) ? 1 : 2);
	e[k] = 1;
	mvod_vec3_cross(t, e, u);
	double nu = mvod_vec3_norm(u);
	for (int j = 0; j < 3; j++)
		u[j] /= nu;
	mvod_vec3_cross(t, u, v);
}

/* The pose moved by p = (w, a, b): R' = exp(w) R, t' = t + a u + b v, normalised. */
static void perturb(const double R[9], const double t[3], const double u[3], const double v[3],
		    const double p[5], double Ro[9], double to[3])
{
	double dR[9];
	mvod_rot_exp(p, dR);
	mvod_mat3_mul(dR, R, Ro);
	for (int k = 0; k < 3; k++)
		to[k] = t[k] + p[3] * u[k] + p[4] * v[k];
	double nt = mvod_vec3_norm(to);
	for (int k = 0; k < 3; k++)
		to[k] /= nt;
}

/* Match i's residual in sigma units. */
static double weighted(const double E[9], const double *x1, const double *x2, const double *w,
		       int i)
{
	return mvod_motion_sampson(E, x1 + 2 * i, x2 + 2 * i) * (w ? w[i] : 1.0);
}

/* Huber's cost at k of the weighted Sampson residuals of the points with mask set. */
static double huber_cost(const double R[9], const double t[3], const double *x1, const double *x2,
			 const double *w, const uint8_t *mask, int n, double k)
{
	double E[9], c = 0;
	mvod_motion_essential(R, t, E);
	for (int i = 0; i < n; i++) {
		if (!mask[i])
			continue;
		double r = fabs(weighted(E, x1, x2, w, i));
		c += r <= k ? 0.5 * r * r : k * (r - 0.5 * k);
	}
	return c;
}


/* Gauss-Newton's normal equations at (R, t) along the 5 parameters of perturb(). */
static void normal_equations(const double R[9], const double t[3], const double u[3],
			     const double v[3], const double *x1, const double *x2, const double *w,
			     const uint8_t *mask, int n, double k, double A[25], double g[5])
{
	/* Forward differences: the residuals are smooth, and 1e-7 rad keeps 8-9 digits. */
	const double h = 1e-7;
	double E[9], Ep[5][9];
	mvod_motion_essential(R, t, E);
	for (int p = 0; p < 5; p++) {
		double d[5] = {0}, Rp[9], tp[3];
		d[p] = h;
		perturb(R, t, u, v, d, Rp, tp);
		mvod_motion_essential(Rp, tp, Ep[p]);
	}
	memset(A, 0, 25 * sizeof(double));
	memset(g, 0, 5 * sizeof(double));
	for (int i = 0; i < n; i++) {
		if (!mask[i])
			continue;
		double r = weighted(E, x1, x2, w, i), J[5];
		for (int p = 0; p < 5; p++)
			J[p] = (weighted(Ep[p], x1, x2, w, i) - r) / h;
		double hw = fabs(r) <= k ? 1.0 : k / fabs(r); /* Huber's weight */
		for (int a = 0; a < 5; a++) {
			g[a] += hw * J[a] * r;
			for (int b = 0; b < 5; b++)
				A[5 * a + b] += hw * J[a] * J[b];
		}
	}
}

/* The refinement as mvod_lsq_solve sees it: the state R (9) then t (3). */
struct refine {
	const double *x1, *x2, *w;
	const uint8_t *mask;
	int n;
	double k;
	double u[3], v[3]; /* the tangent basis of t where the normal equations were taken */
};

static double lsq_cost(void *ctx, const double *x)
{
	const struct refine *r = ctx;
	return huber_cost(x, x + 9, r->x1, r->x2, r->w, r->mask, r->n, r->k);
}

static void lsq_normal(void *ctx, const double *x, double *A, double *g)
{
	struct refine *r = ctx;
	tangent(x + 9, r->u, r->v);
	normal_equations(x, x + 9, r->u, r->v, r->x1, r->x2, r->w, r->mask, r->n, r->k, A, g);
}

static void lsq_move(void *ctx, const double *x, const double *d, double *out)
{
	const struct refine *r = ctx;
	perturb(x, x + 9, r->u, r->v, d, out, out + 9);
}

/* Levenberg-Marquardt: up to 10 tries an iteration, the damping grown until a step lowers the cost. */
int mvod_motion_refine(double R[9], double t[3], const double *x1, const double *x2,
		       const double *w, const uint8_t *mask, int n, double k, int iterations)
{
	double nt = mvod_vec3_norm(t);
	if (!(nt > 0) || !(k > 0))
		return -EINVAL;
	struct refine r = {x1, x2, w, mask, n, k, {0}, {0}};
	const struct mvod_lsq_problem lp = {5, 12, &r, lsq_cost, lsq_normal, lsq_move, NULL};
	const struct mvod_lsq_options o = {.iterations = iterations, .tries = 10, .lambda = 1e-3,
					   .lambda_min = 1e-9, .lambda_max = INFINITY,
					   .damping = MVOD_LSQ_ADD, .stop_when_stuck = true};
	double x[12];
	memcpy(x, R, 9 * sizeof(double));
	for (int j = 0; j < 3; j++)
		x[9 + j] = t[j] / nt;
	int steps = mvod_lsq_solve(&lp, &o, x, NULL);
	memcpy(R, x, 9 * sizeof(double));
	memcpy(t, x + 9, 3 * sizeof(double));
	return steps;
}

int mvod_motion_epipolar_inliers(const double R[9], const double t[3], const double *x1,
				 const double *x2, const double *w, int n, double thresh,
				 uint8_t *mask)
{
	double E[9];
	int count = 0;
	mvod_motion_essential(R, t, E);
	for (int i = 0; i < n; i++) {
		mask[i] = fabs(weighted(E, x1, x2, w, i)) < thresh;
		count += mask[i];
	}
	return count;
}

int mvod_motion_depths(const double R[9], const double t[3], const double *x1, const double *x2,
		       const uint8_t *mask, int n, double *depth1)
{
	return count_in_front(R, t, x1, x2, mask, n, depth1);
}
