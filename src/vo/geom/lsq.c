#include "lsq.h"

#include <errno.h>
#include <math.h>
#include <string.h>

#include "mvod/geom.h"

/* The damped system M d = -g from the undamped A and g; false when it is singular. */
static bool damped_step(const struct mvod_lsq_problem *p, const struct mvod_lsq_options *o,
			const double *A, const double *g, double lambda, double *d)
{
	int n = p->dim;
	double M[MVOD_LSQ_MAX_DIM * MVOD_LSQ_MAX_DIM];
	memcpy(M, A, sizeof(double) * (size_t)(n * n));
	for (int q = 0; q < n; q++) {
		if (o->damping == MVOD_LSQ_SCALE)
			M[(n + 1) * q] *= 1 + lambda;
		else
			M[(n + 1) * q] += lambda * A[(n + 1) * q];
		d[q] = -g[q];
	}
	return mvod_linsolve(M, d, n);
}

/*
 * One iteration's tries from x (cost *c) with the system A, g: the first step that lowers the
 * cost is taken (x, *c, and the damping relaxed), else the damping grows. 1 when a step was
 * taken, 0 when none, -EDOM; d holds the last step tried.
 */
static int try_steps(const struct mvod_lsq_problem *p, const struct mvod_lsq_options *o,
		     const double *A, const double *g, double *lambda, double *x, double *c,
		     double *d)
{
	double xn[MVOD_LSQ_MAX_STATE];
	for (int t = 0; o->tries == 0 || t < o->tries; t++) {
		if (!damped_step(p, o, A, g, *lambda, d))
			return -EDOM;
		p->move(p->ctx, x, d, xn);
		double cn = p->cost(p->ctx, xn);
		if (cn < *c) {
			memcpy(x, xn, sizeof(double) * (size_t)p->state_len);
			*c = cn;
			*lambda = fmax(*lambda * 0.1, o->lambda_min);
			return 1;
		}
		*lambda *= 10;
		if (*lambda > o->lambda_max)
			break;
	}
	return 0;
}

int mvod_lsq_solve(const struct mvod_lsq_problem *p, const struct mvod_lsq_options *o,
		   double *x, bool *singular)
{
	double c = p->cost(p->ctx, x), lambda = o->lambda;
	int steps = 0;
	if (singular)
		*singular = false;
	for (int it = 0; it < o->iterations; it++) {
		double A[MVOD_LSQ_MAX_DIM * MVOD_LSQ_MAX_DIM] = {0}, g[MVOD_LSQ_MAX_DIM] = {0};
		double d[MVOD_LSQ_MAX_DIM];
		p->normal(p->ctx, x, A, g);
		int ret = try_steps(p, o, A, g, &lambda, x, &c, d);
		if (ret < 0 && singular)
			*singular = true;
		if (ret < 0)
			break;
		steps += ret;
		if (!ret && o->stop_when_stuck)
			break;
		if (ret && p->converged && p->converged(p->ctx, x, d))
			break;
	}
	return steps;
}
