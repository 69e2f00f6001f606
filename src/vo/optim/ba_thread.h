/*
 * Windowed bundle adjustment off the frame path: one job buffer, sized at create for the
 * largest window, that changes hands between the frame thread (which fills it with a snapshot
 * of the window and posts it) and a thread of its own (which solves it: ba_lm.h), as capture
 * hands frames over in its mailbox. The frame thread never touches the job while it is posted;
 * the BA thread touches nothing else. Measured on KITTI 06/07 with bundle adjustment inline:
 * keyframe frames took up to 630 ms.
 *
 * The job names what it came from by map ids (slot + generation): when the result comes back
 * frames later, a keyframe or point that left the map in between is a stale id and is skipped.
 */
#ifndef MVOD_BA_THREAD_H
#define MVOD_BA_THREAD_H

#include <stdbool.h>

#include "ba.h"
#include "vo/core/id.h"

struct mvod_ba_job {
	struct mvod_ba_problem p;   /* its arrays are those below */
	struct mvod_ba_options o;
	struct mvod_ba_result r;    /* out */
	int ret;                    /* out: mvod_ba_solve's return */
	double *poses, *points;     /* [kf_cap * 6], [point_cap * 3] */
	uint8_t *fixed;             /* [kf_cap] */
	struct mvod_ba_obs *obs;    /* [point_cap * kf_cap]: a point is seen once per keyframe */
	uint8_t *outlier;           /* [point_cap * kf_cap] */
	mvod_map_id *kf;            /* [kf_cap] the keyframe of each pose */
	mvod_map_id *pt;            /* [point_cap] the map point of each point */
	mvod_map_id *obs_kf;        /* [point_cap * kf_cap] the keyframe of each observation */
};

struct mvod_ba_thread;

/*
 * Starts the thread (named "mvod-ba") with a job for kf_cap keyframes and point_cap points.
 * -ENOMEM, or pthread_create's error.
 */
int mvod_ba_thread_create(int kf_cap, int point_cap, struct mvod_ba_thread **out);
/* Waits for a running solve to end, then stops the thread. NULL is a no-op. */
void mvod_ba_thread_destroy(struct mvod_ba_thread *t);

/*
 * Frame thread: the job to fill, or NULL while the BA thread holds it or its result waits to
 * be taken (mvod_ba_thread_take it first).
 */
struct mvod_ba_job *mvod_ba_thread_job(struct mvod_ba_thread *t);
/* Frame thread: hands the filled job to the BA thread. */
void mvod_ba_thread_post(struct mvod_ba_thread *t);
/*
 * Frame thread: the solved job (valid until the next post), when there is one; with wait, a
 * posted job is waited for. Returns true with *out, false when nothing was posted (or, without
 * wait, the solve is still running).
 */
bool mvod_ba_thread_take(struct mvod_ba_thread *t, bool wait, struct mvod_ba_job **out);

#endif
