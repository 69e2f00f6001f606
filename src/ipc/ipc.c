#include "mvod/ipc.h"

#include <assert.h>
#include <errno.h>
#include <stddef.h>
#include <stdio.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "ipc/lcm_log.h"
#include "mvod/status.h"
#include "mvod_pose2_t.h"
#include "mvod_pose_t.h"
#include "mvod_status2_t.h"
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
 * The four messages: each type on its own channel, the v2 types (pose2_t, status2_t: every v1
 * field, then new ones) beside the v1 ones, on the v1 channel's name + "2".
 */
enum msg { POSE, STATUS, POSE2, STATUS2, MSGS };

/*
 * One allocation holds the struct, the encoding buffers and the channel names, so the
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
	uint8_t *buf[MSGS];
	int len[MSGS];
	char *channel[MSGS];
	char storage[];
};

/* The encoded sizes do not depend on field values: these types hold no arrays of variable length. */
static void encoded_sizes(int len[MSGS])
{
	len[POSE] = mvod_pose_t_encoded_size(&(mvod_pose_t){0});
	len[STATUS] = mvod_status_t_encoded_size(&(mvod_status_t){0});
	len[POSE2] = mvod_pose2_t_encoded_size(&(mvod_pose2_t){0});
	len[STATUS2] = mvod_status2_t_encoded_size(&(mvod_status2_t){0});
}

/*
 * Checked here so a bad configured name fails at startup, not on every publish; the v2
 * channel's name is one character longer.
 */
static bool channel_valid(const char *channel)
{
	size_t len = strlen(channel);
	return len > 0 && len <= MVOD_MAX_CHANNEL_LENGTH;
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

/* Lays out the buffers and the channel names (v1, then v1 + "2") in ipc->storage. */
static void layout(struct mvod_ipc *ipc, const int len[MSGS], const char *const names[2])
{
	char *p = ipc->storage;
	for (int m = 0; m < MSGS; m++) {
		ipc->len[m] = len[m];
		ipc->buf[m] = (uint8_t *)p;
		p += len[m];
	}
	for (int m = 0; m < MSGS; m++) {
		ipc->channel[m] = p;
		p += sprintf(p, "%s%s", names[m % 2], m >= POSE2 ? "2" : "") + 1;
	}
}

int mvod_ipc_create_with(mvod_ipc_send_fn send, void *ctx, const char *pose_channel,
			 const char *status_channel, struct mvod_ipc **out)
{
	if (!send || !out)
		return -EINVAL;
	const char *names[2] = {pose_channel ? pose_channel : MVOD_DEFAULT_POSE_CHANNEL,
				status_channel ? status_channel : MVOD_DEFAULT_STATUS_CHANNEL};
	if (!channel_valid(names[0]) || !channel_valid(names[1]))
		return -EINVAL;

	int len[MSGS];
	encoded_sizes(len);
	size_t size = sizeof(struct mvod_ipc) + 2 * (strlen(names[0]) + strlen(names[1])) + 6;
	for (int m = 0; m < MSGS; m++)
		size += (size_t)len[m];
	struct mvod_ipc *ipc = calloc(1, size);
	if (!ipc)
		return -ENOMEM;
	ipc->send = send;
	ipc->send_ctx = ctx;
	layout(ipc, len, names);
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
	char path[4096], mode;
	if (!out)
		return -EINVAL;
	/* LCM_DEFAULT_URL too: a file:// log named there is written by mvod as well. */
	const char *u = url ? url : getenv("LCM_DEFAULT_URL");
	int ret = mvod_lcm_file_url(u, path, sizeof(path), &mode);
	if (ret != -ENOENT && ret != 0)
		return ret;
	if (ret == 0 && mode == 'w')
		return create_log(u, path, pose_channel, status_channel, out);
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
	size_t event = 0; /* the longest channel name and message */
	for (int m = 0; m < MSGS; m++) {
		size_t e = strlen(ipc->channel[m]) + (size_t)ipc->len[m];
		event = e > event ? e : event;
	}
	char what[4200];
	snprintf(what, sizeof(what), "--lcm-url %s: LCM log", ipc->log_url);
	return mvod_lcm_log_open(what, ipc->log_path, event, &ipc->log, err, errlen);
}

int mvod_ipc_finish(struct mvod_ipc *ipc)
{
	if (!ipc || !ipc->log)
		return 0;
	int ret = mvod_lcm_log_close(ipc->log);
	ipc->log = NULL;
	return ret;
}

int mvod_ipc_reopen_log(struct mvod_ipc *ipc, char *err, size_t errlen)
{
	return ipc && ipc->log ? mvod_lcm_log_reopen(ipc->log, err, errlen) : 0;
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

/*
 * A v2 type begins with every field of its v1 type, in order: the common initial sequence of
 * a union (C11 6.5.2.3), so each v1 message is read out of its v2 one and the other way round,
 * with no field listed twice. The asserts hold the layouts to that.
 */
union pose_msg {
	mvod_pose_t v1;
	mvod_pose2_t v2;
};
union status_msg {
	mvod_status_t v1;
	mvod_status2_t v2;
};
_Static_assert(offsetof(mvod_pose_t, inliers) == offsetof(mvod_pose2_t, inliers),
	       "mvod.pose2_t does not begin with mvod.pose_t's fields");
_Static_assert(offsetof(mvod_status_t, faults) == offsetof(mvod_status2_t, faults),
	       "mvod.status2_t does not begin with mvod.status_t's fields");

void mvod_pose_msg_upgrade(const mvod_pose_t *v1, mvod_pose2_t *v2)
{
	union pose_msg u = {.v2 = {0}};
	u.v1 = *v1;
	*v2 = u.v2;
}

void mvod_status_msg_upgrade(const mvod_status_t *v1, mvod_status2_t *v2)
{
	union status_msg u = {.v2 = {0}};
	u.v1 = *v1;
	*v2 = u.v2;
}

/* Encodes msg of kind m into its buffer and sends it; the size was fixed at create. */
static int publish(const struct mvod_ipc *ipc, enum msg m, const void *msg)
{
	int len = -1;
	switch (m) {
	case POSE: len = mvod_pose_t_encode(ipc->buf[m], 0, ipc->len[m], msg); break;
	case STATUS: len = mvod_status_t_encode(ipc->buf[m], 0, ipc->len[m], msg); break;
	case POSE2: len = mvod_pose2_t_encode(ipc->buf[m], 0, ipc->len[m], msg); break;
	case STATUS2: len = mvod_status2_t_encode(ipc->buf[m], 0, ipc->len[m], msg); break;
	case MSGS: break;
	}
	if (len < 0)
		return -EMSGSIZE;
	return ipc->send(ipc->send_ctx, ipc->channel[m], ipc->buf[m], (size_t)len);
}

/* v2 first, then v1 (so a reader of both, as mvod view, knows from the first message). */
int mvod_ipc_publish_pose(struct mvod_ipc *ipc, int64_t utime, int64_t frame,
			  const struct mvod_vo_result *res)
{
	assert(ipc && res);
	union pose_msg u = {.v2 = {
		.utime = utime,
		.frame = frame,
		.state = (int8_t)res->state,
		.scale_source = (int8_t)res->scale_source,
		.frame_status = (int8_t)res->status,
		.features = res->features,
		.matches = res->matches,
		.inliers = res->inliers,
		.keyframe = res->keyframe,
		.quality = (float)res->quality,
	}};
	memcpy(u.v2.position, res->pose.t, sizeof(u.v2.position));
	mvod_rot_to_quat(res->pose.R, u.v2.orientation);
	int ret = publish(ipc, POSE2, &u.v2);
	int ret1 = publish(ipc, POSE, &u.v1);
	return ret ? ret : ret1;
}

void mvod_status_to_msg(const struct mvod_status *st, mvod_status2_t *msg)
{
	*msg = (mvod_status2_t){
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
		.map_points = st->map_points,
		.keyframes = st->keyframes,
		.scale = st->scale,
		.scale_confidence = (float)st->scale_confidence,
		.latency_ms = (float)st->latency_ms,
	};
}

int mvod_run_state_from_wire(int state)
{
	return state >= MVOD_RUN_STARTING && state <= MVOD_RUN_STOPPING ? state : MVOD_RUN_UNKNOWN;
}

void mvod_status_from_msg(const mvod_status2_t *msg, struct mvod_status *st)
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
		.state = (enum mvod_run_state)mvod_run_state_from_wire(msg->state),
		.faults = msg->faults,
		.map_points = msg->map_points,
		.keyframes = msg->keyframes,
		.scale = msg->scale,
		.scale_confidence = msg->scale_confidence,
		.latency_ms = msg->latency_ms,
	};
}

int mvod_ipc_publish_status(struct mvod_ipc *ipc, const struct mvod_status *st)
{
	assert(ipc && st);
	union status_msg u;
	mvod_status_to_msg(st, &u.v2);
	int ret = publish(ipc, STATUS2, &u.v2);
	int ret1 = publish(ipc, STATUS, &u.v1);
	return ret ? ret : ret1;
}
