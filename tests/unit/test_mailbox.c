/*
 * The single-slot mailbox: the consumer always gets the newest frame, every frame replaced
 * unread is counted, the producer never waits, and the three buffers are the only memory ever
 * handed out. Orderings are forced step by step; the threaded case asserts counts, not timing.
 */
#include <errno.h>
#include <pthread.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "capture/mailbox.h"

#define BYTES 64

/* The producer's side of one frame: stamps the index into the pixels too. */
static void post(struct mvod_mailbox *mb, int64_t index)
{
	struct mvod_letter *l = mvod_mailbox_back(mb);
	memset(l->frame.img.data, (int)(index & 0xff), BYTES);
	l->frame.index = index;
	l->epoch = (int)(index / 100);
	mvod_mailbox_post(mb);
}

static bool one_of_the_three(const struct mvod_mailbox *mb, const struct mvod_letter *l)
{
	return l == &mb->letters[0] || l == &mb->letters[1] || l == &mb->letters[2];
}

static void test_newest_wins_and_drops_are_counted(void **state)
{
	(void)state;
	struct mvod_mailbox mb;
	assert_int_equal(mvod_mailbox_init(&mb, BYTES), 0);
	struct mvod_letter *l;
	assert_int_equal(mvod_mailbox_take(&mb, 0, &l), -EAGAIN);
	for (int i = 0; i < 5; i++)
		post(&mb, i);
	assert_int_equal(mvod_mailbox_take(&mb, 0, &l), 0);
	assert_int_equal(l->frame.index, 4);
	assert_int_equal(l->frame.img.data[BYTES - 1], 4);
	assert_int_equal(mvod_mailbox_dropped(&mb), 4);
	/* Taken once, gone: a second take finds nothing new. */
	assert_int_equal(mvod_mailbox_take(&mb, 0, &l), -EAGAIN);
	post(&mb, 5);
	assert_int_equal(mvod_mailbox_take(&mb, 0, &l), 0);
	assert_int_equal(l->frame.index, 5);
	assert_int_equal(mvod_mailbox_dropped(&mb), 4);
	mvod_mailbox_fini(&mb);
}

/* What the consumer holds is never written by the producer, however many frames it posts. */
static void test_consumer_frame_is_stable(void **state)
{
	(void)state;
	struct mvod_mailbox mb;
	assert_int_equal(mvod_mailbox_init(&mb, BYTES), 0);
	struct mvod_letter *held;
	post(&mb, 7);
	assert_int_equal(mvod_mailbox_take(&mb, 0, &held), 0);
	for (int i = 8; i < 40; i++) {
		assert_ptr_not_equal(mvod_mailbox_back(&mb), held);
		assert_true(one_of_the_three(&mb, mvod_mailbox_back(&mb)));
		post(&mb, i);
	}
	for (int k = 0; k < BYTES; k++)
		assert_int_equal(held->frame.img.data[k], 7);
	assert_int_equal(held->frame.index, 7);
	struct mvod_letter *l;
	assert_int_equal(mvod_mailbox_take(&mb, 0, &l), 0);
	assert_int_equal(l->frame.index, 39);
	assert_int_equal(l->epoch, 0);
	assert_true(one_of_the_three(&mb, l));
	/* 8..38 were replaced unread; 39 was taken. */
	assert_int_equal(mvod_mailbox_dropped(&mb), 31);
	mvod_mailbox_fini(&mb);
}

/* After close the last frame is still delivered, then the reason. */
static void test_close_drains_then_reports(void **state)
{
	(void)state;
	struct mvod_mailbox mb;
	assert_int_equal(mvod_mailbox_init(&mb, BYTES), 0);
	post(&mb, 250);
	mvod_mailbox_close(&mb, -EIO);
	struct mvod_letter *l;
	assert_int_equal(mvod_mailbox_take(&mb, 1000, &l), 0);
	assert_int_equal(l->frame.index, 250);
	assert_int_equal(l->epoch, 2);
	assert_int_equal(mvod_mailbox_take(&mb, 1000, &l), -EIO);
	mvod_mailbox_fini(&mb);
}

#define PRODUCED 20000

static void *producer(void *arg)
{
	struct mvod_mailbox *mb = arg;
	for (int i = 0; i < PRODUCED; i++)
		post(mb, i);
	mvod_mailbox_close(mb, -ENODATA);
	return NULL;
}

/*
 * A producer far faster than the consumer: every frame is either taken or counted as dropped,
 * exactly; the taken ones come in order with their own pixels, and the last one is taken.
 */
static void test_fast_producer_exact_accounting(void **state)
{
	(void)state;
	struct mvod_mailbox mb;
	assert_int_equal(mvod_mailbox_init(&mb, BYTES), 0);
	pthread_t t;
	assert_int_equal(pthread_create(&t, NULL, producer, &mb), 0);
	int64_t taken = 0, last = -1;
	struct mvod_letter *l;
	int ret;
	while ((ret = mvod_mailbox_take(&mb, 1000, &l)) != -ENODATA) {
		if (ret == -EAGAIN)
			continue;
		assert_true(one_of_the_three(&mb, l));
		assert_true(l->frame.index > last);
		for (int k = 0; k < BYTES; k++)
			assert_int_equal(l->frame.img.data[k], l->frame.index & 0xff);
		last = l->frame.index;
		taken++;
	}
	assert_int_equal(pthread_join(t, NULL), 0);
	assert_int_equal(last, PRODUCED - 1);
	assert_int_equal(taken + mvod_mailbox_dropped(&mb), PRODUCED);
	mvod_mailbox_fini(&mb);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_newest_wins_and_drops_are_counted),
		cmocka_unit_test(test_consumer_frame_is_stable),
		cmocka_unit_test(test_close_drains_then_reports),
		cmocka_unit_test(test_fast_producer_exact_accounting),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
