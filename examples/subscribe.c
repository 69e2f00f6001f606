/*
 * A C subscriber to mvod: prints every pose on MVOD_POSE2 and every status on MVOD_STATUS2
 * (mvod.pose2_t and status2_t; mvod publishes the older pose_t and status_t beside them on
 * MVOD_POSE and MVOD_STATUS, whose constants both use).
 *
 *   cc subscribe.c $(pkg-config --cflags --libs mvod-lcmtypes) -o mvod-subscribe
 *   ./mvod-subscribe 'file:///tmp/run.lcmlog?mode=r&speed=0'   # a log of a run; ends with it
 *   ./mvod-subscribe URL                     # beside a running mvod: the URL of its --lcm-url
 */
#include <inttypes.h>
#include <stdio.h>
#include <string.h>

#include <lcm/lcm.h>
#include <mvod_pose2_t.h>
#include <mvod_pose_t.h>
#include <mvod_status2_t.h>
#include <mvod_status_t.h>

static const char *const state_names[] = {
	[MVOD_POSE_T_STATE_STARTING] = "STARTING",
	[MVOD_POSE_T_STATE_INITIALIZING] = "INITIALIZING",
	[MVOD_POSE_T_STATE_TRACKING] = "TRACKING",
	[MVOD_POSE_T_STATE_LOST] = "LOST",
	[MVOD_POSE_T_STATE_SOURCE_DOWN] = "SOURCE_DOWN",
	[MVOD_POSE_T_STATE_STOPPING] = "STOPPING",
};

static const struct {
	int32_t bit;
	const char *name;
} fault_names[] = {
	{MVOD_STATUS_T_FAULT_TRAJECTORY_WRITE, "TRAJECTORY_WRITE"},
	{MVOD_STATUS_T_FAULT_FRAME_UNREADABLE, "FRAME_UNREADABLE"},
	{MVOD_STATUS_T_FAULT_SOURCE_BROKEN, "SOURCE_BROKEN"},
	{MVOD_STATUS_T_FAULT_PUBLISH, "PUBLISH"},
};

static void print_state(int8_t state)
{
	if (state >= 0 && state < (int)(sizeof(state_names) / sizeof(state_names[0])) &&
	    state_names[state])
		printf("state=%s", state_names[state]);
	else
		printf("state=%d", state); /* a state newer than these bindings */
}

static void on_pose(const lcm_recv_buf_t *rbuf, const char *channel, const mvod_pose2_t *p,
		    void *user)
{
	printf("pose frame=%" PRId64 " utime=%" PRId64 " position=%.6f,%.6f,%.6f "
	       "orientation=%.6f,%.6f,%.6f,%.6f ", p->frame, p->utime, p->position[0],
	       p->position[1], p->position[2], p->orientation[0], p->orientation[1],
	       p->orientation[2], p->orientation[3]);
	print_state(p->state);
	printf(" quality=%.3f keyframe=%d\n", p->quality, p->keyframe);
}

static void on_status(const lcm_recv_buf_t *rbuf, const char *channel, const mvod_status2_t *s,
		      void *user)
{
	printf("status utime=%" PRId64 " frames=%" PRId64 " ", s->utime, s->frames);
	print_state(s->state);
	printf(" faults=");
	int32_t left = s->faults;
	for (size_t i = 0; i < sizeof(fault_names) / sizeof(fault_names[0]); i++) {
		if (left & fault_names[i].bit) {
			left &= ~fault_names[i].bit;
			printf("%s%s", fault_names[i].name, left ? "|" : "");
		}
	}
	if (!s->faults)
		printf("none");
	else if (left) /* bits newer than these bindings, in hex */
		printf("0x%" PRIx32, (uint32_t)left);
	printf(" map_points=%" PRId32 " keyframes=%" PRId32 " scale=%.6g latency_ms=%.3f\n",
	       s->map_points, s->keyframes, s->scale, s->latency_ms);
}

int main(int argc, char **argv)
{
	if (argc != 2) {
		fprintf(stderr, "usage: %s LCM_URL (mvod's --lcm-url, or a file:// log "
			"with ?mode=r&speed=0)\n", argv[0]);
		return 2;
	}
	lcm_t *lcm = lcm_create(argv[1]);
	if (!lcm) {
		fprintf(stderr, "%s: LCM cannot open %s\n", argv[0], argv[1]);
		return 1;
	}
	setvbuf(stdout, NULL, _IOLBF, 0); /* a line per message, also into a pipe */
	mvod_pose2_t_subscription_t *ps = mvod_pose2_t_subscribe(lcm, "MVOD_POSE2", on_pose, NULL);
	mvod_status2_t_subscription_t *ss =
		mvod_status2_t_subscribe(lcm, "MVOD_STATUS2", on_status, NULL);
	/* LCM's file provider reports the end of a log as an error. */
	while (lcm_handle(lcm) == 0)
		;
	mvod_status2_t_unsubscribe(lcm, ss);
	mvod_pose2_t_unsubscribe(lcm, ps);
	lcm_destroy(lcm);
	return strncmp(argv[1], "file://", 7) == 0 ? 0 : 1;
}
