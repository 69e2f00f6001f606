#include "ba_ceres.h"

#include <cerrno>
#include <cmath>
#include <memory>

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

/* One observation's cost, in sigma units, with Ceres's automatic derivatives. */
using reprojection_cost = ceres::AutoDiffCostFunction<reprojection, 2, 6, 3>;

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

/* Adds every observation in front of its camera (the problem owns the costs); flags the others. */
static void build(ceres::Problem &pb, ceres::LossFunction *loss, const struct mvod_ba_problem *p)
{
	for (int i = 0; i < p->n_obs; i++) {
		const struct mvod_ba_obs &o = p->obs[i];
		p->outlier[i] = depth_of(p, o) <= 0;
		if (p->outlier[i])
			continue;
		auto *cost = new reprojection_cost(
			new reprojection{o.u, o.v, 1.0 / o.sigma, p->fx, p->fy, p->cx, p->cy});
		pb.AddResidualBlock(cost, loss, p->poses + 6 * o.pose, p->points + 3 * o.point);
	}
	for (int k = 0; p->fixed && k < p->n_poses; k++)
		if (p->fixed[k] && pb.HasParameterBlock(p->poses + 6 * k))
			pb.SetParameterBlockConstant(p->poses + 6 * k);
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

extern "C" int ba_ceres_solve(const struct mvod_ba_problem *p, const struct mvod_ba_options *o,
			      struct mvod_ba_result *r)
{
	return mvod_guarded([&] {
		*r = {};
		if (!valid(p) || !(o->huber > 0) || o->max_iterations < 1 ||
		    !(o->function_tolerance >= 0))
			return -EINVAL;
		ceres::Problem::Options po;
		po.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP; /* one loss, ours */
		auto loss = std::make_unique<ceres::HuberLoss>(o->huber);
		ceres::Problem pb(po);
		build(pb, loss.get(), p);
		if (pb.NumResidualBlocks() > 0) {
			ceres::Solver::Options so;
			/* A window has 5-10 cameras: the dense Schur complement is the cheapest solver. */
			so.linear_solver_type = ceres::DENSE_SCHUR;
			so.logging_type = ceres::SILENT;
			so.num_threads = 1;
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
