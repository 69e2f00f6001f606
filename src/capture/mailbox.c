#include "capture/mailbox.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

void mvod_cond_init_monotonic(pthread_cond_t *cond)
{
	/* Waits are measured on the clock that does not jump with the wall clock. */
	pthread_condattr_t attr;
	pthread_condattr_init(&attr);
	pthread_condattr_setclock(&attr, CLOCK_MONOTONIC);
	pthread_cond_init(cond, &attr);
	pthread_condattr_destroy(&attr);
}

int mvod_letters_alloc(struct mvod_letter *letters, int n, size_t bytes)
{
	for (int i = 0; i < n; i++) {
		letters[i].frame.img.data = malloc(bytes);
		if (!letters[i].frame.img.data) {
			mvod_letters_free(letters, n);
			return -ENOMEM;
		}
	}
	return 0;
}

void mvod_letters_free(struct mvod_letter *letters, int n)
{
	for (int i = 0; i < n; i++) {
		free(letters[i].frame.img.data);
		letters[i].frame.img.data = NULL;
	}
}

int mvod_mailbox_init(struct mvod_mailbox *mb, size_t bytes)
{
	memset(mb, 0, sizeof(*mb));
	int ret = mvod_letters_alloc(mb->letters, 3, bytes);
	if (ret)
		return ret;
	mvod_cond_init_monotonic(&mb->posted);
	pthread_mutex_init(&mb->lock, NULL);
	mb->back = &mb->letters[0];
	mb->slot = &mb->letters[1];
	mb->front = &mb->letters[2];
	return 0;
}

void mvod_mailbox_fini(struct mvod_mailbox *mb)
{
	mvod_letters_free(mb->letters, 3);
	if (mb->back) {
		pthread_cond_destroy(&mb->posted);
		pthread_mutex_destroy(&mb->lock);
	}
	memset(mb, 0, sizeof(*mb));
}

struct mvod_letter *mvod_mailbox_back(struct mvod_mailbox *mb)
{
	return mb->back;
}

void mvod_mailbox_post(struct mvod_mailbox *mb)
{
	pthread_mutex_lock(&mb->lock);
	struct mvod_letter *l = mb->slot;
	mb->slot = mb->back;
	mb->back = l;
	mb->dropped += mb->fresh;
	mb->fresh = true;
	pthread_cond_signal(&mb->posted);
	pthread_mutex_unlock(&mb->lock);
}

void mvod_mailbox_close(struct mvod_mailbox *mb, int reason)
{
	pthread_mutex_lock(&mb->lock);
	mb->closed = reason;
	pthread_cond_signal(&mb->posted);
	pthread_mutex_unlock(&mb->lock);
}

struct timespec mvod_mailbox_deadline(int timeout_ms)
{
	struct timespec t;
	clock_gettime(CLOCK_MONOTONIC, &t);
	t.tv_sec += timeout_ms / 1000;
	t.tv_nsec += (long)(timeout_ms % 1000) * 1000000L;
	if (t.tv_nsec >= 1000000000L) {
		t.tv_sec++;
		t.tv_nsec -= 1000000000L;
	}
	return t;
}

int mvod_mailbox_take(struct mvod_mailbox *mb, int timeout_ms, struct mvod_letter **out)
{
	struct timespec until = mvod_mailbox_deadline(timeout_ms);
	pthread_mutex_lock(&mb->lock);
	int waited = 0;
	while (!mb->fresh && !mb->closed && waited != ETIMEDOUT)
		waited = pthread_cond_timedwait(&mb->posted, &mb->lock, &until);
	int ret = mb->fresh ? 0 : mb->closed ? mb->closed : -EAGAIN;
	if (mb->fresh) {
		struct mvod_letter *l = mb->front;
		mb->front = mb->slot;
		mb->slot = l;
		mb->fresh = false;
		*out = mb->front;
	}
	pthread_mutex_unlock(&mb->lock);
	return ret;
}

int64_t mvod_mailbox_dropped(struct mvod_mailbox *mb)
{
	pthread_mutex_lock(&mb->lock);
	int64_t n = mb->dropped;
	pthread_mutex_unlock(&mb->lock);
	return n;
}
