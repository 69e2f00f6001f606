/* LCM publishing over memq:// (in-process) and file:// logs; nothing leaves the process. */
#include <errno.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>

#include "harness.h"
#include "ipc/lcm_log.h"
#include "mvod/ipc.h"
#include "mvod/pipeline.h"
#include "mvod/speed.h"
#include "mvod_pose2_t.h"
#include "mvod_pose_t.h"
#include "mvod_speed_t.h"
#include "mvod_status2_t.h"
#include "mvod_status_t.h"

#define N_POSES 10
#define DEG (M_PI / 180.0)

struct received {
	mvod_pose_t poses[N_POSES];
	int n_poses;
	mvod_status_t status;
	int n_status;
	mvod_pose2_t poses2[N_POSES];
	int n_poses2;
	mvod_status2_t status2;
	int n_status2;
};

struct fixture {
	lcm_t *lcm;
	struct received got;
};

static void on_pose(const lcm_recv_buf_t *rbuf, const char *channel, const mvod_pose_t *msg,
		    void *user)
{
	struct received *got = user;
	if (got->n_poses < N_POSES)
		got->poses[got->n_poses] = *msg;
	got->n_poses++;
}

static void on_status(const lcm_recv_buf_t *rbuf, const char *channel, const mvod_status_t *msg,
		      void *user)
{
	struct received *got = user;
	got->status = *msg;
	got->n_status++;
}

static void on_pose2(const lcm_recv_buf_t *rbuf, const char *channel, const mvod_pose2_t *msg,
		     void *user)
{
	struct received *got = user;
	if (got->n_poses2 < N_POSES)
		got->poses2[got->n_poses2] = *msg;
	got->n_poses2++;
}

static void on_status2(const lcm_recv_buf_t *rbuf, const char *channel,
		       const mvod_status2_t *msg, void *user)
{
	struct received *got = user;
	got->status2 = *msg;
	got->n_status2++;
}

static int setup(void **state)
{
	struct fixture *f = calloc(1, sizeof(*f));
	if (!f)
		return -1;
	f->lcm = lcm_create("memq://");
	if (!f->lcm) {
		free(f);
		return -1;
	}
	*state = f;
	return 0;
}

static int teardown(void **state)
{
	struct fixture *f = *state;
	lcm_destroy(f->lcm);
	free(f);
	return 0;
}

/* Rotation by angle a about y: its quaternion is (cos a/2, 0, sin a/2, 0), sign chosen so w >= 0. */
static void rot_y(double a, double R[9], double q[4])
{
	const double c = cos(a), s = sin(a);
	const double M[9] = {c, 0, s, 0, 1, 0, -s, 0, c};
	memcpy(R, M, sizeof(M));
	double sign = cos(a / 2) < 0 ? -1.0 : 1.0;
	q[0] = sign * cos(a / 2);
	q[1] = 0.0;
	q[2] = sign * sin(a / 2);
	q[3] = 0.0;
}

/* Frame i: 30° about y plus 40° per frame (crossing w < 0 on the way), position (1,2,3) + i x. */
static void make_result(int i, struct mvod_vo_result *res, double q[4])
{
	memset(res, 0, sizeof(*res));
	rot_y((30.0 + 40.0 * i) * DEG, res->pose.R, q);
	res->pose.t[0] = 1.0 + i;
	res->pose.t[1] = 2.0;
	res->pose.t[2] = 3.0;
	res->state = (enum mvod_track_state)(i % 6);
	res->scale_source = (enum mvod_scale_source)(i % 8); /* all 8 of them */
	res->status = (enum mvod_frame_status)(i % 7);
	res->features = 1000 + i;
	res->matches = 500 + i;
	res->inliers = 200 + i;
	res->keyframe = i % 3 == 1;
	res->quality = 0.125 * (i % 9); /* exact in a float */
}

static int64_t utime_of(int i)
{
	return 1700000000000000LL + 33333LL * i;
}

static void assert_pose_equal(const mvod_pose_t *m, int i)
{
	struct mvod_vo_result res;
	double q[4];
	make_result(i, &res, q);
	assert_int_equal(m->utime, utime_of(i));
	assert_int_equal(m->frame, i);
	for (int k = 0; k < 3; k++)
		assert_true(m->position[k] == res.pose.t[k]);
	assert_true(m->orientation[0] >= 0.0);
	for (int k = 0; k < 4; k++)
		assert_float_equal(m->orientation[k], q[k], 1e-12);
	assert_int_equal(m->state, res.state);
	assert_int_equal(m->scale_source, res.scale_source);
	assert_int_equal(m->frame_status, res.status);
	assert_int_equal(m->features, res.features);
	assert_int_equal(m->matches, res.matches);
	assert_int_equal(m->inliers, res.inliers);
}

/* The v2 message of frame i: the v1 fields as its v1 twin (checked the same), then the new. */
static void assert_pose2_equal(const mvod_pose2_t *m2, int i)
{
	mvod_pose_t m = {.utime = m2->utime, .frame = m2->frame, .state = m2->state,
			 .scale_source = m2->scale_source, .frame_status = m2->frame_status,
			 .features = m2->features, .matches = m2->matches, .inliers = m2->inliers};
	memcpy(m.position, m2->position, sizeof(m.position));
	memcpy(m.orientation, m2->orientation, sizeof(m.orientation));
	assert_pose_equal(&m, i);
	assert_int_equal(m2->keyframe, i % 3 == 1);
	assert_true(m2->quality == 0.125f * (float)(i % 9));
}

/* Both pose messages on their default channels, counted into f->got. */
struct pose_subs {
	mvod_pose_t_subscription_t *v1;
	mvod_pose2_t_subscription_t *v2;
};

static struct pose_subs subscribe_poses(struct fixture *f)
{
	struct pose_subs s = {
		mvod_pose_t_subscribe(f->lcm, MVOD_DEFAULT_POSE_CHANNEL, on_pose, &f->got),
		mvod_pose2_t_subscribe(f->lcm, "MVOD_POSE2", on_pose2, &f->got),
	};
	assert_non_null(s.v1);
	assert_non_null(s.v2);
	return s;
}

static void unsubscribe_poses(struct fixture *f, struct pose_subs *s)
{
	mvod_pose_t_unsubscribe(f->lcm, s->v1);
	mvod_pose2_t_unsubscribe(f->lcm, s->v2);
}

static void publish_poses(struct mvod_ipc *ipc, int n)
{
	for (int i = 0; i < n; i++) {
		struct mvod_vo_result res;
		double q[4];
		make_result(i, &res, q);
		assert_int_equal(mvod_ipc_publish_pose(ipc, utime_of(i), i, &res), 0);
	}
}

static void test_pose_roundtrip(void **state)
{
	struct fixture *f = *state;
	struct mvod_ipc *ipc = NULL;
	assert_int_equal(mvod_ipc_create_on(f->lcm, NULL, NULL, &ipc), 0);
	struct pose_subs subs = subscribe_poses(f);

	publish_poses(ipc, N_POSES);
	for (int i = 0; i < 2 * N_POSES; i++)
		assert_true(lcm_handle_timeout(f->lcm, 1000) > 0);

	assert_int_equal(f->got.n_poses, N_POSES);
	assert_int_equal(f->got.n_poses2, N_POSES);
	for (int i = 0; i < N_POSES; i++) {
		assert_pose_equal(&f->got.poses[i], i);
		assert_pose2_equal(&f->got.poses2[i], i);
	}
	assert_int_equal(lcm_handle_timeout(f->lcm, 10), 0);

	unsubscribe_poses(f, &subs);
	mvod_ipc_destroy(ipc);
}

/*
 * The published orientation's axis order: a pose turned 90 deg about x, then one about y, then
 * one about z (each alone, and each the other way round) comes back from the wire as (w, x, y,
 * z) = (cos 45, sin 45 along that axis only), in the v1 message and the v2 one. A quaternion
 * with two of x, y, z swapped is another rotation (about another axis) that every reader would
 * take at its word; the rotations about y that test_pose_roundtrip publishes cannot tell x
 * from z. Each R is written out here, camera-to-world, rows first (R[3 * r + c]), so the
 * expected quaternion does not come from the code under test. 1e-12: Shepperd's method on
 * entries 0, 1 and -1 rounds to a few ulps (the sine and cosine of 45 deg themselves).
 */
static void test_pose_axis_order(void **state)
{
	struct fixture *f = *state;
	static const struct {
		double R[9];
		int axis;  /* 1: x, 2: y, 3: z (the quaternion's index) */
		double s;  /* the sign of the turn */
	} turns[] = {
		{{1, 0, 0, 0, 0, -1, 0, 1, 0}, 1, 1},  /* +90 about x: y -> z */
		{{0, 0, 1, 0, 1, 0, -1, 0, 0}, 2, 1},  /* +90 about y: z -> x */
		{{0, -1, 0, 1, 0, 0, 0, 0, 1}, 3, 1},  /* +90 about z: x -> y */
		{{1, 0, 0, 0, 0, 1, 0, -1, 0}, 1, -1}, /* -90 about x */
		{{0, 0, -1, 0, 1, 0, 1, 0, 0}, 2, -1}, /* -90 about y */
		{{0, 1, 0, -1, 0, 0, 0, 0, 1}, 3, -1}, /* -90 about z */
	};
	enum { TURNS = sizeof(turns) / sizeof(turns[0]) };
	struct mvod_ipc *ipc = NULL;
	assert_int_equal(mvod_ipc_create_on(f->lcm, NULL, NULL, &ipc), 0);
	struct pose_subs subs = subscribe_poses(f);
	for (int i = 0; i < TURNS; i++) {
		struct mvod_vo_result res = {.state = MVOD_STATE_TRACKING};
		memcpy(res.pose.R, turns[i].R, sizeof(res.pose.R));
		assert_int_equal(mvod_ipc_publish_pose(ipc, utime_of(i), i, &res), 0);
	}
	for (int i = 0; i < 2 * TURNS; i++)
		assert_true(lcm_handle_timeout(f->lcm, 1000) > 0);
	assert_int_equal(f->got.n_poses, TURNS);
	assert_int_equal(f->got.n_poses2, TURNS);
	for (int i = 0; i < TURNS; i++) {
		double want[4] = {M_SQRT1_2, 0, 0, 0};
		want[turns[i].axis] = turns[i].s * M_SQRT1_2;
		for (int k = 0; k < 4; k++) {
			assert_float_equal(f->got.poses[i].orientation[k], want[k], 1e-12);
			assert_float_equal(f->got.poses2[i].orientation[k], want[k], 1e-12);
		}
	}
	unsubscribe_poses(f, &subs);
	mvod_ipc_destroy(ipc);
}

static void test_status_roundtrip(void **state)
{
	struct fixture *f = *state;
	struct mvod_ipc *ipc = NULL;
	const struct mvod_status st = {
		.utime = 1234567890123LL,
		.fps = 29.5,
		.stage_ms = {1.5, 2.25, 3.125, 4.0625, 5.5},
		.features = 1800, .matches = 900, .inliers = 450,
		.frames = 123456789012LL, .dropped = 42, .rss_kb = 65536,
		.uptime_s = 3600.125,
		.state = MVOD_RUN_LOST,
		.faults = MVOD_STATUS_T_FAULT_TRAJECTORY_WRITE | MVOD_STATUS_T_FAULT_PUBLISH,
		.map_points = 4321, .keyframes = 17, .scale = 0.0625, .scale_confidence = 0.75,
		.latency_ms = 12.5,
	};
	assert_int_equal(mvod_ipc_create_on(f->lcm, NULL, NULL, &ipc), 0);
	mvod_status_t_subscription_t *sub =
		mvod_status_t_subscribe(f->lcm, MVOD_DEFAULT_STATUS_CHANNEL, on_status, &f->got);
	mvod_status2_t_subscription_t *sub2 =
		mvod_status2_t_subscribe(f->lcm, "MVOD_STATUS2", on_status2, &f->got);
	assert_non_null(sub);
	assert_non_null(sub2);

	assert_int_equal(mvod_ipc_publish_status(ipc, &st), 0);
	assert_true(lcm_handle_timeout(f->lcm, 1000) > 0);
	assert_true(lcm_handle_timeout(f->lcm, 1000) > 0);

	/* v2: the new fields, and the old ones read back through the one conversion. */
	const mvod_status2_t *m2 = &f->got.status2;
	assert_int_equal(f->got.n_status2, 1);
	assert_int_equal(m2->map_points, 4321);
	assert_int_equal(m2->keyframes, 17);
	assert_true(m2->scale == 0.0625);
	assert_true(m2->scale_confidence == 0.75f);
	assert_true(m2->latency_ms == 12.5f);
	struct mvod_status back;
	mvod_status_from_msg(m2, &back);
	assert_int_equal(back.frames, st.frames);
	assert_int_equal(back.faults, st.faults);
	assert_int_equal(back.state, st.state);
	assert_true(back.latency_ms == 12.5 && back.scale == 0.0625 && back.map_points == 4321);
	mvod_status2_t_unsubscribe(f->lcm, sub2);

	const mvod_status_t *m = &f->got.status;
	assert_int_equal(f->got.n_status, 1);
	assert_int_equal(m->utime, st.utime);
	assert_int_equal(m->state, MVOD_POSE_T_STATE_LOST);
	assert_true(m->fps == 29.5f);
	assert_true(m->capture_ms == 1.5f);
	assert_true(m->preprocess_ms == 2.25f);
	assert_true(m->detect_ms == 3.125f);
	assert_true(m->match_ms == 4.0625f);
	assert_true(m->pose_ms == 5.5f);
	assert_int_equal(m->features, 1800);
	assert_int_equal(m->matches, 900);
	assert_int_equal(m->inliers, 450);
	assert_int_equal(m->frames, st.frames);
	assert_int_equal(m->dropped_frames, 42);
	assert_int_equal(m->rss_kb, 65536);
	assert_true(m->uptime_s == 3600.125);
	assert_int_equal(m->faults, st.faults);

	mvod_status_t_unsubscribe(f->lcm, sub);
	mvod_ipc_destroy(ipc);
}

static void count_pose(const lcm_recv_buf_t *rbuf, const char *channel, const mvod_pose_t *msg,
		       void *user)
{
	(*(int *)user)++;
}

static void count_status(const lcm_recv_buf_t *rbuf, const char *channel,
			 const mvod_status_t *msg, void *user)
{
	(*(int *)user)++;
}

static void test_custom_channels(void **state)
{
	struct fixture *f = *state;
	struct mvod_ipc *ipc = NULL;
	int def_pose = 0, def_status = 0, cam_pose = 0, cam_status = 0;
	assert_int_equal(mvod_ipc_create_on(f->lcm, "CAM0_POSE", "CAM0_STATUS", &ipc), 0);
	mvod_pose_t_subscription_t *pose_subs[] = {
		mvod_pose_t_subscribe(f->lcm, MVOD_DEFAULT_POSE_CHANNEL, count_pose, &def_pose),
		mvod_pose_t_subscribe(f->lcm, "CAM0_POSE", count_pose, &cam_pose),
	};
	mvod_status_t_subscription_t *status_subs[] = {
		mvod_status_t_subscribe(f->lcm, MVOD_DEFAULT_STATUS_CHANNEL, count_status,
					&def_status),
		mvod_status_t_subscribe(f->lcm, "CAM0_STATUS", count_status, &cam_status),
	};

	struct mvod_vo_result res;
	double q[4];
	const struct mvod_status st = {.state = MVOD_RUN_TRACKING};
	make_result(0, &res, q);
	assert_int_equal(mvod_ipc_publish_pose(ipc, utime_of(0), 0, &res), 0);
	assert_int_equal(mvod_ipc_publish_status(ipc, &st), 0);
	/* memq:// drops messages nobody subscribed to: the v2 ones here. */
	assert_true(lcm_handle_timeout(f->lcm, 1000) > 0);
	assert_true(lcm_handle_timeout(f->lcm, 1000) > 0);
	assert_int_equal(lcm_handle_timeout(f->lcm, 10), 0);

	assert_int_equal(cam_pose, 1);
	assert_int_equal(cam_status, 1);
	assert_int_equal(def_pose, 0);
	assert_int_equal(def_status, 0);
	for (int i = 0; i < 2; i++) {
		mvod_pose_t_unsubscribe(f->lcm, pose_subs[i]);
		mvod_status_t_unsubscribe(f->lcm, status_subs[i]);
	}
	mvod_ipc_destroy(ipc);
}

static void test_bad_channels(void **state)
{
	struct fixture *f = *state;
	struct mvod_ipc *ipc = NULL;
	char longname[LCM_MAX_CHANNEL_NAME_LENGTH + 2];
	memset(longname, 'A', sizeof(longname) - 1);
	longname[sizeof(longname) - 1] = '\0';

	assert_int_equal(mvod_ipc_create_on(f->lcm, "", NULL, &ipc), -EINVAL);
	assert_int_equal(mvod_ipc_create_on(f->lcm, NULL, longname, &ipc), -EINVAL);
	assert_int_equal(mvod_ipc_create_on(NULL, NULL, NULL, &ipc), -EINVAL);
	assert_null(ipc);
	/* LCM's longest name is refused too: its v2 channel would be one longer. */
	longname[LCM_MAX_CHANNEL_NAME_LENGTH] = '\0';
	assert_int_equal(mvod_ipc_create_on(f->lcm, longname, NULL, &ipc), -EINVAL);
	longname[MVOD_MAX_CHANNEL_LENGTH] = '\0';
	assert_int_equal(mvod_ipc_create_on(f->lcm, longname, NULL, &ipc), 0);
	mvod_ipc_destroy(ipc);
	mvod_ipc_destroy(NULL);
}

static void test_bad_url(void **state)
{
	struct mvod_ipc *ipc = NULL;
	int ret = mvod_ipc_create("nonsense://x", NULL, NULL, &ipc);
	assert_true(ret < 0);
	assert_null(ipc);
}

struct tmplog {
	char dir[64], path[96], url[128];
};

static void tmplog_init(struct tmplog *t)
{
	strcpy(t->dir, "/tmp/mvod-test-ipc-XXXXXX");
	assert_non_null(mkdtemp(t->dir));
	snprintf(t->path, sizeof(t->path), "%s/poses.lcm", t->dir);
	snprintf(t->url, sizeof(t->url), "file://%s?mode=w", t->path);
}

static void tmplog_fini(const struct tmplog *t)
{
	unlink(t->path);
	rmdir(t->dir);
}

static void test_file_log(void **state)
{
	struct tmplog t;
	struct mvod_ipc *ipc = NULL;
	mvod_pose_t poses[8];
	tmplog_init(&t);

	assert_int_equal(mvod_ipc_create(t.url, NULL, NULL, &ipc), 0);
	assert_int_equal(mvod_ipc_open_log(ipc, NULL, 0), 0);
	publish_poses(ipc, 5);
	assert_int_equal(mvod_ipc_finish(ipc), 0);
	mvod_ipc_destroy(ipc);

	assert_int_equal(harness_poses(t.path, poses, 8), 5);
	assert_pose_equal(&poses[2], 2);
	tmplog_fini(&t);
}

/* An LCM log in t of the n samples on MVOD_SPEED, opened as --speed-url file://. */
static struct mvod_speed *speed_from(struct tmplog *t, const mvod_speed_t *samples, int n)
{
	tmplog_init(t);
	struct mvod_lcm_log *log;
	assert_int_equal(mvod_lcm_log_open("speed log", t->path, 256, &log, NULL, 0), 0);
	for (int i = 0; i < n; i++) {
		uint8_t buf[64];
		int len = mvod_speed_t_encode(buf, 0, sizeof(buf), &samples[i]);
		assert_true(len > 0);
		assert_int_equal(mvod_lcm_log_write(log, "MVOD_SPEED", buf, (size_t)len), 0);
	}
	assert_int_equal(mvod_lcm_log_close(log), 0);
	char url[160];
	snprintf(url, sizeof(url), "file://%s?mode=r", t->path);
	struct mvod_speed *s;
	assert_int_equal(mvod_speed_create(url, NULL, &s, NULL, 0), 0);
	return s;
}

/*
 * --speed-url file://: the odometer between two samples is interpolated, beyond the last one
 * extrapolated at its speed for up to MVOD_SPEED_STALE_US, and in a gap longer than that on
 * both sides there is none. Exact: distances and times are binary fractions.
 */
static void test_speed_log(void **state)
{
	(void)state;
	struct tmplog t;
	/* 1 m/s: 1 m at 1 s, then nothing for 2 s, then 3.5 m at 3 s. */
	static const mvod_speed_t samples[] = {{0, 1.0, 1, 0.0}, {1000000, 1.0, 1, 1.0},
					       {3000000, 1.0, 1, 3.5}};
	struct mvod_speed *s = speed_from(&t, samples, 3);
	double m = -1;
	assert_int_equal(mvod_speed_odometer(s, 250000, &m), 0);
	assert_true(m == 0.25);
	/* Between 1 s and 3 s, 0.25 s from one of them: 1 + 2.5 m * 0.25 / 2. */
	assert_int_equal(mvod_speed_odometer(s, 1250000, &m), 0);
	assert_true(m == 1.3125);
	assert_int_equal(mvod_speed_odometer(s, 2000000, &m), -EAGAIN); /* 1 s from both */
	assert_int_equal(mvod_speed_odometer(s, 2750000, &m), 0);
	assert_true(m == 3.1875);
	assert_int_equal(mvod_speed_odometer(s, 3250000, &m), 0);
	assert_true(m == 3.75);
	assert_int_equal(mvod_speed_odometer(s, 3750000, &m), -EAGAIN);
	mvod_speed_destroy(s);
	tmplog_fini(&t);
}

/*
 * Times at int64's ends are refused as times (they were differenced and overflowed: UBSan);
 * so is a negative one; a frame's time there finds no sample.
 */
static void test_speed_extreme_times(void **state)
{
	(void)state;
	struct tmplog t;
	static const mvod_speed_t samples[] = {{-INT64_MAX, 1.0, 0, 0.0}, {-1, 1.0, 0, 0.0},
					       {INT64_MAX, 1.0, 0, 0.0}, {1000000, 1.0, 0, 0.0}};
	struct mvod_speed *s = speed_from(&t, samples, 4);
	double m = -1;
	assert_int_equal(mvod_speed_odometer(s, INT64_MIN, &m), -EAGAIN);
	assert_int_equal(mvod_speed_odometer(s, INT64_MAX, &m), -EAGAIN);
	struct mvod_speed_counts c;
	mvod_speed_counts(s, &c);
	assert_int_equal(c.bad_time, 3);
	assert_int_equal(c.accepted, 1);
	assert_int_equal(mvod_speed_odometer(s, 1250000, &m), 0);
	assert_true(m == 0.25); /* the one sample at its speed */
	mvod_speed_destroy(s);
	tmplog_fini(&t);
}

/* A NULL url goes to LCM_DEFAULT_URL; pointed at a log file, nothing touches the network. */
static void test_default_url_from_env(void **state)
{
	struct tmplog t;
	struct mvod_ipc *ipc = NULL;
	const char *saved = getenv("LCM_DEFAULT_URL");
	char *restore = saved ? strdup(saved) : NULL;
	tmplog_init(&t);

	assert_int_equal(setenv("LCM_DEFAULT_URL", t.url, 1), 0);
	int ret = mvod_ipc_create(NULL, NULL, NULL, &ipc);
	if (restore)
		setenv("LCM_DEFAULT_URL", restore, 1);
	else
		unsetenv("LCM_DEFAULT_URL");
	free(restore);
	assert_int_equal(ret, 0);
	assert_int_equal(mvod_ipc_open_log(ipc, NULL, 0), 0);
	publish_poses(ipc, 3);
	mvod_ipc_destroy(ipc);

	assert_int_equal(harness_poses(t.path, NULL, 0), 3);
	tmplog_fini(&t);
}

/* The log is opened by mvod_ipc_open_log, never by create: a failed start leaves it alone. */
static void test_file_log_opened_late(void **state)
{
	struct tmplog t;
	struct mvod_ipc *ipc = NULL;
	struct mvod_vo_result res;
	double q[4];
	tmplog_init(&t);
	harness_write_file(t.path, "the log of the run before");

	assert_int_equal(mvod_ipc_create(t.url, NULL, NULL, &ipc), 0);
	make_result(0, &res, q);
	assert_int_equal(mvod_ipc_publish_pose(ipc, 1, 0, &res), -EBADF);
	assert_int_equal(mvod_ipc_open_log(ipc, NULL, 0), 0);
	assert_string_equal(mvod_ipc_log_path(ipc), t.path);
	mvod_ipc_destroy(ipc);
	char text[64];
	harness_read_file(t.path, text, sizeof(text));
	assert_string_equal(text, "the log of the run before");
	tmplog_fini(&t);
}

/* A log on a device that refuses every write: the error comes back, and again at the end. */
static void test_file_log_write_error(void **state)
{
	struct mvod_ipc *ipc = NULL;
	struct mvod_vo_result res;
	double q[4];
	char err[256] = "";
	make_result(0, &res, q);
	assert_int_equal(mvod_ipc_create("file:///dev/full?mode=w", NULL, NULL, &ipc), 0);
	assert_int_equal(mvod_ipc_open_log(ipc, err, sizeof(err)), 0);
	assert_int_equal(mvod_ipc_publish_pose(ipc, 1, 0, &res), -ENOSPC);
	assert_int_equal(mvod_ipc_publish_pose(ipc, 2, 1, &res), -ENOSPC);
	assert_int_equal(mvod_ipc_finish(ipc), -ENOSPC);
	mvod_ipc_destroy(ipc);
}

struct sent {
	int calls, ret;
	char channel[64];
	char order[128]; /* the channels, in order, each followed by a space */
};

static int fake_send(void *ctx, const char *channel, const void *buf, size_t len)
{
	struct sent *s = ctx;
	s->calls++;
	snprintf(s->channel, sizeof(s->channel), "%s", channel);
	size_t n = strlen(s->order);
	snprintf(s->order + n, sizeof(s->order) - n, "%s ", channel);
	return len > 0 ? s->ret : -EINVAL;
}

/* The publish seam: every message goes through it, and its failure is the publish's. */
static void test_send_seam(void **state)
{
	struct sent s = {.ret = -EIO};
	struct mvod_ipc *ipc = NULL;
	struct mvod_vo_result res;
	struct mvod_status st = {.faults = 1};
	double q[4];
	make_result(0, &res, q);
	assert_int_equal(mvod_ipc_create_with(fake_send, &s, "P", "S", &ipc), 0);
	assert_int_equal(mvod_ipc_publish_pose(ipc, 1, 0, &res), -EIO);
	assert_string_equal(s.channel, "P");
	s.ret = 0;
	assert_int_equal(mvod_ipc_publish_status(ipc, &st), 0);
	assert_string_equal(s.channel, "S");
	/* Each publish sends v2, then v1 (mvod view takes v1 only until a v2 came). */
	assert_int_equal(s.calls, 4);
	assert_string_equal(s.order, "P2 P S2 S ");
	assert_int_equal(mvod_ipc_finish(ipc), 0);
	mvod_ipc_destroy(ipc);
}

/*
 * Log URLs: file:// with its path and LCM's mode (mvod writes mode=w itself, reads r), nothing
 * else; an empty path or one too long for the buffer refused.
 */
static void test_log_urls(void **state)
{
	(void)state;
	static const struct {
		const char *url, *path;
		char mode;
		int ret;
	} cases[] = {
		{"file:///tmp/a.lcm?mode=w", "/tmp/a.lcm", 'w', 0},
		{"file:///tmp/a.lcm?speed=1&mode=w", "/tmp/a.lcm", 'w', 0},
		{"file://rel/a.lcm?mode=w&speed=1", "rel/a.lcm", 'w', 0},
		{"file:///tmp/a.lcm", "/tmp/a.lcm", 'r', 0}, /* LCM's default mode is r: playback */
		{"file:///tmp/a.lcm?mode=r&speed=0", "/tmp/a.lcm", 'r', 0},
		{"file:///tmp/a.lcm?mode=a", "/tmp/a.lcm", 'a', 0},
		{"file:///tmp/a.lcm?mode=wx", "/tmp/a.lcm", '?', 0},
		{"file:///tmp/a.lcm?mode=", "/tmp/a.lcm", '?', 0},
		{"file://?mode=w", "unchanged", 'w', -EINVAL},
		{"file:///a/path/longer/than/the/buffer/of/sixty/four/bytes/given/here.lcmlog",
		 "unchanged", 'r', -ENAMETOOLONG},
		{"memq://", "unchanged", 'x', -ENOENT},
		{"tcpq://127.0.0.1:7700", "unchanged", 'x', -ENOENT}, /* parsed only */
		{NULL, "unchanged", 'x', -ENOENT},
	};
	for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
		char path[64] = "unchanged", mode = 'x';
		int ret = mvod_lcm_file_url(cases[i].url, path, sizeof(path), &mode);
		assert_int_equal(ret, cases[i].ret);
		assert_int_equal(mode, cases[i].mode);
		if (ret != -ENAMETOOLONG)
			assert_string_equal(path, cases[i].path);
	}
}

/* A v1 message (an old log) as v2: every field kept, the new ones 0. */
static void test_upgrade(void **state)
{
	(void)state;
	mvod_pose_t p = {.utime = 7, .frame = 3, .position = {1, 2, 3},
			 .orientation = {0.5, 0.5, 0.5, 0.5}, .state = 2, .scale_source = 4,
			 .frame_status = 6, .features = 9, .matches = 8, .inliers = 7};
	mvod_pose2_t p2;
	memset(&p2, 0x55, sizeof(p2));
	mvod_pose_msg_upgrade(&p, &p2);
	assert_int_equal(p2.utime, 7);
	assert_int_equal(p2.frame, 3);
	assert_true(p2.position[2] == 3 && p2.orientation[3] == 0.5);
	assert_int_equal(p2.state, 2);
	assert_int_equal(p2.frame_status, 6);
	assert_int_equal(p2.inliers, 7);
	assert_int_equal(p2.keyframe, 0);
	assert_true(p2.quality == 0);

	mvod_status_t st = {.utime = 5, .frames = 11, .faults = 8, .state = 3};
	mvod_status2_t st2;
	memset(&st2, 0x55, sizeof(st2));
	mvod_status_msg_upgrade(&st, &st2);
	assert_int_equal(st2.utime, 5);
	assert_int_equal(st2.frames, 11);
	assert_int_equal(st2.faults, 8);
	assert_int_equal(st2.state, 3);
	assert_int_equal(st2.map_points, 0);
	assert_true(st2.scale == 0 && st2.latency_ms == 0);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test_setup_teardown(test_pose_roundtrip, setup, teardown),
		cmocka_unit_test_setup_teardown(test_pose_axis_order, setup, teardown),
		cmocka_unit_test_setup_teardown(test_status_roundtrip, setup, teardown),
		cmocka_unit_test_setup_teardown(test_custom_channels, setup, teardown),
		cmocka_unit_test_setup_teardown(test_bad_channels, setup, teardown),
		cmocka_unit_test(test_bad_url),
		cmocka_unit_test(test_file_log),
		cmocka_unit_test(test_default_url_from_env),
		cmocka_unit_test(test_file_log_opened_late),
		cmocka_unit_test(test_file_log_write_error),
		cmocka_unit_test(test_send_seam),
		cmocka_unit_test(test_log_urls),
		cmocka_unit_test(test_speed_log),
		cmocka_unit_test(test_speed_extreme_times),
		cmocka_unit_test(test_upgrade),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
