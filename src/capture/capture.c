/*
 * The capture thread: a live source is read into the mailbox (the newest frame wins) and
 * reopened when it goes down; any other source into the queue (every frame, in order), so
 * that decoding overlaps processing. Cameras convert their buffers straight into the free
 * letter; sources that decode into buffers of their own (files, images) are copied there once.
 */
#include "mvod/capture.h"

#include <errno.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "capture/mailbox.h"
#include "capture/queue.h"
#include "mvod/log.h"
#include "util/errbuf.h"

#define BACKOFF_FIRST_MS 500
#define BACKOFF_MAX_MS 8000

struct mvod_capture {
	struct mvod_source *src;      /* NULL while down; the capture thread's alone once started */
	char *uri;
	struct mvod_source_info info; /* of the first open: a reopened source must match it */
	bool lossless;                /* not live: every frame goes through q, none through mb */
	struct mvod_mailbox mb;
	struct mvod_queue q;
	pthread_t thread;
	pthread_mutex_t lock;         /* guards stop; wake interrupts the backoff */
	pthread_cond_t wake;
	bool stop;
	atomic_bool down;
	int epoch;                    /* times the source came back */
	int backoff_ms;
	int64_t base;                 /* added to the source's indices: a reopened one starts at 0 */
	int64_t last;                 /* index of the last frame posted */
	/* Live: frames that could not be decoded, by reason (the capture thread's alone). */
	int64_t bad[MVOD_BAD_COUNT];
};

static bool stopping(struct mvod_capture *c)
{
	pthread_mutex_lock(&c->lock);
	bool s = c->stop;
	pthread_mutex_unlock(&c->lock);
	return s;
}

/* Sleeps ms, or less when stopped; true when stopped. */
static bool sleep_unless_stopped(struct mvod_capture *c, int ms)
{
	struct timespec until = mvod_mailbox_deadline(ms);
	pthread_mutex_lock(&c->lock);
	while (!c->stop && pthread_cond_timedwait(&c->wake, &c->lock, &until) != ETIMEDOUT)
		;
	bool s = c->stop;
	pthread_mutex_unlock(&c->lock);
	return s;
}

/* The letter to fill next: NULL when the consumer is stopping. */
static struct mvod_letter *back(struct mvod_capture *c)
{
	return c->lossless ? mvod_queue_back(&c->q) : mvod_mailbox_back(&c->mb);
}

static void post(struct mvod_capture *c)
{
	if (c->lossless)
		mvod_queue_post(&c->q);
	else
		mvod_mailbox_post(&c->mb);
}

/* Posts f, read into letter l (or, from a source with buffers of its own, copied there). */
static void deliver(struct mvod_capture *c, struct mvod_letter *l, const struct mvod_frame *f)
{
	const struct mvod_image *in = &f->img;
	size_t row = (size_t)in->w * (in->fmt == MVOD_PIX_BGR ? 3 : 1);
	uint8_t *data = l->frame.img.data;
	if (in->data != data) /* a camera converted straight into the letter: nothing to copy */
		for (int y = 0; y < in->h; y++)
			memcpy(data + (size_t)y * row, in->data + (size_t)y * (size_t)in->stride, row);
	l->frame.img = (struct mvod_image){.w = in->w, .h = in->h, .stride = (int)row,
					   .fmt = in->fmt, .data = data};
	l->frame.utime = f->utime;
	l->frame.delivered_us = f->delivered_us;
	l->frame.index = c->base + f->index;
	memcpy(l->frame.bad_before, c->bad, sizeof(c->bad));
	l->epoch = c->epoch;
	l->read = 0;
	c->last = l->frame.index;
	post(c);
}

/*
 * A frame that could not be decoded at its size: a live source's is logged once per reason
 * and counted, the count going out with the next frame (bad_before: a frame the mailbox
 * replaces loses no count); any other source's goes through the queue in its place, for the
 * consumer to skip and count by its reason.
 */
static void bad_frame(struct mvod_capture *c, struct mvod_letter *l, const struct mvod_frame *f)
{
	if (c->lossless) {
		l->frame = (struct mvod_frame){.img = l->frame.img, .utime = f->utime,
					       .index = f->index, .bad = f->bad};
		l->read = -EINVAL;
		post(c);
		return;
	}
	enum mvod_bad_frame why = f->bad < MVOD_BAD_COUNT ? f->bad : MVOD_BAD_CORRUPT;
	if (c->bad[why]++ == 0)
		LOG(WARN, "%s: frame %lld is %s: skipped; later ones are only counted, in the "
			  "summary", c->uri, (long long)(c->base + f->index), mvod_bad_frame_name(why));
}

static void lose(struct mvod_capture *c)
{
	LOG(ERROR, "%s: the device is gone; reopening it until it returns", c->uri);
	mvod_source_close(c->src);
	c->src = NULL;
	c->base = c->last + 1;
	c->backoff_ms = BACKOFF_FIRST_MS;
	atomic_store(&c->down, true);
}

/* One attempt after the backoff; the outcome of each is a debug line, the return one info line. */
static void reopen(struct mvod_capture *c)
{
	if (sleep_unless_stopped(c, c->backoff_ms))
		return;
	c->backoff_ms = c->backoff_ms * 2 > BACKOFF_MAX_MS ? BACKOFF_MAX_MS : c->backoff_ms * 2;
	char err[MVOD_ERR_MAX] = "";
	struct mvod_source *src;
	int ret = mvod_source_open(c->uri, &src, err, sizeof(err));
	if (ret) {
		LOG(DEBUG, "%s: still down: %s", c->uri, err);
		return;
	}
	struct mvod_source_info info;
	mvod_source_info(src, &info);
	if (info.width != c->info.width || info.height != c->info.height) {
		LOG(DEBUG, "%s: came back at %dx%d, not %dx%d; waiting for it", c->uri, info.width,
		    info.height, c->info.width, c->info.height);
		mvod_source_close(src);
		return;
	}
	c->src = src;
	c->epoch++;
	atomic_store(&c->down, false);
	LOG(INFO, "%s: the source is back; tracking starts over", c->uri);
}

/* A frame, or why there is none: -EAGAIN and -EINVAL (one bad frame) go on, others end. */
static int step(struct mvod_capture *c)
{
	if (!c->src) {
		reopen(c);
		return -EAGAIN;
	}
	struct mvod_letter *l = back(c);
	if (!l)
		return -ECANCELED;
	const struct mvod_image into = {.w = c->info.width, .h = c->info.height,
					.stride = c->info.width, .fmt = MVOD_PIX_GREY,
					.data = l->frame.img.data};
	struct mvod_frame f = {0};
	int ret = mvod_source_read_into(c->src, &f, &into);
	if (ret == 0)
		deliver(c, l, &f);
	if (ret == -EINVAL)
		bad_frame(c, l, &f);
	if (ret != -ENODEV)
		return ret;
	lose(c);
	return -EAGAIN;
}

static void *run(void *arg)
{
	struct mvod_capture *c = arg;
	int ret = 0;
	while (!stopping(c) && (ret == 0 || ret == -EAGAIN || ret == -EINVAL))
		ret = step(c);
	int reason = ret < 0 && ret != -EAGAIN && ret != -EINVAL ? ret : -ENODATA;
	if (c->lossless)
		mvod_queue_close(&c->q, reason);
	else
		mvod_mailbox_close(&c->mb, reason);
	return NULL;
}

static int init(struct mvod_capture *c, struct mvod_source *src, const char *uri)
{
	mvod_source_info(src, &c->info);
	c->uri = strdup(uri);
	if (!c->uri)
		return -ENOMEM;
	c->lossless = !c->info.live;
	size_t bytes = (size_t)c->info.width * (size_t)c->info.height * 3; /* grey or BGR */
	int ret = c->lossless ? mvod_queue_init(&c->q, bytes) : mvod_mailbox_init(&c->mb, bytes);
	if (ret)
		return ret;
	mvod_cond_init_monotonic(&c->wake);
	pthread_mutex_init(&c->lock, NULL);
	c->last = -1;
	ret = -pthread_create(&c->thread, NULL, run, c);
	if (ret) {
		pthread_cond_destroy(&c->wake);
		pthread_mutex_destroy(&c->lock);
		mvod_mailbox_fini(&c->mb);
		mvod_queue_fini(&c->q);
	}
	return ret;
}

int mvod_capture_start(struct mvod_source *src, const char *uri, struct mvod_capture **out)
{
	struct mvod_capture *c = calloc(1, sizeof(*c));
	if (!c)
		return -ENOMEM;
	c->src = src;
	int ret = init(c, src, uri);
	if (ret) {
		free(c->uri);
		free(c);
		return ret;
	}
	*out = c;
	return 0;
}

int mvod_capture_next(struct mvod_capture *c, int timeout_ms, struct mvod_frame *frame,
		      int *epoch)
{
	struct mvod_letter *l;
	int ret = c->lossless ? mvod_queue_take(&c->q, timeout_ms, &l)
			      : mvod_mailbox_take(&c->mb, timeout_ms, &l);
	if (ret)
		return ret;
	*frame = l->frame;
	*epoch = l->epoch;
	return l->read;
}

bool mvod_capture_down(struct mvod_capture *c)
{
	return atomic_load(&c->down);
}

void mvod_capture_stop(struct mvod_capture *c)
{
	if (!c)
		return;
	pthread_mutex_lock(&c->lock);
	c->stop = true;
	pthread_cond_signal(&c->wake);
	pthread_mutex_unlock(&c->lock);
	if (c->lossless) /* a capture thread waiting for a free letter must not wait for ever */
		mvod_queue_cancel(&c->q);
	pthread_join(c->thread, NULL);
	pthread_cond_destroy(&c->wake);
	pthread_mutex_destroy(&c->lock);
	mvod_source_close(c->src);
	mvod_mailbox_fini(&c->mb);
	mvod_queue_fini(&c->q);
	free(c->uri);
	free(c);
}
