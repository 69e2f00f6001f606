#include "mvod/ipc.h"

#include <assert.h>
#include <errno.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

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
 */
struct mvod_ipc {
	lcm_t *lcm;
	bool owns_lcm;
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

int mvod_ipc_create_on(lcm_t *lcm, const char *pose_channel, const char *status_channel,
		       struct mvod_ipc **out)
{
	if (!lcm || !out)
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

	ipc->lcm = lcm;
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

int mvod_ipc_create(const char *url, const char *pose_channel, const char *status_channel,
		    struct mvod_ipc **out)
{
	struct mvod_ipc *ipc = NULL;
	if (!out)
		return -EINVAL;
	/* A NULL url makes lcm_create consult LCM_DEFAULT_URL, then fall back to its default. */
	lcm_t *lcm = lcm_create(url);
	if (!lcm)
		return -EINVAL;

	int ret = mvod_ipc_create_on(lcm, pose_channel, status_channel, &ipc);
	if (ret < 0)
		goto err_lcm;
	ipc->owns_lcm = true;
	*out = ipc;
	return 0;

err_lcm:
	lcm_destroy(lcm);
	return ret;
}

void mvod_ipc_destroy(struct mvod_ipc *ipc)
{
	if (!ipc)
		return;
	if (ipc->owns_lcm)
		lcm_destroy(ipc->lcm);
	free(ipc);
}

static int publish(lcm_t *lcm, const char *channel, const uint8_t *buf, int len)
{
	/* LCM reports failure as -1 without a cause; a send that fails is an I/O error. */
	if (len < 0)
		return -EMSGSIZE;
	return lcm_publish(lcm, channel, buf, (unsigned int)len) == 0 ? 0 : -EIO;
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
	return publish(ipc->lcm, ipc->pose_channel, ipc->pose_buf, len);
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
	return publish(ipc->lcm, ipc->status_channel, ipc->status_buf, len);
}
