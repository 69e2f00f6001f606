/*
 * The evaluation sink: the estimated and ground-truth paths, RPE over consecutive frames with
 * ground truth, and at the end the ATE after Umeyama alignment, into the run's summary.
 */
#include "eval_sink.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "mvod/log.h"
#include "mvod/status.h"

/* Points kept for the plot and the ATE; longer runs are decimated, never grown. */
#define PATH_POINTS 20000

static int eval_frame(void *ctx, const struct mvod_frame_out *f)
{
	struct mvod_sink_eval *e = ctx;
	const struct mvod_pose *est = &f->res->pose, *gt = f->gt;
	if (f->restarted)
		e->prev_had_gt = false; /* no relative motion across the gap */
	mvod_path_add(&e->est_path, est->t);
	if (gt) {
		mvod_path_add(&e->gt_path, gt->t);
		mvod_path_add(&e->est_at_gt, est->t);
		e->gt_last = f->frame->index;
		e->gt_first = e->gt_frames++ ? e->gt_first : f->frame->index;
		if (e->prev_had_gt) {
			struct mvod_frame_err fe = mvod_rpe_add(&e->rpe, &e->prev_est, est,
								&e->prev_gt, gt);
			if (e->n_pairs < e->max_pairs)
				e->pairs[e->n_pairs++] = fe;
			else
				e->lost_pairs++;
			e->path_len_m += mvod_vec3_dist(gt->t, e->prev_gt.t);
		}
		e->prev_gt = *gt;
	}
	e->prev_had_gt = gt != NULL;
	e->prev_est = *est;
	e->have_prev = true;
	return 0;
}

/* err_avg in metres: the free-scale estimate scaled by the alignment's sc, as mvod bench. */
static void rescale_err(struct mvod_sink_eval *e, struct mvod_run_summary *s, double sc)
{
	if (e->lost_pairs) {
		LOG(WARN, "err_avg is in the estimate's own units, not metres: %d more frames "
			  "matched a ground-truth pose than the %d kept for it (twice the ground "
			  "truth's poses)", e->lost_pairs, e->max_pairs);
		return;
	}
	mvod_rpe_rescale_err(&e->rpe, e->pairs, e->n_pairs, sc);
	s->rpe.err_avg = e->rpe.err_avg;
	s->rpe.err_max = e->rpe.err_max;
}

/* A ground truth whose poses all lie within this of its first is static (metres). */
#define STATIC_GT_M 1e-3

/*
 * The ATE over the frames that have a ground-truth pose, if any do. Where no alignment exists
 * (a static ground truth, or an estimate that does not move), the ATE is NAN and the summary
 * says why, with how far the estimate went: an alignment would shrink it onto the still
 * ground truth and report 0. A free-scale estimate is in units of its first step: drawn raw
 * beside metric ground truth it says nothing, so the plot draws it through the same Sim(3)
 * alignment the ATE uses.
 */
static int eval_finish(void *ctx, struct mvod_run_summary *s)
{
	struct mvod_sink_eval *e = ctx;
	const struct mvod_path *g = &e->gt_path;
	mvod_rpe_finish(&e->rpe);
	s->rpe = e->rpe;
	s->path_len_m = e->path_len_m;
	s->gt_frames = e->gt_frames;
	s->gt_first = e->gt_first;
	s->gt_last = e->gt_last;
	memcpy(e->heading, e->prev_est.R, sizeof(e->heading));
	s->have_gt = g->n > 0;
	s->ate_rmse_m = s->ate_scale = NAN;
	if (!s->have_gt)
		return 0;
	double gt_len, gt_extent, R[9], t[3], sc;
	mvod_path_motion(e->est_path.xyz, e->est_path.n, &s->est_len, &s->est_extent);
	mvod_path_motion(g->xyz, g->n, &gt_len, &gt_extent);
	s->gt_static = gt_extent <= STATIC_GT_M;
	if (s->gt_static || mvod_umeyama(e->est_at_gt.xyz, g->xyz, g->n, e->sim3, R, t, &sc))
		return 0;
	s->ate_rmse_m = mvod_ate_rmse(e->est_at_gt.xyz, g->xyz, g->n, R, t, sc);
	s->ate_scale = sc;
	if (!e->sim3)
		return 0;
	rescale_err(e, s, sc);
	mvod_sim3_apply(R, t, sc, e->est_path.xyz, e->est_path.n);
	mvod_mat3_mul(R, e->heading, e->heading);
	e->aligned = true;
	return 0;
}

static void eval_destroy(void *ctx)
{
	struct mvod_sink_eval *e = ctx;
	mvod_path_fini(&e->est_path);
	mvod_path_fini(&e->gt_path);
	mvod_path_fini(&e->est_at_gt);
	free(e->pairs);
	free(e);
}

static const struct mvod_sink_ops eval_ops = {
	.name = "eval",
	.frame = eval_frame,
	.finish = eval_finish,
	.destroy = eval_destroy,
};

int mvod_sink_eval_create(bool sim3, int gt_poses, struct mvod_sink *out)
{
	struct mvod_sink_eval *e = calloc(1, sizeof(*e));
	if (!e)
		return -ENOMEM;
	e->sim3 = sim3;
	e->gt_first = e->gt_last = -1;
	/*
	 * A TUM pose serves the frames within 5 ms of it: at most 2 of a camera at up to 100 fps,
	 * so twice the poses is room for every pair.
	 */
	e->max_pairs = sim3 ? 2 * gt_poses : 0;
	e->pairs = e->max_pairs ? calloc((size_t)e->max_pairs, sizeof(*e->pairs)) : NULL;
	if ((e->max_pairs && !e->pairs) || mvod_path_init(&e->est_path, PATH_POINTS) ||
	    mvod_path_init(&e->gt_path, PATH_POINTS) || mvod_path_init(&e->est_at_gt, PATH_POINTS)) {
		eval_destroy(e);
		return -ENOMEM;
	}
	*out = (struct mvod_sink){&eval_ops, e};
	return 0;
}
