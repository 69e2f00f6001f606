/*
 * A bounded first-in first-out queue between one producer (the capture thread of a source that
 * is not live: a video file, an image folder, a dataset) and one consumer (the visual
 * odometry): MVOD_QUEUE_DEPTH preallocated frame buffers in a ring. The producer waits while
 * every buffer is full, so no frame is ever dropped, and decoding the next frames overlaps
 * processing this one on another core. Letters come out in the order they were posted.
 */
#ifndef MVOD_CAPTURE_QUEUE_H
#define MVOD_CAPTURE_QUEUE_H

#include <pthread.h>
#include <stdbool.h>
#include <stddef.h>

#include "capture/mailbox.h"

/*
 * Letters in the ring, the one the consumer holds included. Decoding a KITTI PNG costs about
 * 5 ms and processing a frame 10-40 ms (a keyframe the most): two decoded frames waiting are
 * enough to cover a spike of either side, one more is filled meanwhile. 4 x 1226 x 370 x 3 bytes
 * = 5.4 MB for KITTI.
 */
#define MVOD_QUEUE_DEPTH 4

struct mvod_queue {
	pthread_mutex_t lock;
	pthread_cond_t changed; /* a letter was posted or freed; the queue was closed or cancelled */
	struct mvod_letter letters[MVOD_QUEUE_DEPTH];
	int head;               /* the oldest posted letter */
	int posted;             /* letters posted and not yet taken, from head on */
	bool held;              /* the consumer holds the letter before head */
	int closed;             /* the producer will post nothing more: why, a negative errno */
	bool cancelled;         /* the consumer is gone: the producer must not wait */
	bool made;              /* lock and condition initialised (fini destroys them) */
};

/* MVOD_QUEUE_DEPTH buffers of bytes each. 0 or -ENOMEM. */
int mvod_queue_init(struct mvod_queue *q, size_t bytes);
/* Safe on a zeroed or failed-init queue. */
void mvod_queue_fini(struct mvod_queue *q);

/*
 * Producer: the letter to fill next, waiting while none is free; NULL once cancelled. Only the
 * producer touches it until it posts.
 */
struct mvod_letter *mvod_queue_back(struct mvod_queue *q);
/* Producer: the letter mvod_queue_back gave goes to the end of the queue. */
void mvod_queue_post(struct mvod_queue *q);
/*
 * Producer: no more letters, because of reason (-ENODATA: the end; another negative errno: a
 * failure). The consumer takes what is queued, then gets reason.
 */
void mvod_queue_close(struct mvod_queue *q, int reason);

/*
 * Consumer: frees the letter of the last take and takes the oldest posted one, waiting up to
 * timeout_ms (0 = not at all). 0 with *out (valid until the next take), -EAGAIN when none came
 * in time, the close reason when closed and empty.
 */
int mvod_queue_take(struct mvod_queue *q, int timeout_ms, struct mvod_letter **out);
/* Consumer: it takes nothing more; a producer waiting for a free letter gets NULL. */
void mvod_queue_cancel(struct mvod_queue *q);

#endif
