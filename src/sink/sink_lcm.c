/*
 * The LCM sink: every frame's mvod.pose_t, and each status report as mvod.status_t; a file://
 * log reopened by name on SIGHUP.
 */
#include "mvod/sink.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "mvod/log.h"
#include "util/errbuf.h"
#include "mvod_status_t.h"

struct lcm_sink {
	struct mvod_ipc *ipc;       /* borrowed */
	struct mvod_faults *faults; /* borrowed */
};

static int lcm_frame(void *ctx, const struct mvod_frame_out *f)
{
	struct lcm_sink *s = ctx;
	struct mvod_vo_result res = *f->res; /* with the pose in --frame's axes */
	res.pose = *f->pose;
	if (mvod_ipc_publish_pose(s->ipc, f->frame->utime, f->frame->index, &res) &&
	    mvod_faults_set(s->faults, MVOD_STATUS_T_FAULT_PUBLISH))
		LOG(ERROR, "frame %lld: publishing the pose over LCM failed (the transport or log "
			   "file refused it); mvod carries on, and says no more of it (a file:// log "
			   "ends there, and mvod will exit with status 1)",
		    (long long)f->frame->index);
	return 0;
}

static void lcm_status(void *ctx, const struct mvod_status *st, bool news)
{
	struct lcm_sink *s = ctx;
	if (mvod_ipc_publish_status(s->ipc, st) &&
	    mvod_faults_set(s->faults, MVOD_STATUS_T_FAULT_PUBLISH))
		LOG(ERROR, "publishing status over LCM failed (the transport or log file refused "
			   "it); mvod carries on, and says no more of it");
}

/* Log rotation: a file:// log goes on in a new file under its name, as the trajectory does. */
static void lcm_between(void *ctx, bool reopen)
{
	struct lcm_sink *s = ctx;
	if (!reopen || !mvod_ipc_log_path(s->ipc))
		return;
	char err[MVOD_ERR_MAX] = "";
	if (mvod_ipc_reopen_log(s->ipc, err, sizeof(err)))
		LOG(ERROR, "cannot reopen LCM log: %s; still writing to the file open before", err);
	else
		LOG(INFO, "reopened LCM log %s", mvod_ipc_log_path(s->ipc));
}

/* An incomplete file:// LCM log is a failed run, as an incomplete trajectory is. */
static int lcm_finish(void *ctx, struct mvod_run_summary *summary)
{
	struct lcm_sink *s = ctx;
	int ret = mvod_ipc_finish(s->ipc);
	if (ret && !(s->faults->bits & MVOD_STATUS_T_FAULT_PUBLISH))
		LOG(ERROR, "LCM log %s: %s", mvod_ipc_log_path(s->ipc), strerror(-ret));
	return ret;
}

static const struct mvod_sink_ops lcm_ops = {
	.name = "lcm",
	.frame = lcm_frame,
	.status = lcm_status,
	.between = lcm_between,
	.finish = lcm_finish,
	.destroy = free,
};

int mvod_sink_lcm_create(struct mvod_ipc *ipc, struct mvod_faults *faults, struct mvod_sink *out)
{
	struct lcm_sink *s = calloc(1, sizeof(*s));
	if (!s)
		return -ENOMEM;
	*s = (struct lcm_sink){ipc, faults};
	*out = (struct mvod_sink){&lcm_ops, s};
	return 0;
}
