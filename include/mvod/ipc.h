/* LCM publishing of mvod.pose_t and mvod.status_t. */
#ifndef MVOD_IPC_H
#define MVOD_IPC_H

#include <stdint.h>

#include <lcm/lcm.h>

#include "mvod/vo.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MVOD_DEFAULT_POSE_CHANNEL "MVOD_POSE"
#define MVOD_DEFAULT_STATUS_CHANNEL "MVOD_STATUS"

struct mvod_status; /* mvod/pipeline.h */
struct mvod_ipc;

/*
 * url: an LCM provider URL, or NULL for LCM_DEFAULT_URL and then LCM's own default.
 * Channels NULL = the defaults above. Encoding buffers are allocated here, once.
 */
int mvod_ipc_create(const char *url, const char *pose_channel, const char *status_channel,
		    struct mvod_ipc **out);
/* Same, on an lcm_t the caller owns and keeps alive longer (tests over memq://). */
int mvod_ipc_create_on(lcm_t *lcm, const char *pose_channel, const char *status_channel,
		       struct mvod_ipc **out);
void mvod_ipc_destroy(struct mvod_ipc *ipc);

int mvod_ipc_publish_pose(struct mvod_ipc *ipc, int64_t utime, int64_t frame,
			  const struct mvod_vo_result *res);
int mvod_ipc_publish_status(struct mvod_ipc *ipc, const struct mvod_status *st);

/*
 * The one conversion between struct mvod_status and the generated mvod.status_t
 * (mvod_status_t.h), both ways: publishing uses the first, mvod view the second.
 */
struct _mvod_status_t;
void mvod_status_to_msg(const struct mvod_status *st, struct _mvod_status_t *msg);
void mvod_status_from_msg(const struct _mvod_status_t *msg, struct mvod_status *st);

#ifdef __cplusplus
}
#endif

#endif
