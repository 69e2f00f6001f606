/* The --plot sink: a top-down PNG of the evaluation sink's paths, written once at the end. */
#include "eval_sink.h"

#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mvod/log.h"
#include "mvod/plot.h"

struct plot_sink {
	const char *path, *source;         /* borrowed: the run's options */
	bool gt_scale;                     /* --scale gt: the estimate is in metres already */
	const struct mvod_sink_eval *eval; /* borrowed */
};

static int plot_finish(void *ctx, struct mvod_run_summary *summary)
{
	struct plot_sink *p = ctx;
	const struct mvod_sink_eval *e = p->eval;
	char title[256];
	snprintf(title, sizeof(title), "mvod: %s%s", p->source,
		 e->aligned ? " (Sim(3)-aligned to ground truth)" : "");
	/* Metres once the ground truth set the scale, by --scale gt or by the Sim(3) alignment. */
	bool metric = e->aligned || p->gt_scale;
	int ret = mvod_plot_topdown(p->path, title, e->est_path.xyz, e->est_path.n,
				    e->have_prev ? e->heading : NULL, e->gt_path.xyz, e->gt_path.n,
				    mvod_plot_unit(metric));
	if (ret)
		LOG(ERROR, "cannot write plot %s: %s", p->path, strerror(-ret));
	return ret;
}

static const struct mvod_sink_ops plot_ops = {
	.name = "plot",
	.finish = plot_finish,
	.destroy = free,
};

int mvod_sink_plot_create(const char *path, const char *source, bool gt_scale,
			  const struct mvod_sink *eval, struct mvod_sink *out)
{
	char err[PATH_MAX + 128];
	int ret = mvod_plot_check("--plot", path, err, sizeof(err));
	if (ret) {
		LOG(ERROR, "%s", err);
		return ret;
	}
	struct plot_sink *p = calloc(1, sizeof(*p));
	if (!p)
		return -ENOMEM;
	*p = (struct plot_sink){path, source, gt_scale, eval->ctx};
	*out = (struct mvod_sink){&plot_ops, p};
	return 0;
}
