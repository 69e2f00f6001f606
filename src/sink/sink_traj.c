/* The trajectory sink: every pose to a TUM or KITTI file; reopened by name on SIGHUP. */
#include "mvod/sink.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "mvod/log.h"
#include "util/errbuf.h"
#include "mvod_status_t.h"

struct traj_sink {
	struct mvod_traj_writer *w; /* NULL once closed */
	const char *path;           /* borrowed: the run's options */
	struct mvod_faults *faults; /* borrowed */
};

static int traj_frame(void *ctx, const struct mvod_frame_out *f)
{
	struct traj_sink *s = ctx;
	const int32_t bit = MVOD_STATUS_T_FAULT_TRAJECTORY_WRITE;
	if (s->faults->bits & bit)
		return 0;
	int ret = mvod_traj_writer_add(s->w, f->frame->utime / 1e6, f->pose);
	if (ret && mvod_faults_set(s->faults, bit))
		LOG(ERROR, "trajectory %s: %s at frame %lld; it is incomplete from there on "
			   "(poses still go out over LCM) and mvod will exit with status 1",
		    s->path, strerror(-ret), (long long)f->frame->index);
	return 0;
}

/* Log rotation: the trajectory goes on in a new file under its name. */
static void traj_between(void *ctx, bool reopen)
{
	struct traj_sink *s = ctx;
	if (!reopen)
		return;
	char err[MVOD_ERR_MAX] = "";
	int ret = mvod_traj_writer_reopen(s->w, err, sizeof(err));
	if (ret)
		LOG(ERROR, "cannot reopen trajectory: %s; still writing to the file open before", err);
	else
		LOG(INFO, "reopened trajectory %s", s->path);
}

/* An incomplete trajectory is a failed run, even though the poses went out over LCM. */
static int traj_finish(void *ctx, struct mvod_run_summary *summary)
{
	struct traj_sink *s = ctx;
	int ret = mvod_traj_writer_close(s->w);
	s->w = NULL;
	if (ret && !(s->faults->bits & MVOD_STATUS_T_FAULT_TRAJECTORY_WRITE))
		LOG(ERROR, "trajectory %s: %s", s->path, strerror(-ret));
	return ret;
}

static void traj_destroy(void *ctx)
{
	struct traj_sink *s = ctx;
	mvod_traj_writer_close(s->w); /* a run that never started: nothing written to lose */
	free(s);
}

static const struct mvod_sink_ops traj_ops = {
	.name = "trajectory",
	.frame = traj_frame,
	.between = traj_between,
	.finish = traj_finish,
	.destroy = traj_destroy,
};

int mvod_sink_traj_create(const char *path, enum mvod_traj_format fmt,
			  struct mvod_faults *faults, struct mvod_sink *out, char *err,
			  size_t errlen)
{
	struct traj_sink *s = calloc(1, sizeof(*s));
	if (!s)
		return mvod_errf(err, errlen, -ENOMEM, "trajectory %s: %s", path, strerror(ENOMEM));
	int ret = mvod_traj_writer_open(path, fmt, &s->w, err, errlen);
	if (ret) {
		free(s);
		return ret;
	}
	s->path = path;
	s->faults = faults;
	*out = (struct mvod_sink){&traj_ops, s};
	return 0;
}
