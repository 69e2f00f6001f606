/* The run's outputs, the sinks (src/sink/), in the order they are called, and the fan-out. */
#include "internal.h"

#include <errno.h>

#include "mvod/log.h"
#include "util/errbuf.h"
#include "util/output.h"

/* Appends a sink made by the caller of mvod_run (owned false) or here (true), after ret 0. */
static int add_sink(struct run *r, int ret, const struct mvod_sink *made, bool owned)
{
	if (ret)
		return ret;
	if (r->n_sinks == MAX_SINKS) {
		if (owned && made->ops->destroy)
			made->ops->destroy(made->ctx);
		return -E2BIG;
	}
	r->owned[r->n_sinks] = owned;
	r->sinks[r->n_sinks++] = *made;
	return 0;
}

/*
 * Outputs open last, so bad input never leaves an empty or truncated output behind; every one
 * goes through the output policy (util/output.h), and none truncates before its first record. The
 * evaluation comes first (the plot draws what it kept), then the caller's sinks (they see
 * each frame before it is published), systemd, LCM, the plot and the trajectory.
 */
int mvod_run_open_outputs(struct run *r)
{
	const struct mvod_run_opts *o = r->o;
	char err[MVOD_ERR_MAX] = "", target[4096];
	int ret = o->plot ? mvod_output_check("--plot", o->plot, target, sizeof(target), NULL, err,
					      sizeof(err))
			  : 0;
	if (!ret && r->ipc)
		ret = mvod_ipc_open_log(r->ipc, err, sizeof(err));
	if (ret) {
		LOG(ERROR, "%s", err);
		return ret;
	}
	struct mvod_sink m;
	bool metric = mvod_scale_mode_metric(o->vo.scale_mode); /* metres: no scale alignment */
	ret = add_sink(r, mvod_sink_eval_create(!metric, r->gt.n, &m), &m, true);
	const struct mvod_sink *eval = &r->sinks[0];
	for (int i = 0; i < o->n_sinks; i++)
		ret = add_sink(r, ret, &o->sinks[i], false);
	if (!ret)
		ret = add_sink(r, mvod_sink_notify_create(&m), &m, true);
	if (!ret && r->ipc)
		ret = add_sink(r, mvod_sink_lcm_create(r->ipc, &r->faults, &m), &m, true);
	if (!ret && o->plot) {
		ret = mvod_sink_plot_create(o->plot, o->source, metric, eval, &m);
		ret = add_sink(r, ret, &m, true);
	}
	if (ret || !o->trajectory)
		return ret;
	ret = mvod_sink_traj_create(o->trajectory, o->traj_format, &r->faults, &m, err,
				    sizeof(err));
	if (ret)
		LOG(ERROR, "%s", err);
	return add_sink(r, ret, &m, true);
}

/* The fan-out: each sink's hook in order. frame and finish return the first error. */
int mvod_run_sinks_frame(struct run *r, const struct mvod_frame_out *f)
{
	int ret = 0;
	for (int i = 0; i < r->n_sinks; i++) {
		const struct mvod_sink *s = &r->sinks[i];
		int sret = s->ops->frame ? s->ops->frame(s->ctx, f) : 0;
		ret = ret ? ret : sret;
	}
	return ret;
}

void mvod_run_sinks_status(struct run *r, const struct mvod_status *st, bool news)
{
	for (int i = 0; i < r->n_sinks; i++)
		if (r->sinks[i].ops->status)
			r->sinks[i].ops->status(r->sinks[i].ctx, st, news);
}

void mvod_run_sinks_between(struct run *r, bool reopen)
{
	for (int i = 0; i < r->n_sinks; i++)
		if (r->sinks[i].ops->between)
			r->sinks[i].ops->between(r->sinks[i].ctx, reopen);
}

int mvod_run_sinks_finish(struct run *r)
{
	int ret = 0;
	for (int i = 0; i < r->n_sinks; i++) {
		const struct mvod_sink *s = &r->sinks[i];
		int sret = s->ops->finish ? s->ops->finish(s->ctx, r->sum) : 0;
		ret = ret ? ret : sret;
	}
	return ret;
}

void mvod_run_sinks_destroy(struct run *r)
{
	for (int i = r->n_sinks - 1; i >= 0; i--)
		if (r->owned[i] && r->sinks[i].ops->destroy)
			r->sinks[i].ops->destroy(r->sinks[i].ctx);
}
