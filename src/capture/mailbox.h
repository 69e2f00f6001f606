/*
 * A single-slot mailbox between one producer (the capture thread) and one consumer (the
 * visual odometry): three preallocated frame buffers that change hands by swapping pointers.
 * The producer fills its own buffer and posts it, never waiting for the consumer; an unread
 * frame in the slot is replaced and counted as dropped. The consumer always gets the newest.
 */
#ifndef MVOD_CAPTURE_MAILBOX_H
#define MVOD_CAPTURE_MAILBOX_H

#include <pthread.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <time.h>

#include "mvod/capture.h"

struct mvod_letter {
	struct mvod_frame frame; /* frame.img.data points into this letter's own buffer */
	int epoch;               /* whatever the producer tags the frame with */
	int read;                /* 0, or -EINVAL: one bad frame, which frame.index and .bad name */
};

struct mvod_mailbox {
	pthread_mutex_t lock;
	pthread_cond_t posted;
	struct mvod_letter letters[3];
	struct mvod_letter *back;  /* the producer's, being filled */
	struct mvod_letter *slot;  /* the newest posted */
	struct mvod_letter *front; /* the consumer's, being read */
	bool fresh;                /* slot holds a frame not yet taken */
	int closed;                /* the producer will post nothing more: why, a negative errno */
	int64_t dropped;
};

/* Three buffers of bytes each. 0 or -ENOMEM. */
int mvod_mailbox_init(struct mvod_mailbox *mb, size_t bytes);
/* Safe on a zeroed or failed-init mailbox. */
void mvod_mailbox_fini(struct mvod_mailbox *mb);

/* Producer: the letter to fill next. Only the producer touches it until it posts. */
struct mvod_letter *mvod_mailbox_back(struct mvod_mailbox *mb);
/* Producer: publishes the back letter; the one it replaces becomes the new back. */
void mvod_mailbox_post(struct mvod_mailbox *mb);
/*
 * Producer: no more frames, because of reason (-ENODATA: the end; another negative errno: a
 * failure). The consumer takes what is left, then gets reason.
 */
void mvod_mailbox_close(struct mvod_mailbox *mb, int reason);

/*
 * Consumer: the newest frame, waiting up to timeout_ms (0 = not at all). 0 with *out (valid
 * until the next take), -EAGAIN when nothing came in time, the close reason when closed and empty.
 */
int mvod_mailbox_take(struct mvod_mailbox *mb, int timeout_ms, struct mvod_letter **out);
/* Frames replaced before they were taken. */
int64_t mvod_mailbox_dropped(struct mvod_mailbox *mb);

/* timeout_ms from now on CLOCK_MONOTONIC, the clock every wait in capture is measured on. */
/* A condition whose timed waits are measured on that clock. */
void mvod_cond_init_monotonic(pthread_cond_t *cond);
/* n letters of bytes each: 0, or -ENOMEM with every buffer freed. */
int mvod_letters_alloc(struct mvod_letter *letters, int n, size_t bytes);
/* Frees the buffers of n letters (NULL ones too). */
void mvod_letters_free(struct mvod_letter *letters, int n);
struct timespec mvod_mailbox_deadline(int timeout_ms);

#endif
