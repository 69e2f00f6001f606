/*
 * The pipelined input of sources that are not live: the bounded queue on its own (order,
 * letters never handed to both sides, close and cancel), then the capture thread on images:
 * and kitti: sequences written at test time, longer than the queue, with bad frames among
 * them: every frame comes out once, in order, with its own pixels and time, and each bad one
 * in its place with its reason. The file: source is run end to end in integration/pipelined_run.
 */
#include <errno.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <cmocka.h>

#include "harness.h"

#include "capture/queue.h"
#include "mvod/capture.h"

#define BYTES 64
/* Ten times the queue's depth: the capture thread has to wait for room again and again. */
#define FRAMES (10 * MVOD_QUEUE_DEPTH)
#define W 16
#define H 8

/* Frame i's grey level: distinct for every frame of a sequence. */
static int level(int i)
{
	return (7 * i + 3) % 256;
}

static void post(struct mvod_queue *q, int64_t index)
{
	struct mvod_letter *l = mvod_queue_back(q);
	assert_non_null(l);
	l->frame.index = index;
	l->read = 0;
	mvod_queue_post(q);
}

static void test_queue_order(void **state)
{
	(void)state;
	struct mvod_queue q;
	struct mvod_letter *l = NULL, *prev = NULL;
	assert_int_equal(mvod_queue_init(&q, BYTES), 0);
	assert_int_equal(mvod_queue_take(&q, 0, &l), -EAGAIN);
	int64_t next = 0, taken = 0;
	for (int round = 0; round < 5; round++) {
		/* Fill every free letter; the one the consumer holds is never handed out. */
		while (q.posted + q.held < MVOD_QUEUE_DEPTH) {
			struct mvod_letter *back = mvod_queue_back(&q);
			assert_ptr_not_equal(back, l);
			post(&q, next++);
		}
		for (int k = 0; k < MVOD_QUEUE_DEPTH - 1; k++) {
			assert_int_equal(mvod_queue_take(&q, 0, &l), 0);
			assert_int_equal(l->frame.index, taken++);
			assert_ptr_not_equal(l, prev);
			prev = l;
		}
	}
	mvod_queue_close(&q, -EIO);
	while (taken < next) {
		assert_int_equal(mvod_queue_take(&q, 0, &l), 0);
		assert_int_equal(l->frame.index, taken++);
	}
	assert_int_equal(mvod_queue_take(&q, 0, &l), -EIO);
	assert_int_equal(mvod_queue_take(&q, 0, &l), -EIO);
	mvod_queue_fini(&q);
	mvod_queue_fini(&q); /* a zeroed queue too */
}

/* A full queue's producer is released by cancel, and gets no letter. */
static void test_queue_cancel(void **state)
{
	(void)state;
	struct mvod_queue q;
	assert_int_equal(mvod_queue_init(&q, BYTES), 0);
	for (int i = 0; i < MVOD_QUEUE_DEPTH; i++)
		post(&q, i);
	mvod_queue_cancel(&q);
	assert_null(mvod_queue_back(&q));
	mvod_queue_fini(&q);
}

static void write_pgm(const char *path, int w, int h, int v)
{
	FILE *f = fopen(path, "wb");
	assert_non_null(f);
	fprintf(f, "P5\n%d %d\n255\n", w, h);
	for (int k = 0; k < w * h; k++)
		fputc(v, f);
	assert_int_equal(fclose(f), 0);
}

/* What frame i of the sequence is: a good one, or bad for a reason. */
static int badness(int i)
{
	return i == 5 ? MVOD_BAD_CORRUPT : i == 6 ? MVOD_BAD_SIZE : i == 23 ? MVOD_BAD_CORRUPT : -1;
}

/* FRAMES frames in dir (000000.pgm ...) and times.txt, 0.1 s + i * 0.05 s. */
static void write_sequence(const char *dir)
{
	char path[512], times[FRAMES * 16] = "";
	for (int i = 0; i < FRAMES; i++) {
		snprintf(path, sizeof(path), "%s/%06d.pgm", dir, i);
		if (badness(i) == MVOD_BAD_CORRUPT)
			harness_write_file(path, "not an image");
		else
			write_pgm(path, badness(i) == MVOD_BAD_SIZE ? W / 2 : W, H, level(i));
		snprintf(times + strlen(times), sizeof(times) - strlen(times), "%.2f\n",
			 0.1 + i * 0.05);
	}
	snprintf(path, sizeof(path), "%s/times.txt", dir);
	harness_write_file(path, times);
}

/* Frame i as it came out of the capture thread: its index, time and every pixel. */
static void check_frame(const struct mvod_frame *f, int i)
{
	assert_int_equal(f->index, i);
	assert_int_equal(f->utime, 100000 + i * 50000);
	assert_int_equal(f->img.w, W);
	assert_int_equal(f->img.h, H);
	assert_int_equal(f->img.fmt, MVOD_PIX_GREY);
	for (int y = 0; y < H; y++)
		for (int x = 0; x < W; x++)
			assert_int_equal(f->img.data[y * f->img.stride + x], level(i));
}

/* The capture thread on uri ("scheme:" and dir). */
static struct mvod_capture *start(const char *scheme, const char *dir)
{
	char uri[512], err[512] = "";
	snprintf(uri, sizeof(uri), "%s:%s", scheme, dir);
	struct mvod_source *src = NULL;
	if (mvod_source_open(uri, &src, err, sizeof(err)))
		fail_msg("%s: %s", uri, err);
	struct mvod_capture *cap = NULL;
	assert_int_equal(mvod_capture_start(src, uri, &cap), 0);
	return cap;
}

/* Every frame once, in order, then -ENODATA; bad ones as -EINVAL with their reason. */
static void drain(struct mvod_capture *cap)
{
	struct mvod_frame f;
	int epoch, ret;
	for (int i = 0; i < FRAMES; i++) {
		/* A generous wait: an answer comes long before; the loop retries rather than fail. */
		while ((ret = mvod_capture_next(cap, 1000, &f, &epoch)) == -EAGAIN)
			;
		assert_int_equal(epoch, 0);
		if (badness(i) >= 0) {
			assert_int_equal(ret, -EINVAL);
			assert_int_equal(f.index, i);
			assert_int_equal(f.bad, badness(i));
			continue;
		}
		assert_int_equal(ret, 0);
		check_frame(&f, i);
	}
	while ((ret = mvod_capture_next(cap, 1000, &f, &epoch)) == -EAGAIN)
		;
	assert_int_equal(ret, -ENODATA);
	assert_int_equal(mvod_capture_next(cap, 0, &f, &epoch), -ENODATA);
	mvod_capture_stop(cap);
}

static void test_images_in_order(void **state)
{
	(void)state;
	const char *dir = harness_tmp_path("images");
	assert_int_equal(mkdir(dir, 0755), 0);
	write_sequence(dir);
	drain(start("images", dir));
}

static void test_kitti_in_order(void **state)
{
	(void)state;
	const char *seq = harness_tmp_path("seq");
	char path[512];
	assert_int_equal(mkdir(seq, 0755), 0);
	snprintf(path, sizeof(path), "%s/image_0", seq);
	assert_int_equal(mkdir(path, 0755), 0);
	write_sequence(path);
	/* KITTI keeps times.txt beside image_0/, and P0 in calib.txt. */
	char moved[512];
	snprintf(moved, sizeof(moved), "%s/times.txt", seq);
	snprintf(path, sizeof(path), "%s/image_0/times.txt", seq);
	assert_int_equal(rename(path, moved), 0);
	snprintf(path, sizeof(path), "%s/calib.txt", seq);
	harness_write_file(path, "P0: 20 0 8 0 0 20 4 0 0 0 1 0\n");
	drain(start("kitti", seq));
}

/* Stopped with the queue full and the thread waiting for room: it ends, nothing leaks. */
static void test_stop_while_full(void **state)
{
	(void)state;
	const char *dir = harness_tmp_path("full");
	assert_int_equal(mkdir(dir, 0755), 0);
	write_sequence(dir);
	struct mvod_capture *cap = start("images", dir);
	struct mvod_frame f;
	int epoch, ret;
	while ((ret = mvod_capture_next(cap, 1000, &f, &epoch)) == -EAGAIN)
		;
	assert_int_equal(ret, 0);
	check_frame(&f, 0);
	mvod_capture_stop(cap);
	mvod_capture_stop(NULL);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_queue_order),
		cmocka_unit_test(test_queue_cancel),
		cmocka_unit_test(test_images_in_order),
		cmocka_unit_test(test_kitti_in_order),
		cmocka_unit_test(test_stop_while_full),
	};
	return cmocka_run_group_tests(tests, NULL, harness_teardown);
}
