#include "ba_thread.h"

#include "ba_lm.h"

#include <errno.h>
#include <pthread.h>
#include <stdlib.h>

/* Who holds the job: the frame thread (FREE, DONE) or the BA thread (POSTED). */
enum job_state { JOB_FREE, JOB_POSTED, JOB_DONE };

struct mvod_ba_thread {
	struct mvod_ba_lm *lm; /* used by the BA thread only */
	struct mvod_ba_job job;
	pthread_t thread;
	pthread_mutex_t lock;
	pthread_cond_t changed; /* the state or stop changed */
	enum job_state state;
	bool stop;
	bool started;
};

static void *run(void *arg)
{
	struct mvod_ba_thread *t = arg;
	pthread_mutex_lock(&t->lock);
	for (;;) {
		while (t->state != JOB_POSTED && !t->stop)
			pthread_cond_wait(&t->changed, &t->lock);
		if (t->state != JOB_POSTED)
			break;
		pthread_mutex_unlock(&t->lock);
		struct mvod_ba_job *j = &t->job;
		/*
		 * ba_lm.c's Levenberg-Marquardt, not Ceres: the same steps (unit/ba compares them;
		 * the KITTI clip table unchanged, every map trajectory within 1e-7 m of Ceres's but
		 * 07 orb auto's, 2e-5 m; KITTI 00's free-scale t_rel Ceres's 4.20 / 3.01 / 4.68 %)
		 * for about a third of the instructions: KITTI 06 (callgrind, --scale gt) 92.3e6 ->
		 * 85.1e6 a frame. Ceres is now the tests' reference only (BENCHMARKS.md).
		 */
		j->ret = mvod_ba_lm_solve(t->lm, &j->p, &j->o, &j->r);
		pthread_mutex_lock(&t->lock);
		t->state = JOB_DONE;
		pthread_cond_broadcast(&t->changed);
	}
	pthread_mutex_unlock(&t->lock);
	return NULL;
}

static int alloc_job(struct mvod_ba_job *j, int kf_cap, int point_cap)
{
	size_t nk = (size_t)kf_cap, np = (size_t)point_cap;
	j->poses = calloc(nk * 6, sizeof(double));
	j->points = calloc(np * 3, sizeof(double));
	j->fixed = calloc(nk, 1);
	j->obs = calloc(np * nk, sizeof(*j->obs));
	j->outlier = calloc(np * nk, 1);
	j->kf = calloc(nk, sizeof(*j->kf));
	j->pt = calloc(np, sizeof(*j->pt));
	j->obs_kf = calloc(np * nk, sizeof(*j->obs_kf));
	return j->poses && j->points && j->fixed && j->obs && j->outlier && j->kf && j->pt &&
			       j->obs_kf
		       ? 0
		       : -ENOMEM;
}

int mvod_ba_thread_create(int kf_cap, int point_cap, struct mvod_ba_thread **out)
{
	*out = NULL;
	struct mvod_ba_thread *t = calloc(1, sizeof(*t));
	if (!t)
		return -ENOMEM;
	pthread_mutex_init(&t->lock, NULL);
	pthread_cond_init(&t->changed, NULL);
	int ret = alloc_job(&t->job, kf_cap, point_cap);
	if (!ret)
		ret = mvod_ba_lm_create(kf_cap, point_cap, kf_cap * point_cap, &t->lm);
	if (!ret)
		ret = -pthread_create(&t->thread, NULL, run, t);
	t->started = !ret;
	if (ret) {
		mvod_ba_thread_destroy(t);
		return ret;
	}
	/* Named so that tools (and tests/integration/test_alloc.c) can tell its work apart. */
	pthread_setname_np(t->thread, "mvod-ba");
	*out = t;
	return 0;
}

/* Tells the BA thread: a job is posted (post) or it is to end (stop, after any job). */
static void tell(struct mvod_ba_thread *t, bool post, bool stop)
{
	pthread_mutex_lock(&t->lock);
	if (post)
		t->state = JOB_POSTED;
	t->stop = stop;
	pthread_cond_broadcast(&t->changed);
	pthread_mutex_unlock(&t->lock);
}

void mvod_ba_thread_destroy(struct mvod_ba_thread *t)
{
	if (!t)
		return;
	if (t->started) {
		tell(t, false, true);
		pthread_join(t->thread, NULL);
	}
	pthread_cond_destroy(&t->changed);
	pthread_mutex_destroy(&t->lock);
	mvod_ba_lm_destroy(t->lm);
	struct mvod_ba_job *j = &t->job;
	void *arrays[] = {j->poses, j->points, j->fixed, j->obs, j->outlier, j->kf, j->pt,
			  j->obs_kf};
	for (size_t i = 0; i < sizeof(arrays) / sizeof(arrays[0]); i++)
		free(arrays[i]);
	free(t);
}

struct mvod_ba_job *mvod_ba_thread_job(struct mvod_ba_thread *t)
{
	pthread_mutex_lock(&t->lock);
	bool free_ = t->state == JOB_FREE;
	pthread_mutex_unlock(&t->lock);
	return free_ ? &t->job : NULL;
}

void mvod_ba_thread_post(struct mvod_ba_thread *t)
{
	tell(t, true, false);
}

bool mvod_ba_thread_take(struct mvod_ba_thread *t, bool wait, struct mvod_ba_job **out)
{
	pthread_mutex_lock(&t->lock);
	while (wait && t->state == JOB_POSTED)
		pthread_cond_wait(&t->changed, &t->lock);
	bool done = t->state == JOB_DONE;
	if (done)
		t->state = JOB_FREE;
	pthread_mutex_unlock(&t->lock);
	*out = done ? &t->job : NULL;
	return done;
}
