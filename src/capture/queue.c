#include "capture/queue.h"

#include <errno.h>
#include <string.h>
#include <time.h>

int mvod_queue_init(struct mvod_queue *q, size_t bytes)
{
	memset(q, 0, sizeof(*q));
	int ret = mvod_letters_alloc(q->letters, MVOD_QUEUE_DEPTH, bytes);
	if (ret)
		return ret;
	mvod_cond_init_monotonic(&q->changed);
	pthread_mutex_init(&q->lock, NULL);
	q->made = true;
	return 0;
}

void mvod_queue_fini(struct mvod_queue *q)
{
	mvod_letters_free(q->letters, MVOD_QUEUE_DEPTH);
	if (q->made) {
		pthread_cond_destroy(&q->changed);
		pthread_mutex_destroy(&q->lock);
	}
	memset(q, 0, sizeof(*q));
}

struct mvod_letter *mvod_queue_back(struct mvod_queue *q)
{
	pthread_mutex_lock(&q->lock);
	while (!q->cancelled && q->posted + q->held >= MVOD_QUEUE_DEPTH)
		pthread_cond_wait(&q->changed, &q->lock);
	/* The ring holds, in order: the consumer's letter, the posted ones, then the free ones. */
	struct mvod_letter *l =
		q->cancelled ? NULL : &q->letters[(q->head + q->posted) % MVOD_QUEUE_DEPTH];
	pthread_mutex_unlock(&q->lock);
	return l;
}

void mvod_queue_post(struct mvod_queue *q)
{
	pthread_mutex_lock(&q->lock);
	q->posted++;
	pthread_cond_broadcast(&q->changed);
	pthread_mutex_unlock(&q->lock);
}

void mvod_queue_close(struct mvod_queue *q, int reason)
{
	pthread_mutex_lock(&q->lock);
	q->closed = reason;
	pthread_cond_broadcast(&q->changed);
	pthread_mutex_unlock(&q->lock);
}

void mvod_queue_cancel(struct mvod_queue *q)
{
	pthread_mutex_lock(&q->lock);
	q->cancelled = true;
	pthread_cond_broadcast(&q->changed);
	pthread_mutex_unlock(&q->lock);
}

int mvod_queue_take(struct mvod_queue *q, int timeout_ms, struct mvod_letter **out)
{
	struct timespec until = mvod_mailbox_deadline(timeout_ms);
	pthread_mutex_lock(&q->lock);
	if (q->held) { /* the consumer is done with it: the producer may fill it */
		q->held = false;
		pthread_cond_broadcast(&q->changed);
	}
	int waited = 0;
	while (!q->posted && !q->closed && waited != ETIMEDOUT)
		waited = pthread_cond_timedwait(&q->changed, &q->lock, &until);
	int ret = q->posted ? 0 : q->closed ? q->closed : -EAGAIN;
	if (q->posted) {
		*out = &q->letters[q->head];
		q->head = (q->head + 1) % MVOD_QUEUE_DEPTH;
		q->posted--;
		q->held = true;
	}
	pthread_mutex_unlock(&q->lock);
	return ret;
}
