/*
 * The v4l2: backend against a fake device behind its system-call seam (struct mvod_v4l2_io):
 * frames in GREY, YUYV, NV12 and MJPEG (encoded here with libjpeg) come out as the right grey
 * pixels; EINTR, EAGAIN storms, a refused format or size, fewer buffers than asked, sequence
 * gaps, corrupt MJPEG frames and a device that disappears and comes back (with a rendered scene:
 * the poses go on from where they were) each do what mvod promises. The fake answers at once: nothing here waits on a clock except the reopen backoff.
 */
#include <errno.h>
#include <math.h>
#include <poll.h>
#include <setjmp.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cmocka.h>

#include "harness.h"
#include <jpeglib.h>
#include <linux/videodev2.h>
#include <lcm/lcm.h>

#include "capture/v4l2.h"
#include "mvod/capture.h"
#include "mvod/pipeline.h"
#include "util/clock.h"
#include "mvod_status_t.h"

#define W 64
#define H 48
#define BUFSZ (W * H * 2)
#define MAX_FRAMES 48
#define MAX_BUFS 8
/* Rendered scenes (test_reconnect_continues_pose): large enough for the VO to track. */
#define SCENE_W 320
#define SCENE_H 240
#define DEV "/dev/video0"

struct script_frame {
	uint8_t data[BUFSZ];
	size_t len;
	const uint8_t *scene; /* GREY pixels to deliver instead of data, or NULL */
	uint32_t seq;
	bool gone; /* the device disappears here instead of delivering */
};

struct ctrl {
	uint32_t id;
	int value;
};

/* The fake device: its behaviour (set by a test), then its state. */
static struct fake {
	uint32_t offered[4];
	int n_offered;
	uint32_t fourcc, w, h;
	bool refuse_format;   /* S_FMT keeps the current pixel format whatever is asked */
	bool shrink;          /* S_FMT halves the size asked */
	unsigned grant;       /* buffers REQBUFS grants at most */
	bool eintr;           /* every ioctl and poll is interrupted once before it runs */
	int eagain_storm;     /* DQBUF answers EAGAIN this many times before each frame */
	int fail_opens;       /* opens refused (ENOENT) after the device is gone */
	struct ctrl ctrls[4];
	int n_ctrls;
	struct script_frame frames[MAX_FRAMES];
	int n_frames;
	volatile sig_atomic_t *done; /* raised once every frame was dequeued */
	volatile sig_atomic_t *stop_when_down; /* raised by the second reopen refused */
	size_t bufsz;         /* bytes of each buffer */
	/*
	 * Frames the run has processed (counted by its on_frame), when each frame should wait for
	 * the one before to be processed: no frame is dropped, however slow the machine.
	 */
	atomic_int *processed;

	int next, delivered, eagain_left, interrupts, opens, mapped, idle_polls, refused;
	bool interrupted, gone;
	unsigned nbuf;
	bool queued[MAX_BUFS];
	uint8_t mem[MAX_BUFS][SCENE_W * SCENE_H];
} F;

static bool interrupt_once(void)
{
	if (!F.eintr || F.interrupted) {
		F.interrupted = false;
		return false;
	}
	F.interrupted = true;
	F.interrupts++;
	errno = EINTR;
	return true;
}

static int fake_open(const char *path, int flags)
{
	(void)flags;
	if (strcmp(path, DEV) != 0 || (F.gone && F.fail_opens-- > 0)) {
		/* A stop while the device is away: raised on the second refused reopen. */
		if (F.gone && F.stop_when_down && ++F.refused == 2)
			*F.stop_when_down = 1;
		errno = ENOENT;
		return -1;
	}
	F.gone = false;
	F.opens++;
	return 42;
}

static int fake_close(int fd)
{
	(void)fd;
	return 0;
}

static void *fake_mmap(void *addr, size_t len, int prot, int flags, int fd, off_t off)
{
	(void)addr, (void)prot, (void)flags, (void)fd;
	size_t i = (size_t)off / 4096;
	if (i >= F.nbuf || len != F.bufsz)
		return MAP_FAILED;
	F.mapped++;
	return F.mem[i];
}

static int fake_munmap(void *addr, size_t len)
{
	(void)addr, (void)len;
	F.mapped--;
	return 0;
}

static int fake_poll(struct pollfd *fds, nfds_t n, int timeout_ms)
{
	(void)n, (void)timeout_ms;
	if (interrupt_once())
		return -1;
	fds[0].revents = F.gone ? POLLERR : POLLIN;
	bool behind = F.processed && atomic_load(F.processed) < F.delivered;
	if (F.gone || (F.next < F.n_frames && !behind))
		return 1;
	if (behind) {
		usleep(1000);
		return 0;
	}
	/*
	 * The script is over: stop the run once the consumer has surely taken the last frame, the
	 * newest in the mailbox (a 64x48 frame takes it well under a millisecond; this is 300).
	 */
	if (F.done && ++F.idle_polls > 300)
		*F.done = 1;
	usleep(1000); /* a real poll would wait; keep a spinning reader off the CPU */
	return 0;
}

static bool offered(uint32_t fourcc)
{
	for (int i = 0; i < F.n_offered; i++)
		if (F.offered[i] == fourcc)
			return true;
	return false;
}

static void fill_pix(struct v4l2_pix_format *p)
{
	p->width = F.w;
	p->height = F.h;
	p->pixelformat = F.fourcc;
	p->field = V4L2_FIELD_NONE;
	p->bytesperline = F.fourcc == V4L2_PIX_FMT_YUYV ? 2 * F.w : F.fourcc == V4L2_PIX_FMT_MJPEG ? 0 : F.w;
	p->sizeimage = (uint32_t)F.bufsz;
}

static struct ctrl *find_ctrl(uint32_t id)
{
	for (int i = 0; i < F.n_ctrls; i++)
		if (F.ctrls[i].id == id)
			return &F.ctrls[i];
	return NULL;
}

static int refuse(int e)
{
	errno = e;
	return -1;
}

static int dqbuf(struct v4l2_buffer *b)
{
	if (F.eagain_left > 0 || F.next >= F.n_frames) {
		F.eagain_left -= F.eagain_left > 0;
		return refuse(EAGAIN);
	}
	const struct script_frame *s = &F.frames[F.next++];
	if (s->gone) {
		F.gone = true;
		return refuse(ENODEV);
	}
	unsigned i = 0;
	while (i < F.nbuf && !F.queued[i])
		i++;
	assert_true(i < F.nbuf); /* mvod gave every buffer back */
	memcpy(F.mem[i], s->scene ? s->scene : s->data, s->len);
	F.queued[i] = false;
	F.delivered++;
	*b = (struct v4l2_buffer){.index = i, .type = b->type, .memory = b->memory,
				  .bytesused = (uint32_t)s->len, .sequence = s->seq,
				  .flags = V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC,
				  .timestamp = {.tv_sec = 100, .tv_usec = s->seq * 1000}};
	F.eagain_left = F.eagain_storm;
	return 0;
}

static int set_fmt(struct v4l2_format *f)
{
	if (!F.refuse_format && offered(f->fmt.pix.pixelformat))
		F.fourcc = f->fmt.pix.pixelformat;
	F.w = F.shrink ? f->fmt.pix.width / 2 : f->fmt.pix.width;
	F.h = F.shrink ? f->fmt.pix.height / 2 : f->fmt.pix.height;
	fill_pix(&f->fmt.pix);
	return 0;
}

static int query_ctrl(struct v4l2_queryctrl *q)
{
	return find_ctrl(q->id) ? 0 : refuse(EINVAL);
}

static int ctrl(unsigned long req, struct v4l2_control *c)
{
	struct ctrl *k = find_ctrl(c->id);
	if (!k)
		return refuse(EINVAL);
	if (req == VIDIOC_G_CTRL)
		c->value = k->value;
	else
		k->value = c->value;
	return 0;
}

static int enum_sizes(struct v4l2_frmsizeenum *s)
{
	if (s->index > 1)
		return refuse(EINVAL);
	s->type = V4L2_FRMSIZE_TYPE_DISCRETE;
	s->discrete.width = W >> s->index;
	s->discrete.height = H >> s->index;
	return 0;
}

static int enum_intervals(struct v4l2_frmivalenum *i)
{
	if (i->index > 1)
		return refuse(EINVAL);
	i->type = V4L2_FRMIVAL_TYPE_DISCRETE;
	i->discrete = (struct v4l2_fract){1, 30 / (i->index + 1)};
	return 0;
}

static int parm(unsigned long req, struct v4l2_streamparm *p)
{
	struct v4l2_fract *t = &p->parm.capture.timeperframe;
	/* The fake runs at 30 fps only, whatever is asked. */
	*t = (struct v4l2_fract){1, 30};
	return 0;
}

static int querycap(struct v4l2_capability *c)
{
	*c = (struct v4l2_capability){.capabilities = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_STREAMING |
						      V4L2_CAP_DEVICE_CAPS,
				      .device_caps = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_STREAMING};
	strcpy((char *)c->card, "fake cam");
	strcpy((char *)c->driver, "fake");
	strcpy((char *)c->bus_info, "test");
	return 0;
}

static int buffers(unsigned long req, struct v4l2_buffer *b, struct v4l2_requestbuffers *rb)
{
	switch (req) {
	case VIDIOC_REQBUFS:
		rb->count = rb->count < F.grant ? rb->count : F.grant;
		F.nbuf = rb->count;
		memset(F.queued, 0, sizeof(F.queued));
		return 0;
	case VIDIOC_QUERYBUF:
		b->length = (uint32_t)F.bufsz;
		b->m.offset = b->index * 4096;
		return b->index < F.nbuf ? 0 : refuse(EINVAL);
	case VIDIOC_QBUF:
		F.queued[b->index] = true;
		return 0;
	default:
		return dqbuf(b);
	}
}

static int fake_ioctl(int fd, unsigned long req, void *arg)
{
	(void)fd;
	if (interrupt_once())
		return -1;
	if (F.gone)
		return refuse(ENODEV);
	switch (req) {
	case VIDIOC_QUERYCAP: return querycap(arg);
	case VIDIOC_ENUM_FMT: {
		struct v4l2_fmtdesc *d = arg;
		if (d->index >= (uint32_t)F.n_offered)
			return refuse(EINVAL);
		d->pixelformat = F.offered[d->index];
		snprintf((char *)d->description, sizeof(d->description), "%.4s", (char *)&d->pixelformat);
		return 0;
	}
	case VIDIOC_ENUM_FRAMESIZES: return enum_sizes(arg);
	case VIDIOC_ENUM_FRAMEINTERVALS: return enum_intervals(arg);
	case VIDIOC_G_FMT: fill_pix(&((struct v4l2_format *)arg)->fmt.pix); return 0;
	case VIDIOC_S_FMT: return set_fmt(arg);
	case VIDIOC_S_PARM:
	case VIDIOC_G_PARM: return parm(req, arg);
	case VIDIOC_QUERYCTRL: return query_ctrl(arg);
	case VIDIOC_G_CTRL:
	case VIDIOC_S_CTRL: return ctrl(req, arg);
	case VIDIOC_REQBUFS: return buffers(req, NULL, arg);
	case VIDIOC_QUERYBUF:
	case VIDIOC_QBUF:
	case VIDIOC_DQBUF: return buffers(req, arg, NULL);
	case VIDIOC_STREAMON:
	case VIDIOC_STREAMOFF: return 0;
	}
	return refuse(ENOTTY);
}

static const struct mvod_v4l2_io fake_io = {
	.open = fake_open,
	.close = fake_close,
	.ioctl = fake_ioctl,
	.mmap = fake_mmap,
	.munmap = fake_munmap,
	.poll = fake_poll,
};

/* The grey value of pixel (x, y) in frame i: smooth, so that JPEG keeps it within a level. */
static uint8_t pattern(int i, int x, int y)
{
	return (uint8_t)(40 + 20 * i + 2 * x + y);
}

static size_t encode_jpeg(int i, uint8_t *out, size_t cap)
{
	/* Webcams send YCbCr JPEGs: encode colour (r = g = b) so the decoder drops the chroma. */
	struct jpeg_compress_struct c;
	struct jpeg_error_mgr e;
	c.err = jpeg_std_error(&e);
	jpeg_create_compress(&c);
	unsigned char *mem = NULL;
	unsigned long len = 0;
	jpeg_mem_dest(&c, &mem, &len);
	c.image_width = W;
	c.image_height = H;
	c.input_components = 3;
	c.in_color_space = JCS_RGB;
	jpeg_set_defaults(&c);
	jpeg_set_quality(&c, 100, TRUE);
	jpeg_start_compress(&c, TRUE);
	uint8_t row[W * 3];
	while (c.next_scanline < H) {
		for (int x = 0; x < W; x++)
			memset(row + 3 * x, pattern(i, x, (int)c.next_scanline), 3);
		JSAMPROW r = row;
		jpeg_write_scanlines(&c, &r, 1);
	}
	jpeg_finish_compress(&c);
	jpeg_destroy_compress(&c);
	assert_true(len <= cap);
	memcpy(out, mem, len);
	free(mem);
	return len;
}

/* Frame i of the script in the device's format, with driver sequence number seq. */
static void add_frame(int i, uint32_t seq)
{
	struct script_frame *s = &F.frames[F.n_frames++];
	s->seq = seq;
	s->gone = false;
	s->scene = NULL;
	if (F.fourcc == V4L2_PIX_FMT_MJPEG) {
		s->len = encode_jpeg(i, s->data, sizeof(s->data));
		return;
	}
	int bpp = F.fourcc == V4L2_PIX_FMT_YUYV ? 2 : 1;
	memset(s->data, 128, sizeof(s->data)); /* chroma: grey */
	for (int y = 0; y < H; y++)
		for (int x = 0; x < W; x++)
			s->data[(y * W + x) * bpp] = pattern(i, x, y);
	s->len = F.fourcc == V4L2_PIX_FMT_NV12 ? W * H * 3 / 2 : (size_t)(W * H * bpp);
}

static void add_gone(void)
{
	F.frames[F.n_frames++].gone = true;
}

/* A device offering fourcc (current format) and nothing else quirky. */
static void reset(uint32_t fourcc)
{
	memset(&F, 0, sizeof(F));
	F.offered[F.n_offered++] = fourcc;
	F.fourcc = fourcc;
	F.w = W;
	F.h = H;
	F.grant = 4;
	F.bufsz = BUFSZ;
	mvod_v4l2_io = &fake_io;
}

static struct mvod_source *open_ok(const char *uri)
{
	struct mvod_source *src = NULL;
	char err[512] = "";
	if (mvod_source_open(uri, &src, err, sizeof(err)) != 0)
		fail_msg("%s: %s", uri, err);
	return src;
}

static void expect_open_error(const char *uri, int code, const char *needle)
{
	harness_source_open_fails(uri, code, needle);
	assert_int_equal(F.mapped, 0); /* a failed open leaves nothing mapped */
}

/* The next read that is not "no frame yet"; *waits counts those. */
static int read_frame(struct mvod_source *src, struct mvod_frame *f, int *waits)
{
	int ret, n = 0;
	while ((ret = mvod_source_read(src, f)) == -EAGAIN)
		assert_true(++n < 1000);
	if (waits)
		*waits = n;
	return ret;
}

/*
 * Largest difference from the pattern. JPEG at quality 100 of this smooth ramp, decoded to
 * grey by the same library, measured 0 grey levels here; 2 leaves room for the DCT rounding of
 * another libjpeg build. A wrong conversion (chroma read as luma, a shifted row) is off by tens.
 */
static int max_error(const struct mvod_frame *f, int i)
{
	int worst = 0;
	for (int y = 0; y < H; y++)
		for (int x = 0; x < W; x++) {
			int d = abs(f->img.data[y * f->img.stride + x] - pattern(i, x, y));
			worst = d > worst ? d : worst;
		}
	return worst;
}

static void play_format(uint32_t fourcc, const char *name, int tolerance)
{
	reset(fourcc);
	for (int i = 0; i < 3; i++)
		add_frame(i, (uint32_t)(7 + i));
	char uri[128];
	snprintf(uri, sizeof(uri), "v4l2:" DEV "?width=%d&height=%d&fps=30&format=%s", W, H, name);
	struct mvod_source *src = open_ok(uri);
	struct mvod_source_info info;
	mvod_source_info(src, &info);
	assert_int_equal(info.width, W);
	assert_int_equal(info.height, H);
	assert_true(fabs(info.fps - 30) < 1e-9);
	assert_true(info.live);
	assert_true(isnan(info.focus));
	for (int i = 0; i < 3; i++) {
		struct mvod_frame f;
		assert_int_equal(read_frame(src, &f, NULL), 0);
		assert_int_equal(f.img.fmt, MVOD_PIX_GREY);
		assert_int_equal(f.index, i);
		assert_int_equal(f.utime, 100 * 1000000LL + (7 + i) * 1000);
		int err = max_error(&f, i);
		if (err > tolerance)
			fail_msg("%s frame %d: off by %d grey levels", name, i, err);
	}
	mvod_source_close(src);
	assert_int_equal(F.mapped, 0);
}

static void test_formats(void **state)
{
	(void)state;
	play_format(V4L2_PIX_FMT_GREY, "GREY", 0);
	play_format(V4L2_PIX_FMT_YUYV, "YUYV", 0);
	play_format(V4L2_PIX_FMT_NV12, "NV12", 0);
	play_format(V4L2_PIX_FMT_MJPEG, "MJPEG", 2);
}

/*
 * A caller's buffer offered to the read (the capture thread's mailbox) gets the converted
 * frame itself, with no copy through the source's own buffer; without one the source's is used.
 */
static void test_read_into(void **state)
{
	(void)state;
	static const uint32_t fourcc[] = {V4L2_PIX_FMT_GREY, V4L2_PIX_FMT_YUYV};
	for (size_t k = 0; k < sizeof(fourcc) / sizeof(fourcc[0]); k++) {
		reset(fourcc[k]);
		add_frame(0, 0);
		add_frame(1, 1);
		struct mvod_source *src = open_ok("v4l2:" DEV);
		uint8_t buf[W * H];
		const struct mvod_image into = {W, H, W, MVOD_PIX_GREY, buf};
		struct mvod_frame f;
		while (mvod_source_read_into(src, &f, &into) == -EAGAIN)
			;
		assert_ptr_equal(f.img.data, buf);
		assert_int_equal(max_error(&f, 0), 0);
		assert_int_equal(read_frame(src, &f, NULL), 0);
		assert_ptr_not_equal(f.img.data, buf);
		assert_int_equal(max_error(&f, 1), 0);
		mvod_source_close(src);
	}
}

/* Every ioctl and poll interrupted once: open goes through, a read says "no frame yet". */
static void test_eintr(void **state)
{
	(void)state;
	reset(V4L2_PIX_FMT_YUYV);
	F.eintr = true;
	add_frame(0, 0);
	struct mvod_source *src = open_ok("v4l2:" DEV "?format=YUYV");
	struct mvod_frame f;
	assert_int_equal(mvod_source_read(src, &f), -EAGAIN); /* the poll was interrupted */
	assert_int_equal(read_frame(src, &f, NULL), 0);
	assert_int_equal(max_error(&f, 0), 0);
	assert_true(F.interrupts > 10);
	mvod_source_close(src);
}

static void test_eagain_storm(void **state)
{
	(void)state;
	reset(V4L2_PIX_FMT_GREY);
	F.eagain_storm = 50;
	add_frame(0, 0);
	add_frame(1, 1);
	struct mvod_source *src = open_ok("v4l2:" DEV);
	struct mvod_frame f;
	int waits;
	assert_int_equal(read_frame(src, &f, &waits), 0);
	assert_int_equal(waits, 0);
	assert_int_equal(read_frame(src, &f, &waits), 0);
	assert_int_equal(waits, 50);
	assert_int_equal(f.index, 1);
	assert_int_equal(max_error(&f, 1), 0);
	mvod_source_close(src);
}

static void test_refused_format_and_size(void **state)
{
	(void)state;
	reset(V4L2_PIX_FMT_YUYV);
	F.offered[F.n_offered++] = V4L2_PIX_FMT_MJPEG;
	F.refuse_format = true;
	expect_open_error("v4l2:" DEV "?format=MJPEG", -EINVAL, "refused format MJPG (it set YUYV)");
	reset(V4L2_PIX_FMT_YUYV);
	F.shrink = true;
	expect_open_error("v4l2:" DEV "?width=64&height=48", -EINVAL,
			  "cannot deliver 64x48 in YUYV (it set 32x24)");
	reset(V4L2_PIX_FMT_YUYV);
	expect_open_error("v4l2:" DEV "?fps=60", -EINVAL, "runs at 30 fps at 64x48 YUYV, not the 60");
	reset(V4L2_PIX_FMT_YUYV);
	F.offered[0] = v4l2_fourcc('B', 'G', 'R', '3');
	F.fourcc = F.offered[0];
	expect_open_error("v4l2:" DEV, -ENOTSUP, "offers none of the formats mvod reads");
}

static void test_fewer_buffers(void **state)
{
	(void)state;
	reset(V4L2_PIX_FMT_GREY);
	F.grant = 2;
	add_frame(0, 0);
	add_frame(1, 1);
	add_frame(2, 2);
	struct mvod_source *src = open_ok("v4l2:" DEV);
	assert_int_equal(F.mapped, 2);
	struct mvod_frame f;
	for (int i = 0; i < 3; i++) { /* two buffers cycle: each is given back */
		assert_int_equal(read_frame(src, &f, NULL), 0);
		assert_int_equal(max_error(&f, i), 0);
	}
	mvod_source_close(src);
	reset(V4L2_PIX_FMT_GREY);
	F.grant = 1;
	expect_open_error("v4l2:" DEV, -ENOMEM, "granted 1 buffer(s) and mvod needs at least 2");
}

/* Driver sequence 5, 6, 9, 10 (and a wrap of the 32-bit counter): frames 0, 1, 4, 5, 7. */
static void test_sequence_gaps(void **state)
{
	(void)state;
	reset(V4L2_PIX_FMT_GREY);
	const uint32_t seq[] = {5, 6, 9, 10, 12};
	const int64_t want[] = {0, 1, 4, 5, 7};
	for (int i = 0; i < 5; i++)
		add_frame(i, seq[i] - 11); /* 5 - 11 wraps: the counter rolls over mid-stream */
	struct mvod_source *src = open_ok("v4l2:" DEV);
	for (int i = 0; i < 5; i++) {
		struct mvod_frame f;
		assert_int_equal(read_frame(src, &f, NULL), 0);
		assert_int_equal(f.index, want[i]);
	}
	mvod_source_close(src);
}

/* A truncated and a corrupt JPEG are each one lost frame; the stream goes on. */
static void test_corrupt_mjpeg(void **state)
{
	(void)state;
	reset(V4L2_PIX_FMT_MJPEG);
	for (int i = 0; i < 4; i++)
		add_frame(i, (uint32_t)i);
	F.frames[1].len /= 2;
	for (size_t k = 200; k < F.frames[2].len; k += 7)
		F.frames[2].data[k] ^= 0x5a;
	struct mvod_source *src = open_ok("v4l2:" DEV "?format=MJPG");
	struct mvod_frame f;
	assert_int_equal(read_frame(src, &f, NULL), 0);
	assert_int_equal(read_frame(src, &f, NULL), -EINVAL);
	assert_int_equal(read_frame(src, &f, NULL), -EINVAL);
	assert_int_equal(read_frame(src, &f, NULL), 0);
	assert_int_equal(f.index, 3);
	assert_true(max_error(&f, 3) <= 2);
	mvod_source_close(src);
}

static void test_lens_and_exposure(void **state)
{
	(void)state;
	reset(V4L2_PIX_FMT_GREY);
	F.ctrls[F.n_ctrls++] = (struct ctrl){V4L2_CID_FOCUS_AUTO, 1};
	F.ctrls[F.n_ctrls++] = (struct ctrl){V4L2_CID_FOCUS_ABSOLUTE, 120};
	F.ctrls[F.n_ctrls++] = (struct ctrl){V4L2_CID_EXPOSURE_AUTO, V4L2_EXPOSURE_APERTURE_PRIORITY};
	F.ctrls[F.n_ctrls++] = (struct ctrl){V4L2_CID_EXPOSURE_ABSOLUTE, 0};
	struct mvod_source *src = open_ok("v4l2:" DEV "?exposure=250");
	struct mvod_source_info info;
	mvod_source_info(src, &info);
	assert_int_equal(F.ctrls[0].value, 0); /* autofocus off */
	assert_true(info.focus == 120);
	assert_int_equal(F.ctrls[2].value, V4L2_EXPOSURE_MANUAL);
	assert_int_equal(F.ctrls[3].value, 250);
	mvod_source_close(src);
	reset(V4L2_PIX_FMT_GREY);
	expect_open_error("v4l2:" DEV "?exposure=auto", -ENOTSUP, "has no exposure control");
}

static void test_list(void **state)
{
	(void)state;
	reset(V4L2_PIX_FMT_YUYV);
	F.offered[F.n_offered++] = v4l2_fourcc('B', 'G', 'R', '3');
	char *text = NULL;
	size_t len = 0;
	FILE *out = open_memstream(&text, &len);
	assert_int_equal(mvod_v4l2_list(out), 1);
	fclose(out);
	const char *want[] = {
		"v4l2:/dev/video0  fake cam (driver fake, bus test)\n",
		"    YUYV (YUYV)\n      64x48 @ 30, 15 fps\n      32x24 @ 30, 15 fps\n",
		"    BGR3 (BGR3): mvod does not read this format\n",
		"    --source 'v4l2:/dev/video0?width=64&height=48&fps=30&format=YUYV'\n",
	};
	for (size_t i = 0; i < sizeof(want) / sizeof(want[0]); i++)
		if (!strstr(text, want[i]))
			fail_msg("missing \"%s\" in:\n%s", want[i], text);
	free(text);
#if !MVOD_HAVE_LIBCAMERA
	/* The whole list (mvod --list-cameras) ends by saying libcamera's cameras are not in it. */
	out = open_memstream(&text, &len);
	assert_int_equal(mvod_capture_list_cameras(out), 1);
	fclose(out);
	const char *note = "\nlibcamera cameras cannot be listed: this mvod was built without "
			   "libcamera: install libcamera-dev and rebuild (meson setup "
			   "-Dlibcamera=enabled)\n";
	if (len < strlen(note) || strcmp(text + len - strlen(note), note) != 0)
		fail_msg("no \"%s\" at the end of:\n%s", note, text);
	free(text);
#endif
}

/* The mvod.status_t states a run published, in order. */
struct statuses {
	int n;
	int8_t state[256];
	mvod_status_t last;
};

static void on_status(const lcm_recv_buf_t *rbuf, const char *ch, const mvod_status_t *msg,
		      void *user)
{
	(void)rbuf, (void)ch;
	struct statuses *s = user;
	if (s->n < 256)
		s->state[s->n++] = msg->state;
	s->last = *msg;
}

static int index_of(const struct statuses *s, int8_t state, int from)
{
	for (int i = from; i < s->n; i++)
		if (s->state[i] == state)
			return i;
	return -1;
}

/* A full run of o (mvod_run over memq) on the fake device until *stop, with its statuses. */
static void run_opts(struct mvod_run_opts *o, volatile sig_atomic_t *stop, struct statuses *got,
		     struct mvod_run_summary *sum)
{
	lcm_t *lcm = lcm_create("memq://");
	assert_non_null(lcm);
	mvod_status_t_subscription_t *sub = mvod_status_t_subscribe(lcm, "S", on_status, got);
	struct mvod_ipc *ipc;
	assert_int_equal(mvod_ipc_create_on(lcm, "P", "S", &ipc), 0);
	assert_int_equal(mvod_run(o, ipc, stop, sum), 0);
	while (lcm_handle_timeout(lcm, 0) > 0)
		;
	mvod_ipc_destroy(ipc);
	mvod_status_t_unsubscribe(lcm, sub);
	lcm_destroy(lcm);
}

/* The --clock of run_fake's runs (monotonic unless a test sets it). */
static enum mvod_clock fake_clock;

/* run_opts on the W x H device; the calibration records calib_focus unless it is NaN. */
static void run_fake_focus(volatile sig_atomic_t *stop, struct statuses *got,
			   struct mvod_run_summary *sum, double calib_focus)
{
	char calib[64] = "/tmp/mvod-test-v4l2-XXXXXX";
	int fd = mkstemp(calib);
	assert_true(fd >= 0);
	close(fd);
	struct mvod_camera cam = {.width = W, .height = H, .fx = 50, .fy = 50, .cx = W / 2.0,
				  .cy = H / 2.0, .has_focus = !isnan(calib_focus),
				  .focus = isnan(calib_focus) ? 0 : calib_focus};
	assert_int_equal(mvod_calib_save(calib, &cam, NULL), 0);
	struct mvod_run_opts o;
	mvod_run_opts_default(&o);
	o.source = "v4l2:" DEV "?width=64&height=48&format=GREY";
	o.calib = calib;
	o.clock = fake_clock;
	run_opts(&o, stop, got, sum);
	unlink(calib);
}

static void run_fake(volatile sig_atomic_t *stop, struct statuses *got,
		     struct mvod_run_summary *sum)
{
	run_fake_focus(stop, got, sum, NAN);
}

/* run_fake through the whole script: the fake raises the stop once it is over. */
static void run_script(struct statuses *got, struct mvod_run_summary *sum)
{
	static volatile sig_atomic_t stop;
	stop = 0;
	F.done = &stop;
	*got = (struct statuses){0};
	run_fake(&stop, got, sum);
}

/*
 * A calibration made at focus 100 on a camera whose lens is held at 120: the run warns with
 * both values; at 120 it says nothing. stderr is captured in a file for the check.
 */
static void focus_run(double calib_focus, char *log, size_t len)
{
	reset(V4L2_PIX_FMT_GREY);
	F.ctrls[F.n_ctrls++] = (struct ctrl){V4L2_CID_FOCUS_AUTO, 1};
	F.ctrls[F.n_ctrls++] = (struct ctrl){V4L2_CID_FOCUS_ABSOLUTE, 120};
	for (int i = 0; i < 3; i++)
		add_frame(i, (uint32_t)i);
	static volatile sig_atomic_t stop;
	stop = 0;
	F.done = &stop;
	FILE *cap = tmpfile();
	assert_non_null(cap);
	fflush(stderr);
	int saved = dup(2);
	dup2(fileno(cap), 2);
	struct statuses got = {0};
	struct mvod_run_summary sum;
	run_fake_focus(&stop, &got, &sum, calib_focus);
	fflush(stderr);
	dup2(saved, 2);
	close(saved);
	rewind(cap);
	size_t n = fread(log, 1, len - 1, cap);
	log[n] = '\0';
	fclose(cap);
}

static void test_focus_against_calibration(void **state)
{
	(void)state;
	char log[8192];
	focus_run(100, log, sizeof(log));
	if (!strstr(log, "calibration was made at focus 100 but the camera is at 120"))
		fail_msg("no focus warning in:\n%s", log);
	focus_run(120, log, sizeof(log));
	assert_null(strstr(log, "calibration was made at focus"));
	assert_non_null(strstr(log, "focus held at 120"));
}

/*
 * The device vanishes after 6 frames (ENODEV), refuses the first reopen, and comes back with
 * 6 more: the run reports SOURCE_DOWN, tracks again, and every frame is processed or counted.
 */
static void test_unplug_and_return(void **state)
{
	(void)state;
	reset(V4L2_PIX_FMT_GREY);
	for (int i = 0; i < 6; i++)
		add_frame(i, (uint32_t)i);
	add_gone();
	for (int i = 0; i < 6; i++)
		add_frame(i, (uint32_t)(1000 + i)); /* a new stream numbers afresh */
	F.fail_opens = 1;
	struct statuses got;
	struct mvod_run_summary sum;
	run_script(&got, &sum);
	assert_int_equal(F.opens, 2); /* the first and the one after the refusal */
	assert_true(sum.live);
	assert_int_equal(sum.frames + sum.dropped, 12);
	int down = index_of(&got, MVOD_RUN_SOURCE_DOWN, 0);
	assert_true(down >= 0);
	assert_true(index_of(&got, MVOD_STATE_INITIALIZING, down) > down);
	assert_int_equal(got.last.state, MVOD_RUN_STOPPING);
	assert_int_equal(got.last.frames, sum.frames);
	assert_int_equal(got.last.dropped_frames, sum.dropped);
}

/*
 * Frames the camera sends broken (buffers cut short) are skipped and counted apart from the
 * dropped ones, with FAULT_FRAME_UNREADABLE in status: processed + dropped + skipped = sent.
 */
static void test_bad_frames_not_dropped(void **state)
{
	(void)state;
	reset(V4L2_PIX_FMT_GREY);
	for (int i = 0; i < 8; i++)
		add_frame(i, (uint32_t)i);
	F.frames[2].len /= 2;
	F.frames[5].len /= 2;
	struct statuses got;
	struct mvod_run_summary sum;
	run_script(&got, &sum);
	assert_int_equal(sum.skipped[MVOD_BAD_CORRUPT], 2);
	assert_int_equal(sum.frames + sum.dropped + 2, 8);
	assert_int_equal(got.last.frames, sum.frames);
	assert_int_equal(got.last.dropped_frames, sum.dropped);
	assert_true(got.last.faults & MVOD_STATUS_T_FAULT_FRAME_UNREADABLE);
}

/* A stop that comes while the device is away ends the run (it would hang here otherwise). */
static void test_stop_while_down(void **state)
{
	(void)state;
	reset(V4L2_PIX_FMT_GREY);
	for (int i = 0; i < 3; i++)
		add_frame(i, (uint32_t)i);
	add_gone();
	F.fail_opens = 1000;
	static volatile sig_atomic_t stop;
	stop = 0;
	F.stop_when_down = &stop;
	struct statuses got = {0};
	struct mvod_run_summary sum;
	run_fake(&stop, &got, &sum);
	assert_int_equal(F.refused, 2);
	assert_int_equal(F.opens, 1);
	assert_true(index_of(&got, MVOD_RUN_SOURCE_DOWN, 0) >= 0);
	assert_int_equal(got.last.state, MVOD_RUN_STOPPING);
	assert_int_equal(sum.frames + sum.dropped, 3);
}

/* The scene test: frames before the unplug, frames the camera moves through unseen, after. */
#define BEFORE 20
#define UNSEEN 10
#define AFTER 20

/* Where each processed frame's pose went, in order; counts frames for the lockstep. */
struct poses {
	atomic_int n;
	double t[BEFORE + AFTER][3];
	double R[BEFORE + AFTER][9];
};

static int on_pose(void *ctx, const struct mvod_frame_out *f)
{
	struct poses *p = ctx;
	int i = atomic_load(&p->n);
	assert_true(i < BEFORE + AFTER);
	memcpy(p->t[i], f->res->pose.t, sizeof(p->t[i]));
	memcpy(p->R[i], f->res->pose.R, sizeof(p->R[i]));
	atomic_store(&p->n, i + 1);
	return 0;
}

/* The grey frames of a rendered sequence, scene[i] for frame i. */
static uint8_t *load_scenes(const char *dir, int n)
{
	char uri[320];
	snprintf(uri, sizeof(uri), "images:%s/images", dir);
	struct mvod_source *src = open_ok(uri);
	uint8_t *px = malloc((size_t)n * SCENE_W * SCENE_H);
	assert_non_null(px);
	for (int i = 0; i < n; i++) {
		struct mvod_frame f;
		assert_int_equal(mvod_source_read(src, &f), 0);
		assert_int_equal(f.img.fmt, MVOD_PIX_GREY);
		for (int y = 0; y < SCENE_H; y++)
			memcpy(px + ((size_t)i * SCENE_H + y) * SCENE_W,
			       f.img.data + (size_t)y * (size_t)f.img.stride, SCENE_W);
	}
	mvod_source_close(src);
	return px;
}

static void add_scene(const uint8_t *px, uint32_t seq)
{
	struct script_frame *s = &F.frames[F.n_frames++];
	*s = (struct script_frame){.scene = px, .len = SCENE_W * SCENE_H, .seq = seq};
}

/*
 * A camera driving forward (mvod-synth) is unplugged after frame 19 and comes back at frame 30:
 * the first pose after the return is the last one before it, not the identity of a new world
 * frame, though the camera moved on by 1.1 m; tracking then goes on in the same direction.
 */
static void test_reconnect_continues_pose(void **state)
{
	(void)state;
	char dir[300], calib[320];
	snprintf(dir, sizeof(dir), "%s/forward", harness_tmpdir());
	harness_synth(dir, "forward", BEFORE + UNSEEN + AFTER, "png", "--size", "320x240", NULL);
	snprintf(calib, sizeof(calib), "%s/calib.json", dir);
	uint8_t *scenes = load_scenes(dir, BEFORE + UNSEEN + AFTER);
	reset(V4L2_PIX_FMT_GREY);
	F.w = SCENE_W;
	F.h = SCENE_H;
	F.bufsz = SCENE_W * SCENE_H;
	for (int i = 0; i < BEFORE; i++)
		add_scene(scenes + (size_t)i * F.bufsz, (uint32_t)i);
	add_gone();
	for (int i = BEFORE + UNSEEN; i < BEFORE + UNSEEN + AFTER; i++)
		add_scene(scenes + (size_t)i * F.bufsz, (uint32_t)i);
	static struct poses got_poses;
	atomic_store(&got_poses.n, 0);
	F.processed = &got_poses.n;
	static volatile sig_atomic_t stop;
	stop = 0;
	F.done = &stop;
	struct mvod_run_opts o;
	mvod_run_opts_default(&o);
	o.source = "v4l2:" DEV "?width=320&height=240&format=GREY";
	o.calib = calib;
	static const struct mvod_sink_ops pose_ops = {.name = "poses", .frame = on_pose};
	struct mvod_sink sink = {&pose_ops, &got_poses};
	o.sinks = &sink;
	o.n_sinks = 1;
	struct statuses got = {0};
	struct mvod_run_summary sum;
	run_opts(&o, &stop, &got, &sum);
	free(scenes);
	assert_int_equal(sum.frames, BEFORE + AFTER); /* the lockstep lost none */
	assert_true(index_of(&got, MVOD_RUN_SOURCE_DOWN, 0) >= 0);

	double (*t)[3] = got_poses.t, (*R)[9] = got_poses.R;
	int last = BEFORE - 1, first = BEFORE, end = BEFORE + AFTER - 1;
	/*
	 * Measured: the last pose before is 11.45 units out (the first step is the unit); a
	 * restart into a new world frame would put the next one back at the origin.
	 */
	assert_true(mvod_vec3_norm(t[last]) > 5);
	/* Held, not recomputed: the same doubles, so only rounding-free equality will do. */
	assert_true(mvod_vec3_dist(t[first], t[last]) < 1e-12);
	for (int k = 0; k < 9; k++)
		assert_true(fabs(R[first][k] - R[last][k]) < 1e-12);
	/* ... while the camera really moved on, through the frames nobody saw. */
	char gt_path[320], err[256];
	snprintf(gt_path, sizeof(gt_path), "%s/gt.tum", dir);
	struct mvod_traj gt;
	assert_int_equal(mvod_traj_load(gt_path, &gt, err, sizeof(err)), 0);
	assert_true(mvod_vec3_dist(gt.pose[BEFORE + UNSEEN].t, gt.pose[BEFORE - 1].t) > 1.0);
	/*
	 * Tracking goes on in the world frame it had: the path after the return points the way
	 * the camera drove (measured: cosine 0.996, 5 degrees off), not some new frame's axes;
	 * 0.98 is 11 degrees. Its steps take the scale from the last step before the return:
	 * measured 0.66 of the mean step before, as a free-scale chain drifts; a factor of 2
	 * either way is what the constant-speed guess may be off by.
	 */
	const double *g0 = gt.pose[BEFORE + UNSEEN].t, *g1 = gt.pose[gt.n - 1].t;
	double cosine = 0, step_after = mvod_vec3_dist(t[end], t[first]) / (AFTER - 1);
	double step_before = mvod_vec3_dist(t[last], t[0]) / (BEFORE - 1);
	for (int k = 0; k < 3; k++)
		cosine += (t[end][k] - t[first][k]) * (g1[k] - g0[k]);
	cosine /= mvod_vec3_dist(t[end], t[first]) * mvod_vec3_dist(g1, g0);
	assert_true(cosine > 0.98);
	assert_true(step_after > step_before / 2 && step_after < step_before * 2);
	mvod_traj_free(&gt);
}

/* A run of 3 frames stamped 100 s + seq ms by the driver, with clock; its last status. */
static void clock_run(enum mvod_clock clock, mvod_status_t *last)
{
	reset(V4L2_PIX_FMT_GREY);
	for (int i = 0; i < 3; i++)
		add_frame(i, (uint32_t)i);
	static volatile sig_atomic_t stop;
	stop = 0;
	F.done = &stop;
	fake_clock = clock;
	struct statuses got = {0};
	struct mvod_run_summary sum;
	run_fake(&stop, &got, &sum);
	fake_clock = MVOD_CLOCK_MONOTONIC;
	assert_true(got.n > 0);
	*last = got.last;
}

/*
 * --clock: monotonic leaves a frame's utime as the driver stamped the buffer; realtime moves
 * it to the same instant in Unix time, by the offset between the two clocks during the run.
 */
static void test_clock(void **state)
{
	(void)state;
	const int64_t stamped = 100 * 1000000LL; /* frame seq s: stamped + s ms */
	mvod_status_t last;
	clock_run(MVOD_CLOCK_MONOTONIC, &last);
	assert_in_range(last.utime, stamped, stamped + 2000);
	int64_t before = mvod_realtime_offset_us();
	clock_run(MVOD_CLOCK_REALTIME, &last);
	int64_t after = mvod_realtime_offset_us();
	/*
	 * The offset is sampled per frame, between before and after; only NTP's slew (at most
	 * 500 ppm) moves it, so 50 ms holds for runs up to 100 s.
	 */
	assert_in_range(last.utime, stamped + before - 50000, stamped + 2000 + after + 50000);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_clock),
		cmocka_unit_test(test_formats),
		cmocka_unit_test(test_read_into),
		cmocka_unit_test(test_focus_against_calibration),
		cmocka_unit_test(test_eintr),
		cmocka_unit_test(test_eagain_storm),
		cmocka_unit_test(test_refused_format_and_size),
		cmocka_unit_test(test_fewer_buffers),
		cmocka_unit_test(test_sequence_gaps),
		cmocka_unit_test(test_corrupt_mjpeg),
		cmocka_unit_test(test_bad_frames_not_dropped),
		cmocka_unit_test(test_lens_and_exposure),
		cmocka_unit_test(test_list),
		cmocka_unit_test(test_unplug_and_return),
		cmocka_unit_test(test_stop_while_down),
		cmocka_unit_test(test_reconnect_continues_pose),
	};
	return cmocka_run_group_tests(tests, NULL, harness_teardown);
}
