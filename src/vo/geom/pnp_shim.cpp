#include "pnp_shim.h"

#include <algorithm>
#include <cerrno>
#include <cfloat>
#include <memory>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include "lsq.h"
#include "mvod/geom.h"
#include "util/shim_guard.hpp"

struct mvod_pnp {
	struct mvod_pnp_params p;
	int cap;
	cv::Mat inliers;        /* RANSAC's inlier indices (OpenCV sizes it) */
	cv::Mat rvec, tvec;     /* 3 x 1 doubles */
};

extern "C" void mvod_pnp_params_default(struct mvod_pnp_params *p)
{
	/*
	 * USAC (P3P with local optimisation) was the most accurate and the cheapest of the five on
	 * test_pnp's 20 scenes (300 matches, 30 % outliers, 1-2 px noise): rotation 8.5e-4 rad,
	 * translation 0.0125 units, 3.7 ms CPU, against AP3P's 9.3e-4, 0.0167, 5.1 ms and
	 * MAGSAC++'s 8.1e-4, 0.0119, 7.4 ms (CPU times on a loaded 2-core machine: relative only).
	 */
	p->method = MVOD_PNP_USAC_DEFAULT;
	p->thresh_px = 2.45;
	p->confidence = 0.999;
	p->max_iterations = 200;
	p->refine_rounds = 2;
	p->min_inliers = 10;
}

extern "C" int mvod_pnp_create(const struct mvod_pnp_params *p, int cap, struct mvod_pnp **out)
{
	*out = nullptr;
	return mvod_guarded([&] {
		if (cap < 4 || !(p->thresh_px > 0) || p->max_iterations < 1 || p->refine_rounds < 0)
			return -EINVAL;
		auto pnp = std::make_unique<mvod_pnp>();
		pnp->p = *p;
		pnp->cap = cap;
		pnp->inliers.create(cap, 1, CV_32S);
		pnp->rvec.create(3, 1, CV_64F);
		pnp->tvec.create(3, 1, CV_64F);
		*out = pnp.release();
		return 0;
	});
}

extern "C" void mvod_pnp_destroy(struct mvod_pnp *pnp)
{
	delete pnp;
}

/* Camera matrix of fx, fy, cx, cy. */
static cv::Matx33d K_of(const double K4[4])
{
	return cv::Matx33d(K4[0], 0, K4[2], 0, K4[1], K4[3], 0, 0, 1);
}

/* OpenCV's flags for a method: the PnP solver and, for the USAC ones, the USAC variant. */
static int flags_of(enum mvod_pnp_method m)
{
	switch (m) {
	case MVOD_PNP_RANSAC_EPNP: return cv::SOLVEPNP_EPNP;
	case MVOD_PNP_RANSAC_P3P: return cv::SOLVEPNP_P3P;
	case MVOD_PNP_USAC_DEFAULT: return cv::USAC_DEFAULT;
	case MVOD_PNP_USAC_MAGSAC: return cv::USAC_MAGSAC;
	default: return cv::SOLVEPNP_AP3P;
	}
}

/* Re-selects inliers: squared reprojection error in sigma units within thresh^2, in front. */
static int classify(const struct mvod_pnp *pnp, const double *X, const double *uv,
		    const double *sigma, int n, const double K[4], double gate_px, uint8_t *inlier)
{
	cv::Matx33d R;
	cv::Rodrigues(pnp->rvec, R);
	const double *t = pnp->tvec.ptr<double>();
	double gate = gate_px * gate_px;
	int k = 0;
	for (int i = 0; i < n; i++) {
		cv::Vec3d c = R * cv::Vec3d(X[3 * i], X[3 * i + 1], X[3 * i + 2]);
		double z = c[2] + t[2], s = sigma ? sigma[i] : 1.0;
		double du = (K[0] * (c[0] + t[0]) / z + K[2] - uv[2 * i]) / s;
		double dv = (K[1] * (c[1] + t[1]) / z + K[3] - uv[2 * i + 1]) / s;
		inlier[i] = z > 0 && du * du + dv * dv <= gate;
		k += inlier[i];
	}
	return k;
}

/* Sum of the inliers' squared pixel reprojection errors at R, t (classify keeps them in front). */
static double sq_cost(const double *X, const double *uv, int n, const double K[4],
		      const uint8_t *inlier, const double R[9], const double t[3])
{
	double c = 0;
	for (int i = 0; i < n; i++) {
		if (!inlier[i])
			continue;
		double p[3];
		mvod_rigid_apply(R, t, X + 3 * i, p);
		double du = K[0] * p[0] / p[2] + K[2] - uv[2 * i];
		double dv = K[1] * p[1] / p[2] + K[3] - uv[2 * i + 1];
		c += du * du + dv * dv;
	}
	return c;
}

/* The refinement as mvod_lsq_solve sees it: the state R (9) then t (3), the inliers' pixels. */
struct refinement {
	const double *X, *uv, *K;
	const uint8_t *inlier;
	int n;
	double w0[3]; /* the start's rotation vector, for the step's stopping rule */
};

static double lsq_cost(void *ctx, const double *x)
{
	const refinement *r = (const refinement *)ctx;
	return sq_cost(r->X, r->uv, r->n, r->K, r->inlier, x, x + 9);
}

/* The inliers' J^T J and J^T r at x, the Jacobians written out for the left perturbation. */
static void lsq_normal(void *ctx, const double *x, double *A, double *g)
{
	const refinement *r = (const refinement *)ctx;
	const double *K = r->K;
	for (int i = 0; i < r->n; i++) {
		if (!r->inlier[i])
			continue;
		double c[3];
		mvod_rigid_apply(x, x + 9, r->X + 3 * i, c);
		double iz = 1.0 / c[2];
		double e[2] = {K[0] * c[0] * iz + K[2] - r->uv[2 * i],
			       K[1] * c[1] * iz + K[3] - r->uv[2 * i + 1]};
		/* d(uv)/dc times dc/d(w, tau) = [-[c]x | I] */
		double du[3] = {K[0] * iz, 0, -K[0] * c[0] * iz * iz};
		double dv[3] = {0, K[1] * iz, -K[1] * c[1] * iz * iz};
		double J[2][6] = {{c[1] * du[2] - c[2] * du[1], c[2] * du[0] - c[0] * du[2],
				   c[0] * du[1] - c[1] * du[0], du[0], du[1], du[2]},
				  {c[1] * dv[2] - c[2] * dv[1], c[2] * dv[0] - c[0] * dv[2],
				   c[0] * dv[1] - c[1] * dv[0], dv[0], dv[1], dv[2]}};
		for (int k = 0; k < 2; k++)
			for (int a = 0; a < 6; a++) {
				g[a] += J[k][a] * e[k];
				for (int b = a; b < 6; b++)
					A[6 * a + b] += J[k][a] * J[k][b];
			}
	}
	for (int a = 0; a < 6; a++)
		for (int b = 0; b < a; b++)
			A[6 * a + b] = A[6 * b + a];
}

/* The pose moved on the left: R' = exp(w) R, t' = exp(w) t + tau. */
static void lsq_move(void *, const double *x, const double *d, double *out)
{
	double dR[9];
	mvod_rot_exp(d, dR);
	mvod_mat3_mul(dR, x, out);
	mvod_mat3_vec(dR, x + 9, out + 9);
	for (int q = 0; q < 3; q++)
		out[9 + q] += d[3 + q];
}

/* solvePnPRefineLM's stop: a step below FLT_EPSILON of the start's rotation vector and t. */
static bool lsq_converged(void *ctx, const double *x, const double *d)
{
	const refinement *r = (const refinement *)ctx;
	double norm = 0, step = 0;
	for (int q = 0; q < 6; q++)
		step += d[q] * d[q];
	for (int q = 0; q < 3; q++)
		norm += r->w0[q] * r->w0[q] + x[9 + q] * x[9 + q];
	return step <= (double)FLT_EPSILON * FLT_EPSILON * norm;
}

/*
 * Levenberg-Marquardt on the current inliers' squared pixel errors, from the current pose
 * (pnp->rvec, tvec in and out): what cv::solvePnPRefineLM minimised here before, with its
 * stops (20 iterations, or a step below FLT_EPSILON of the parameters' norm: the start's
 * rotation vector and t) and its damping (1e-3 of the diagonal, / 10 on success, x 10 on
 * failure), but the Jacobians written out for a left perturbation (R' = exp(w) R,
 * t' = exp(w) t + tau) instead of projectPoints' with the full camera model (distortion,
 * focal and centre derivatives, all thrown away) and Rodrigues' 3 x 9 Jacobian: 1.77e6 ->
 * 0.19e6 instructions a frame on KITTI 06 map klt (callgrind); the KITTI clips' map
 * trajectories within 1e-7 m of OpenCV's (klt; orb 07 free scale 1.3e-4 m) and every score
 * of their table unchanged (BENCHMARKS.md). A singular system leaves the pose as it was.
 */
static void refine(struct mvod_pnp *pnp, const double *X, const double *uv, int n,
		   const double K[4], const uint8_t *inlier)
{
	refinement r = {X, uv, K, inlier, n, {0, 0, 0}};
	const double *rv = pnp->rvec.ptr<double>();
	double *tv = pnp->tvec.ptr<double>();
	std::copy(rv, rv + 3, r.w0);
	double x[12];
	mvod_rot_exp(r.w0, x);
	std::copy(tv, tv + 3, x + 9);
	const struct mvod_lsq_problem lp = {6, 12, &r, lsq_cost, lsq_normal, lsq_move,
					    lsq_converged};
	struct mvod_lsq_options o = {};
	o.iterations = 20;
	o.tries = 0;
	o.lambda = 1e-3;
	o.lambda_min = 1e-16;
	o.lambda_max = 1e16;
	o.damping = MVOD_LSQ_SCALE;
	o.stop_when_stuck = true;
	bool singular;
	mvod_lsq_solve(&lp, &o, x, &singular);
	if (singular)
		return;
	cv::Mat Rm(3, 3, CV_64F, x);
	cv::Rodrigues(Rm, pnp->rvec);
	std::copy(x + 9, x + 12, tv);
}

/* Refinement rounds from the current pose and inliers (k of them), then the result out. */
static int rounds(struct mvod_pnp *pnp, const double *X, const double *uv, const double *sigma,
		  int n, const double K4[4], int k, double R[9], double t[3], uint8_t *inlier)
{
	for (int r = 0; r < pnp->p.refine_rounds && k >= 4; r++) {
		refine(pnp, X, uv, n, K4, inlier);
		k = classify(pnp, X, uv, sigma, n, K4, pnp->p.thresh_px, inlier);
	}
	if (k < pnp->p.min_inliers || k < 4)
		return -ENODATA;
	cv::Mat Rm(3, 3, CV_64F, R);
	cv::Rodrigues(pnp->rvec, Rm);
	std::copy(pnp->tvec.ptr<double>(), pnp->tvec.ptr<double>() + 3, t);
	return k;
}

extern "C" int mvod_pnp_solve(struct mvod_pnp *pnp, const double *X, const double *uv,
			      const double *sigma, int n, const double K4[4], double R[9],
			      double t[3], uint8_t *inlier)
{
	return mvod_guarded([&] {
		if (n < 4 || n > pnp->cap)
			return -EINVAL;
		const cv::Matx33d K = K_of(K4);
		const cv::Mat Xm(n, 3, CV_64F, const_cast<double *>(X));
		const cv::Mat uvm(n, 2, CV_64F, const_cast<double *>(uv));
		const struct mvod_pnp_params &p = pnp->p;
		if (!cv::solvePnPRansac(Xm, uvm, K, cv::noArray(), pnp->rvec, pnp->tvec, false,
					p.max_iterations, (float)p.thresh_px, p.confidence,
					pnp->inliers, flags_of(p.method)))
			return -ENODATA;
		int k = (int)pnp->inliers.total();
		std::fill(inlier, inlier + n, 0);
		for (int j = 0; j < k; j++)
			inlier[pnp->inliers.at<int>(j)] = 1;
		return rounds(pnp, X, uv, sigma, n, K4, k, R, t, inlier);
	});
}

extern "C" int mvod_pnp_refine(struct mvod_pnp *pnp, const double *X, const double *uv,
			       const double *sigma, int n, const double K4[4], double R[9],
			       double t[3], uint8_t *inlier)
{
	return mvod_guarded([&] {
		if (n < 4 || n > pnp->cap)
			return -EINVAL;
		cv::Rodrigues(cv::Mat(3, 3, CV_64F, R), pnp->rvec);
		std::copy(t, t + 3, pnp->tvec.ptr<double>());
		int k = classify(pnp, X, uv, sigma, n, K4, 4 * pnp->p.thresh_px, inlier);
		return rounds(pnp, X, uv, sigma, n, K4, k, R, t, inlier);
	});
}
