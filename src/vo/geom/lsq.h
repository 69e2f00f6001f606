/*
 * Levenberg-Marquardt on a small dense problem: the loop the pose refinements share (two-view's
 * Sampson refinement, motion.c: 5 parameters; PnP's, pnp_shim.cpp, and map mode's pose on every
 * track, posefit.c: 6). Each keeps what is its own: the cost, the normal equations (residuals,
 * Jacobians, robust weights) and how a step moves its state; the loop (damping, trying,
 * accepting, stopping) is here once, its rules set by the options each solver was measured
 * with. Bundle adjustment (optim/ba_lm.c) is not this algorithm: Ceres's trust region (Jacobi
 * scaling, a step's quality against its model) over a Schur complement.
 *
 * Plain C, no allocation: the state and the system live on the stack.
 */
#ifndef MVOD_VO_GEOM_LSQ_H
#define MVOD_VO_GEOM_LSQ_H

#include <stdbool.h>

#ifdef __cplusplus
extern "C" {
#endif

#define MVOD_LSQ_MAX_DIM 6    /* parameters of a step */
#define MVOD_LSQ_MAX_STATE 12 /* doubles of a state (a rotation and a translation) */

struct mvod_lsq_problem {
	int dim;       /* parameters of a step, <= MVOD_LSQ_MAX_DIM */
	int state_len; /* doubles of a state, <= MVOD_LSQ_MAX_STATE */
	void *ctx;     /* the solver's own, passed to each function */
	/* The cost at state x (any robust loss; only its comparisons matter). */
	double (*cost)(void *ctx, const double *x);
	/*
	 * The normal equations at x: J^T W J into A (dim x dim, row-major) and J^T W r into g,
	 * both zeroed before the call (W: the robust weights).
	 */
	void (*normal)(void *ctx, const double *x, double *A, double *g);
	/* State x moved by step d (dim parameters) into out (not x). */
	void (*move)(void *ctx, const double *x, const double *d, double *out);
	/*
	 * Optional: after an accepted step d to state x, whether the solve has converged (a
	 * step too small to matter). NULL: it runs its iterations.
	 */
	bool (*converged)(void *ctx, const double *x, const double *d);
};

/* How the damping lambda enters the system's diagonal. */
enum mvod_lsq_damping {
	MVOD_LSQ_SCALE, /* A_ii (1 + lambda) */
	MVOD_LSQ_ADD,   /* A_ii + lambda A_ii (the same in exact arithmetic, not in rounding) */
};

struct mvod_lsq_options {
	int iterations; /* normal equations evaluated at most */
	/*
	 * Steps tried per iteration, the damping growing tenfold after each that does not lower
	 * the cost; 0: until lambda exceeds lambda_max.
	 */
	int tries;
	double lambda, lambda_min, lambda_max; /* start; floor after a success; ceiling */
	enum mvod_lsq_damping damping;
	/* An iteration whose tries all fail ends the solve; else the next tries on from there. */
	bool stop_when_stuck;
};

/*
 * Minimises p's cost from state x (in and out: changed only by steps that lower the cost).
 * Returns the steps accepted; *singular (may be NULL) says whether the solve ended on a damped
 * system that could not be solved (x then holds the last accepted state).
 */
int mvod_lsq_solve(const struct mvod_lsq_problem *p, const struct mvod_lsq_options *o,
		   double *x, bool *singular);

#ifdef __cplusplus
}
#endif

#endif
