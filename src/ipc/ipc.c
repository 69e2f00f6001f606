#include "mvod/ipc.h"

#include <assert.h>
#include <errno.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "ipc/lcm_log.h"
#include "mvod/pipeline.h"
#include "mvod_pose_t.h"
#include "mvod_status_t.h"

/*
 * mvod's enums go on the wire as they are: a reader decodes them with the generated
 * constants, so each value is pinned to its constant here (types change only additively).
 */
#define SAME(a, b) _Static_assert((int)(a) == (b), #a " is not " #b " on the wire")
SAME(MVOD_RUN_STARTING, MVOD_POSE_T_STATE_STARTING);
SAME(MVOD_STATE_INITIALIZING, MVOD_POSE_T_STATE_INITIALIZING);
SAME(MVOD_STATE_TRACKING, MVOD_POSE_T_STATE_TRACKING);
SAME(MVOD_STATE_LOST, MVOD_POSE_T_STATE_LOST);
SAME(MVOD_RUN_SOURCE_DOWN, MVOD_POSE_T_STATE_SOURCE_DOWN);
SAME(MVOD_RUN_STOPPING, MVOD_POSE_T_STATE_STOPPING);
SAME(MVOD_SCALE_NONE, MVOD_POSE_T_SCALE_NONE);
SAME(MVOD_SCALE_STRUCTURE, MVOD_POSE_T_SCALE_STRUCTURE);
SAME(MVOD_SCALE_CONSTANT_SPEED, MVOD_POSE_T_SCALE_CONSTANT_SPEED);
SAME(MVOD_SCALE_GROUND_TRUTH, MVOD_POSE_T_SCALE_GROUND_TRUTH);
SAME(MVOD_SCALE_UNIT, MVOD_POSE_T_SCALE_UNIT);
SAME(MVOD_SCALE_MAP, MVOD_POSE_T_SCALE_MAP);
SAME(MVOD_SCALE_HEIGHT, MVOD_POSE_T_SCALE_HEIGHT);
SAME(MVOD_SCALE_EXTERNAL, MVOD_POSE_T_SCALE_EXTERNAL);
SAME(MVOD_FRAME_MOTION, MVOD_POSE_T_FRAME_MOTION);
SAME(MVOD_FRAME_FIRST, MVOD_POSE_T_FRAME_FIRST);
SAME(MVOD_FRAME_ROTATION, MVOD_POSE_T_FRAME_ROTATION);
SAME(MVOD_FRAME_FEW_FEATURES, MVOD_POSE_T_FRAME_FEW_FEATURES);
SAME(MVOD_FRAME_FEW_MATCHES, MVOD_POSE_T_FRAME_FEW_MATCHES);
SAME(MVOD_FRAME_RANSAC_FAILED, MVOD_POSE_T_FRAME_RANSAC_FAILED);
SAME(MVOD_FRAME_FEW_INLIERS, MVOD_POSE_T_FRAME_FEW_INLIERS);
/* The status message has one field per stage, in this order. */
SAME(MVOD_STAGE_COUNT, 5);
#undef SAME

/*
 * One allocation holds the struct, both encoding buffers and both channel names, so the
 * per-frame publish path touches no allocator (the generated *_publish mallocs per call).
 * Messages go out through one seam, send(): lcm_publish, mvod's own file:// log writer, or a
 * test's function.
 */
struct mvod_ipc {
	mvod_ipc_send_fn send;
	void *send_ctx;
	lcm_t *lcm;                /* owned when owns_lcm */
	bool owns_lcm;
	char *log_url, *log_path;  /* file://PATH?mode=w: opened by mvod_ipc_open_log, owned */
	struct mvod_lcm_log *log;
	uint8_t *pose_buf, *status_buf;
	int pose_len, status_len;
	char *pose_channel, *status_channel;
	char storage[];
};

/* The encoded sizes do not depend on field values: these types hold no arrays of variable length. */
static int pose_encoded_size(void)
{
	const mvod_pose_t msg = {0};
	return mvod_pose_t_encoded_size(&msg);
}

static int status_encoded_size(void)
{
	const mvod_status_t msg = {0};
	return mvod_status_t_encoded_size(&msg);
}

/* Checked here so a bad configured name fails at startup, not on every publish. */
static bool channel_valid(const char *channel)
{
	size_t len = strlen(channel);
	return len > 0 && len <= LCM_MAX_CHANNEL_NAME_LENGTH;
}

/* LCM reports failure as -1 without a cause; a send that fails is an I/O error. */
static int lcm_send(void *ctx, const char *channel, const void *buf, size_t len)
{
	return lcm_publish(ctx, channel, buf, (unsigned int)len) == 0 ? 0 : -EIO;
}

static int log_send(void *ctx, const char *channel, const void *buf, size_t len)
{
	struct mvod_ipc *ipc = ctx;
	return ipc->log ? mvod_lcm_log_write(ipc->log, channel, buf, len) : -EBADF;
}

int mvod_ipc_create_on(lcm_t *lcm, const char *pose_channel, const char *status_channel,
		       struct mvod_ipc **out)
{
	if (!lcm)
		return -EINVAL;
	int ret = mvod_ipc_create_with(lcm_send, lcm, pose_channel, status_channel, out);
	if (!ret)
		(*out)->lcm = lcm;
	return ret;
}

int mvod_ipc_create_with(mvod_ipc_send_fn send, void *ctx, const char *pose_channel,
			 const char *status_channel, struct mvod_ipc **out)
{
	if (!send || !out)
		return -EINVAL;
	if (!pose_channel)
		pose_channel = MVOD_DEFAULT_POSE_CHANNEL;
	if (!status_channel)
		status_channel = MVOD_DEFAULT_STATUS_CHANNEL;
	if (!channel_valid(pose_channel) || !channel_valid(status_channel))
		return -EINVAL;

	int pose_len = pose_encoded_size(), status_len = status_encoded_size();
	size_t pc_len = strlen(pose_channel) + 1, sc_len = strlen(status_channel) + 1;
	struct mvod_ipc *ipc = calloc(1, sizeof(*ipc) + (size_t)pose_len + (size_t)status_len +
						 pc_len + sc_len);
	if (!ipc)
		return -ENOMEM;

	ipc->send = send;
	ipc->send_ctx = ctx;
	ipc->pose_len = pose_len;
	ipc->status_len = status_len;
	ipc->pose_buf = (uint8_t *)ipc->storage;
	ipc->status_buf = ipc->pose_buf + pose_len;
	ipc->pose_channel = (char *)ipc->status_buf + status_len;
	ipc->status_channel = ipc->pose_channel + pc_len;
	memcpy(ipc->pose_channel, pose_channel, pc_len);
	memcpy(ipc->status_channel, status_channel, sc_len);
	*out = ipc;
	return 0;
}

/* A file:// log LCM would write: mvod's own writer, opened later by mvod_ipc_open_log. */
static int create_log(const char *url, const char *path, const char *pose_channel,
		      const char *status_channel, struct mvod_ipc **out)
{
	struct mvod_ipc *ipc = NULL;
	int ret = mvod_ipc_create_with(log_send, NULL, pose_channel, status_channel, &ipc);
	if (ret)
		return ret;
	ipc->send_ctx = ipc;
	ipc->log_path = strdup(path);
	ipc->log_url = strdup(url);
	if (!ipc->log_path || !ipc->log_url) {
		mvod_ipc_destroy(ipc);
		return -ENOMEM;
	}
	*out = ipc;
	return 0;
}

int mvod_ipc_create(const char *url, const char *pose_channel, const char *status_channel,
		    struct mvod_ipc **out)
{
	struct mvod_ipc *ipc = NULL;
	char path[4096];
	if (!out)
		return -EINVAL;
	/* LCM_DEFAULT_URL too: a file:// log named there is written by mvod as well. */
	const char *u = url ? url : getenv("LCM_DEFAULT_URL");
	int ret = mvod_lcm_log_url_path(u, path, sizeof(path));
	if (ret != -ENOENT)
		return ret ? ret : create_log(u, path, pose_channel, status_channel, out);
	/* A NULL url makes lcm_create consult LCM_DEFAULT_URL, then fall back to its default. */
	lcm_t *lcm = lcm_create(url);
	if (!lcm)
		return -EINVAL;

	ret = mvod_ipc_create_on(lcm, pose_channel, status_channel, &ipc);
	if (ret < 0)
		goto err_lcm;
	ipc->owns_lcm = true;
	*out = ipc;
	return 0;

err_lcm:
	lcm_destroy(lcm);
	return ret;
}

int mvod_ipc_open_log(struct mvod_ipc *ipc, char *err, size_t errlen)
{
	if (!ipc->log_path || ipc->log)
		return 0;
	size_t chan = strlen(ipc->pose_channel) > strlen(ipc->status_channel)
			      ? strlen(ipc->pose_channel)
			      : strlen(ipc->status_channel);
	size_t msg = (size_t)(ipc->pose_len > ipc->status_len ? ipc->pose_len : ipc->status_len);
	char what[4200];
	snprintf(what, sizeof(what), "--lcm-url %s: LCM log", ipc->log_url);
	return mvod_lcm_log_open(what, ipc->log_path, chan + msg, &ipc->log, err, errlen);
}

int mvod_ipc_finish(struct mvod_ipc *ipc)
{
	if (!ipc || !ipc->log)
		return 0;
	int ret = mvod_lcm_log_close(ipc->log);
	ipc->log = NULL;
	return ret;
}

const char *mvod_ipc_log_path(const struct mvod_ipc *ipc)
{
	return ipc ? ipc->log_path : NULL;
}

void mvod_ipc_destroy(struct mvod_ipc *ipc)
{
	if (!ipc)
		return;
	mvod_ipc_finish(ipc);
	if (ipc->owns_lcm)
		lcm_destroy(ipc->lcm);
	free(ipc->log_path);
	free(ipc->log_url);
	free(ipc);
}

static int publish(const struct mvod_ipc *ipc, const char *channel, const uint8_t *buf, int len)
{
	if (len < 0)
		return -EMSGSIZE;
	return ipc->send(ipc->send_ctx, channel, buf, (size_t)len);
}

int mvod_ipc_publish_pose(struct mvod_ipc *ipc, int64_t utime, int64_t frame,
			  const struct mvod_vo_result *res)
{
	assert(ipc && res);
	mvod_pose_t msg = {
		.utime = utime,
		.frame = frame,
		.state = (int8_t)res->state,
		.scale_source = (int8_t)res->scale_source,
		.frame_status = (int8_t)res->status,
		.features = res->features,
		.matches = res->matches,
		.inliers = res->inliers,
	};
	memcpy(msg.position, res->pose.t, sizeof(msg.position));
	mvod_rot_to_quat(res->pose.R, msg.orientation);

	int len = mvod_pose_t_encode(ipc->pose_buf, 0, ipc->pose_len, &msg);
	return publish(ipc, ipc->pose_channel, ipc->pose_buf, len);
}

void mvod_status_to_msg(const struct mvod_status *st, mvod_status_t *msg)
{
	*msg = (mvod_status_t){
		.utime = st->utime,
		.state = (int8_t)st->state,
		.fps = (float)st->fps,
		.capture_ms = (float)st->stage_ms[MVOD_STAGE_CAPTURE],
		.preprocess_ms = (float)st->stage_ms[MVOD_STAGE_PREPROCESS],
		.detect_ms = (float)st->stage_ms[MVOD_STAGE_DETECT],
		.match_ms = (float)st->stage_ms[MVOD_STAGE_MATCH],
		.pose_ms = (float)st->stage_ms[MVOD_STAGE_POSE],
		.features = st->features,
		.matches = st->matches,
		.inliers = st->inliers,
		.frames = st->frames,
		.dropped_frames = st->dropped,
		.rss_kb = st->rss_kb,
		.uptime_s = st->uptime_s,
		.faults = st->faults,
	};
}

void mvod_status_from_msg(const mvod_status_t *msg, struct mvod_status *st)
{
	*st = (struct mvod_status){
		.utime = msg->utime,
		.fps = msg->fps,
		.stage_ms = {msg->capture_ms, msg->preprocess_ms, msg->detect_ms, msg->match_ms,
			     msg->pose_ms},
		.features = msg->features,
		.matches = msg->matches,
		.inliers = msg->inliers,
		.frames = msg->frames,
		.dropped = msg->dropped_frames,
		.rss_kb = msg->rss_kb,
		.uptime_s = msg->uptime_s,
		.state = (enum mvod_run_state)msg->state,
		.faults = msg->faults,
	};
}

int mvod_ipc_publish_status(struct mvod_ipc *ipc, const struct mvod_status *st)
{
	assert(ipc && st);
	mvod_status_t msg;
	mvod_status_to_msg(st, &msg);
	int len = mvod_status_t_encode(ipc->status_buf, 0, ipc->status_len, &msg);
	return publish(ipc, ipc->status_channel, ipc->status_buf, len);
}
