/* The systemd sink (Type=notify): readiness, watchdog, a status line, stopping. Stateless. */
#include "mvod/sink.h"

#include "mvod/status.h"
#include "util/notify.h"

static int notify_frame(void *ctx, const struct mvod_frame_out *f)
{
	mvod_notify_ready(); /* sent once, after the first frame */
	return 0;
}

static void notify_status(void *ctx, const struct mvod_status *st, bool news)
{
	mvod_notify_status(news, "%s, %.1f fps, %lld frames, %lld dropped",
			   mvod_run_state_name(st->state), st->fps, (long long)st->frames,
			   (long long)st->dropped);
}

static void notify_between(void *ctx, bool reopen)
{
	mvod_notify_watchdog();
}

static int notify_finish(void *ctx, struct mvod_run_summary *summary)
{
	mvod_notify_stopping();
	return 0;
}

static const struct mvod_sink_ops notify_ops = {
	.name = "notify",
	.frame = notify_frame,
	.status = notify_status,
	.between = notify_between,
	.finish = notify_finish,
};

int mvod_sink_notify_create(struct mvod_sink *out)
{
	*out = (struct mvod_sink){&notify_ops, NULL};
	return 0;
}
