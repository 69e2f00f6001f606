#include "ba_shim.h"

#include <cerrno>
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include "util/shim_guard.hpp"

/* Reprojection error in sigma units of one observation; pose = (angle-axis, t), X world. */
struct reprojection {
	double u, v, inv_sigma, fx, fy, cx, cy;

	template <typename T> bool operator()(const T *pose, const T *X, T *r) const
	{
		T p[3];
		ceres::AngleAxisRotatePoint(pose, X, p);
		p[0] += pose[3];
		p[1] += pose[4];
		p[2] += pose[5];
		/*
		 * A step that takes a point to or behind a camera is not evaluable: Ceres rejects it
		 * and shrinks its trust region. Dividing by z = 0 instead gave inf residuals and a
		 * 30-line glog warning on stderr (seen in a 10 000-frame synthetic run, map mode).
		 */
		if (!(p[2] > T(0)))
			return false;
		r[0] = (T(fx) * p[0] / p[2] + T(cx) - T(u)) * T(inv_sigma);
		r[1] = (T(fy) * p[1] / p[2] + T(cy) - T(v)) * T(inv_sigma);
		return true;
	}
};

/*
 * A value and its derivatives with respect to the angle-axis r (3) and the point X (3): the
 * derivatives with respect to t are units and are added at the projection. Rotation's terms
 * depend on r alone, the point's on X alone; a Jet over all nine inputs (AutoDiff) carries
 * their zeros through every operation.
 */
struct dual {
	double a, r[3], x[3];
};

/*
 * reprojection's residuals and Jacobians (2x6 row-major for the pose, 2x3 for X, either may be
 * NULL) by forward differentiation written out: each derivative is computed by the operations
 * Ceres's Jet<double, 9> applies to it in the same order, without the products and sums with a
 * structural zero (x * 0 = 0 and x + 0 = x exactly, but for the sign of a zero), so residuals
 * and Jacobians equal AutoDiffCostFunction's bit for bit (tests/unit/test_ba.c checks it) at
 * a quarter of the instructions. Keep in step with ceres::AngleAxisRotatePoint (Ceres 2.1).
 */
static bool reprojection_jacobians(const reprojection &f, const double *pose, const double *X,
				   double *res, double *Jp, double *Jx)
{
	const double *aa = pose;
	dual q[3]; /* R(aa) X */
	const double theta2 = aa[0] * aa[0] + aa[1] * aa[1] + aa[2] * aa[2];
	if (theta2 > std::numeric_limits<double>::epsilon()) {
		/* theta = sqrt(theta2); d theta2 / d aa_k = aa_k * 1 + 1 * aa_k */
		const double th = std::sqrt(theta2), two_inv = 1.0 / (2.0 * th);
		double th_r[3];
		for (int k = 0; k < 3; k++)
			th_r[k] = (aa[k] + aa[k]) * two_inv;
		const double c = std::cos(th), s = std::sin(th);
		/* ti = T(1) / theta, a Jet's quotient: 1 * (1 / theta), (0 - ti theta') / theta */
		double c_r[3], s_r[3], ti_r[3];
		const double ti = 1.0 / th;
		for (int k = 0; k < 3; k++) {
			c_r[k] = -s * th_r[k];
			s_r[k] = c * th_r[k];
			ti_r[k] = (0.0 - ti * th_r[k]) * ti;
		}
		/* w = aa / theta: no X part */
		double w[3], w_r[3][3];
		for (int i = 0; i < 3; i++) {
			w[i] = aa[i] * ti;
			for (int k = 0; k < 3; k++)
				w_r[i][k] = k == i ? aa[i] * ti_r[k] + ti : aa[i] * ti_r[k];
		}
		/* w x X */
		dual wc[3];
		for (int i = 0; i < 3; i++) {
			const int j = (i + 1) % 3, l = (i + 2) % 3;
			wc[i].a = w[j] * X[l] - w[l] * X[j];
			for (int k = 0; k < 3; k++)
				wc[i].r[k] = w_r[j][k] * X[l] - w_r[l][k] * X[j];
			for (int m = 0; m < 3; m++)
				wc[i].x[m] = (m == l ? w[j] : 0.0) - (m == j ? w[l] : 0.0);
		}
		/* tmp = (w . X) (1 - cos theta) */
		dual dot;
		dot.a = w[0] * X[0] + w[1] * X[1] + w[2] * X[2];
		for (int k = 0; k < 3; k++)
			dot.r[k] = w_r[0][k] * X[0] + w_r[1][k] * X[1] + w_r[2][k] * X[2];
		for (int m = 0; m < 3; m++)
			dot.x[m] = w[m];
		const double omc = 1.0 - c;
		dual tmp;
		tmp.a = dot.a * omc;
		for (int k = 0; k < 3; k++)
			tmp.r[k] = dot.a * (0.0 - c_r[k]) + dot.r[k] * omc;
		for (int m = 0; m < 3; m++)
			tmp.x[m] = dot.x[m] * omc;
		/* q = X cos theta + (w x X) sin theta + w tmp */
		for (int i = 0; i < 3; i++) {
			q[i].a = X[i] * c + wc[i].a * s + w[i] * tmp.a;
			for (int k = 0; k < 3; k++)
				q[i].r[k] = X[i] * c_r[k] + (wc[i].a * s_r[k] + wc[i].r[k] * s) +
					    (w[i] * tmp.r[k] + w_r[i][k] * tmp.a);
			for (int m = 0; m < 3; m++)
				q[i].x[m] = (m == i ? c : 0.0) + wc[i].x[m] * s + w[i] * tmp.x[m];
		}
	} else {
		/* q = X + aa x X */
		for (int i = 0; i < 3; i++) {
			const int j = (i + 1) % 3, l = (i + 2) % 3;
			q[i].a = X[i] + (aa[j] * X[l] - aa[l] * X[j]);
			for (int k = 0; k < 3; k++)
				q[i].r[k] = (k == j ? X[l] : 0.0) - (k == l ? X[j] : 0.0);
			for (int m = 0; m < 3; m++)
				q[i].x[m] = (m == i ? 1.0 : 0.0) +
					    ((m == l ? aa[j] : 0.0) - (m == j ? aa[l] : 0.0));
		}
	}
	double p[3];
	for (int i = 0; i < 3; i++)
		p[i] = q[i].a + pose[3 + i];
	if (!(p[2] > 0))
		return false;
	/* r_i = ((f_i p_i) / p_2 + c_i - m_i) / sigma, the quotient as Jet's (times 1 / p_2) */
	const double inv_z = 1.0 / p[2], fl[2] = {f.fx, f.fy}, cc[2] = {f.cx, f.cy},
		     m[2] = {f.u, f.v};
	for (int i = 0; i < 2; i++) {
		const double fab = fl[i] * p[i] * inv_z;
		res[i] = (fab + cc[i] - m[i]) * f.inv_sigma;
		if (Jp) {
			for (int k = 0; k < 3; k++)
				Jp[6 * i + k] = (fl[i] * q[i].r[k] - fab * q[2].r[k]) * inv_z * f.inv_sigma;
			/* d p / d t = identity */
			for (int k = 0; k < 3; k++)
				Jp[6 * i + 3 + k] = ((k == i ? fl[i] : 0.0) - (k == 2 ? fab : 0.0)) * inv_z *
						    f.inv_sigma;
		}
		if (Jx)
			for (int k = 0; k < 3; k++)
				Jx[3 * i + k] = (fl[i] * q[i].x[k] - fab * q[2].x[k]) * inv_z * f.inv_sigma;
	}
	return true;
}

/* reprojection with its Jacobians from reprojection_jacobians. */
struct reprojection_cost final : ceres::SizedCostFunction<2, 6, 3> {
	reprojection f;
	explicit reprojection_cost(const reprojection &r) : f(r) {}
	bool Evaluate(double const *const *x, double *res, double **J) const override
	{
		if (!J)
			return f(x[0], x[1], res);
		return reprojection_jacobians(f, x[0], x[1], res, J[0], J[1]);
	}
};

struct mvod_ba {
	ceres::Solver::Options options;
	/* Kept across solves: Ceres's context, and one cost per observation (grown, never shrunk). */
	std::unique_ptr<ceres::Context> context{ceres::Context::Create()};
	std::vector<std::unique_ptr<reprojection_cost>> costs;
};

extern "C" const bool mvod_ba_present = true;

extern "C" int mvod_ba_create(struct mvod_ba **out)
{
	*out = nullptr;
	return mvod_guarded([&] {
		auto ba = std::make_unique<mvod_ba>();
		/* A window has 5-10 cameras: the dense Schur complement is the cheapest solver. */
		ba->options.linear_solver_type = ceres::DENSE_SCHUR;
		ba->options.logging_type = ceres::SILENT;
		/* Two shared cores; the rest of the pipeline runs beside bundle adjustment. */
		ba->options.num_threads = 1;
		*out = ba.release();
		return 0;
	});
}

extern "C" void mvod_ba_destroy(struct mvod_ba *ba)
{
	delete ba;
}

/* Depth of observation o's point in its camera (before or after solving). */
static double depth_of(const struct mvod_ba_problem *p, const struct mvod_ba_obs &o)
{
	double c[3];
	ceres::AngleAxisRotatePoint(p->poses + 6 * o.pose, p->points + 3 * o.point, c);
	return c[2] + p->poses[6 * o.pose + 5];
}

static bool valid(const struct mvod_ba_problem *p)
{
	if (p->n_poses < 0 || p->n_points < 0 || p->n_obs < 0 || !(p->fx > 0) || !(p->fy > 0))
		return false;
	for (int i = 0; i < p->n_obs; i++) {
		const struct mvod_ba_obs &o = p->obs[i];
		if (o.pose < 0 || o.pose >= p->n_poses || o.point < 0 || o.point >= p->n_points ||
		    !(o.sigma > 0) || !std::isfinite(o.u) || !std::isfinite(o.v))
			return false;
	}
	return true;
}

/* Adds every observation in front of its camera; flags the others. Returns those flagged. */
static int build(struct mvod_ba *ba, ceres::Problem &pb, ceres::LossFunction *loss,
		 const struct mvod_ba_problem *p)
{
	int behind = 0;
	while ((int)ba->costs.size() < p->n_obs)
		ba->costs.push_back(std::make_unique<reprojection_cost>(reprojection{}));
	for (int i = 0; i < p->n_obs; i++) {
		const struct mvod_ba_obs &o = p->obs[i];
		p->outlier[i] = depth_of(p, o) <= 0;
		if (p->outlier[i]) {
			behind++;
			continue;
		}
		reprojection_cost *cost = ba->costs[i].get();
		cost->f = reprojection{o.u, o.v, 1.0 / o.sigma, p->fx, p->fy, p->cx, p->cy};
		pb.AddResidualBlock(cost, loss, p->poses + 6 * o.pose, p->points + 3 * o.point);
	}
	for (int k = 0; p->fixed && k < p->n_poses; k++)
		if (p->fixed[k] && pb.HasParameterBlock(p->poses + 6 * k))
			pb.SetParameterBlockConstant(p->poses + 6 * k);
	return behind;
}

/* Flags observations whose squared residual (sigma units) exceeds chi2 or that went behind. */
static int flag_outliers(const struct mvod_ba_problem *p, double chi2)
{
	int n = 0;
	for (int i = 0; i < p->n_obs; i++) {
		const struct mvod_ba_obs &o = p->obs[i];
		if (!p->outlier[i]) {
			reprojection f{o.u, o.v, 1.0 / o.sigma, p->fx, p->fy, p->cx, p->cy};
			double r[2];
			/* false: the point went to or behind the camera */
			p->outlier[i] = !f(p->poses + 6 * o.pose, p->points + 3 * o.point, r) ||
					r[0] * r[0] + r[1] * r[1] > chi2;
		}
		n += p->outlier[i];
	}
	return n;
}

extern "C" int mvod_ba_solve(struct mvod_ba *ba, const struct mvod_ba_problem *p,
			     const struct mvod_ba_options *o, struct mvod_ba_result *r)
{
	return mvod_guarded([&] {
		*r = {};
		if (!valid(p) || !(o->huber > 0) || o->max_iterations < 1 ||
		    !(o->function_tolerance >= 0))
			return -EINVAL;
		ceres::Problem::Options po;
		po.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP; /* one loss, ours */
		po.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP; /* ba->costs */
		/*
		 * Ceres's checks of each residual's blocks (sizes, one block twice): valid() has
		 * checked the indices, and a residual's pose and point are distinct arrays.
		 */
		po.disable_all_safety_checks = true;
		po.context = ba->context.get();
		auto loss = std::make_unique<ceres::HuberLoss>(o->huber);
		ceres::Problem pb(po);
		build(ba, pb, loss.get(), p);
		if (pb.NumResidualBlocks() > 0) {
			ceres::Solver::Options so = ba->options;
			so.max_num_iterations = o->max_iterations;
			if (o->function_tolerance > 0)
				so.function_tolerance = o->function_tolerance;
			ceres::Solver::Summary sum;
			ceres::Solve(so, &pb, &sum);
			if (sum.termination_type == ceres::FAILURE)
				return -EIO;
			r->initial_cost = sum.initial_cost;
			r->final_cost = sum.final_cost;
			r->iterations = (int)sum.iterations.size() - 1; /* [0] is the start */
			r->converged = sum.termination_type == ceres::CONVERGENCE;
		}
		r->n_outliers = flag_outliers(p, o->chi2_outlier);
		return 0;
	});
}

extern "C" int mvod_ba_jacobian_mismatches(const double pose[6], const double X[3],
					   const struct mvod_ba_obs *o, double fx, double fy,
					   double cx, double cy, bool *evaluated)
{
	return mvod_guarded([&] {
		const reprojection f{o->u, o->v, 1.0 / o->sigma, fx, fy, cx, cy};
		const ceres::AutoDiffCostFunction<reprojection, 2, 6, 3> ad(new reprojection(f));
		const reprojection_cost hand(f);
		const double *x[2] = {pose, X};
		double r[2][2], J[2][18];
		double *Ja[2] = {J[0], J[0] + 12}, *Jh[2] = {J[1], J[1] + 12};
		bool a = ad.Evaluate(x, r[0], Ja), h = hand.Evaluate(x, r[1], Jh);
		*evaluated = a && h;
		if (a != h)
			return -1;
		int n = 0;
		/* != rather than memcmp: the sign of a zero may differ (x + 0), and nothing else */
		for (int i = 0; a && i < 2; i++)
			n += r[0][i] != r[1][i];
		for (int i = 0; a && i < 18; i++)
			n += J[0][i] != J[1][i];
		return n;
	});
}
