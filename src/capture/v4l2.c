/*
 * v4l2:/dev/videoN?width=W&height=H&fps=F&format=F&exposure=auto|N: a V4L2 capture device,
 * streamed through mmap buffers acquired once at open. Frames are converted to grey into the
 * caller's buffer (the capture thread's mailbox) or one the source owns; the driver's buffer
 * goes back to it right after.
 */
#include "capture/v4l2.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <linux/videodev2.h>

#include "capture/backends.h"
#include "capture/uri.h"
#include "util/clock.h"

/* Enough to keep the driver filling one buffer while mvod converts another. */
#define WANT_BUFFERS 4
#define MIN_BUFFERS 2

static int libc_open(const char *path, int flags)
{
	return open(path, flags);
}

static int libc_ioctl(int fd, unsigned long request, void *arg)
{
	return ioctl(fd, request, arg);
}

const struct mvod_v4l2_io mvod_v4l2_libc_io = {
	.open = libc_open,
	.close = close,
	.ioctl = libc_ioctl,
	.mmap = mmap,
	.munmap = munmap,
	.poll = poll,
};

const struct mvod_v4l2_io *mvod_v4l2_io = &mvod_v4l2_libc_io;

int mvod_v4l2_xioctl(const struct mvod_v4l2_io *io, int fd, unsigned long request, void *arg)
{
	int r;
	do
		r = io->ioctl(fd, request, arg);
	while (r < 0 && errno == EINTR);
	return r < 0 ? -errno : 0;
}

/* What the URI asks for; 0 (or format -1) leaves the choice to the device. */
struct request {
	long width, height;
	double fps;
	int format;        /* enum mvod_camfmt, or -1 */
	bool set_exposure;
	long exposure;     /* 100 us units; -1 = automatic */
};

struct buffer {
	void *start;
	size_t len;
};

struct v4l2_source {
	const struct mvod_v4l2_io *io;
	char path[256];
	int fd;
	struct request want;
	enum mvod_camfmt fmt;
	int stride;                    /* bytes between luma rows in the driver's buffers */
	struct buffer buf[WANT_BUFFERS];
	unsigned nbuf;                 /* buffers mapped */
	bool streaming;
	struct mvod_mjpeg *mjpeg;
	struct mvod_image grey;        /* the converted frame; owned */
	struct mvod_seq seq;
	struct mvod_source_info info;
};

static int xioctl(const struct v4l2_source *v, unsigned long request, void *arg)
{
	return mvod_v4l2_xioctl(v->io, v->fd, request, arg);
}

static int take_param(void *ctx, const char *key, const char *value, char *err, size_t errlen)
{
	struct request *w = ctx;
	if (strcmp(key, "width") == 0)
		return mvod_uri_int(key, value, 1, 16384, &w->width, err, errlen);
	if (strcmp(key, "height") == 0)
		return mvod_uri_int(key, value, 1, 16384, &w->height, err, errlen);
	if (strcmp(key, "fps") == 0)
		return mvod_uri_positive(key, value, 1000, &w->fps, err, errlen);
	if (strcmp(key, "format") == 0)
		return mvod_camfmt_param(value, &w->format, err, errlen);
	if (strcmp(key, "exposure") == 0) {
		w->set_exposure = true;
		w->exposure = -1;
		if (strcmp(value, "auto") == 0)
			return 0;
		return mvod_uri_int(key, value, 1, 10000000, &w->exposure, err, errlen);
	}
	return mvod_uri_unknown(key, "width, height, fps, format, exposure", err, errlen);
}

static int open_device(struct v4l2_source *v, char *err, size_t errlen)
{
	v->fd = v->io->open(v->path, O_RDWR | O_NONBLOCK | O_CLOEXEC);
	if (v->fd < 0 && errno == ENOENT)
		return mvod_errf(err, errlen, -ENOENT, "no such device %s: mvod --list-cameras "
				 "shows the cameras there are", v->path);
	if (v->fd < 0 && errno == EACCES)
		return mvod_errf(err, errlen, -EACCES, "permission denied opening %s: add the user "
				 "to the video group", v->path);
	if (v->fd < 0)
		return mvod_errf(err, errlen, -errno, "cannot open %s: %s", v->path,
				 strerror(errno));
	struct v4l2_capability cap = {0};
	int ret = xioctl(v, VIDIOC_QUERYCAP, &cap);
	if (ret)
		return mvod_errf(err, errlen, -ENODEV, "%s is not a V4L2 device (%s)", v->path,
				 strerror(-ret));
	uint32_t caps = cap.capabilities & V4L2_CAP_DEVICE_CAPS ? cap.device_caps : cap.capabilities;
	if (!(caps & V4L2_CAP_VIDEO_CAPTURE) || !(caps & V4L2_CAP_STREAMING))
		return mvod_errf(err, errlen, -ENODEV, "%s (%s) is not a streaming video capture "
				 "node (a metadata node?): mvod --list-cameras shows those that are",
				 v->path, (const char *)cap.card);
	return 0;
}

/* The device's current format when mvod reads it, else the first one it offers that mvod reads. */
static int pick_format(struct v4l2_source *v, uint32_t *fourcc, char *err, size_t errlen)
{
	enum mvod_camfmt f;
	if (mvod_camfmt_of_fourcc(*fourcc, MVOD_CAMFMT_V4L2, &f) == 0)
		return 0;
	struct v4l2_fmtdesc d = {.type = V4L2_BUF_TYPE_VIDEO_CAPTURE};
	for (; xioctl(v, VIDIOC_ENUM_FMT, &d) == 0; d.index++) {
		if (mvod_camfmt_of_fourcc(d.pixelformat, MVOD_CAMFMT_V4L2, &f) == 0) {
			*fourcc = d.pixelformat;
			return 0;
		}
	}
	return mvod_errf(err, errlen, -ENOTSUP, "%s offers none of the formats mvod reads (%s)",
			 v->path, mvod_camfmt_known);
}

/* S_FMT may change what was asked: anything but exactly the request is refused, not adapted. */
static int check_format(struct v4l2_source *v, uint32_t asked, const struct v4l2_pix_format *p,
			char *err, size_t errlen)
{
	if (p->pixelformat != asked ||
	    mvod_camfmt_of_fourcc(p->pixelformat, MVOD_CAMFMT_V4L2, &v->fmt) < 0)
		return mvod_errf(err, errlen, -EINVAL, "%s refused format %.4s (it set %.4s): pick "
				 "one it lists in mvod --list-cameras", v->path, (const char *)&asked,
				 (const char *)&p->pixelformat);
	if ((v->want.width && p->width != (uint32_t)v->want.width) ||
	    (v->want.height && p->height != (uint32_t)v->want.height))
		return mvod_errf(err, errlen, -EINVAL, "%s cannot deliver %ldx%ld in %s (it set "
				 "%ux%u): pick a size it lists in mvod --list-cameras", v->path,
				 v->want.width, v->want.height, mvod_camfmt_name(v->fmt), p->width,
				 p->height);
	if (p->field != V4L2_FIELD_NONE)
		return mvod_errf(err, errlen, -EINVAL, "%s delivers interlaced fields, which mvod "
				 "cannot track", v->path);
	int packed = v->fmt == MVOD_CAMFMT_YUYV ? 2 : 1;
	v->stride = (int)p->bytesperline;
	if (v->stride < packed * (int)p->width)
		v->stride = packed * (int)p->width; /* drivers may leave it 0 for packed formats */
	v->info.width = (int)p->width;
	v->info.height = (int)p->height;
	return 0;
}

static int set_format(struct v4l2_source *v, char *err, size_t errlen)
{
	struct v4l2_format f = {.type = V4L2_BUF_TYPE_VIDEO_CAPTURE};
	int ret = xioctl(v, VIDIOC_G_FMT, &f);
	if (ret)
		return mvod_errf(err, errlen, ret, "%s: cannot read its format: %s", v->path,
				 strerror(-ret));
	if (v->want.format >= 0)
		f.fmt.pix.pixelformat = mvod_camfmt_fourcc(v->want.format, MVOD_CAMFMT_V4L2);
	else if ((ret = pick_format(v, &f.fmt.pix.pixelformat, err, errlen)) < 0)
		return ret;
	if (v->want.width)
		f.fmt.pix.width = (uint32_t)v->want.width;
	if (v->want.height)
		f.fmt.pix.height = (uint32_t)v->want.height;
	f.fmt.pix.field = V4L2_FIELD_NONE;
	uint32_t asked = f.fmt.pix.pixelformat;
	ret = xioctl(v, VIDIOC_S_FMT, &f);
	if (ret == -EBUSY)
		return mvod_errf(err, errlen, ret, "%s is busy: another program is streaming from "
				 "it", v->path);
	if (ret)
		return mvod_errf(err, errlen, ret, "%s: cannot set format %.4s: %s", v->path,
				 (const char *)&asked, strerror(-ret));
	return check_format(v, asked, &f.fmt.pix, err, errlen);
}

/* Asks for want.fps and refuses a rate more than 1 % off it; records the rate either way. */
static int set_rate(struct v4l2_source *v, char *err, size_t errlen)
{
	struct v4l2_streamparm p = {.type = V4L2_BUF_TYPE_VIDEO_CAPTURE};
	struct v4l2_fract *tpf = &p.parm.capture.timeperframe;
	if (v->want.fps > 0) {
		*tpf = (struct v4l2_fract){.numerator = 1000,
					   .denominator = (uint32_t)lround(v->want.fps * 1000)};
		int ret = xioctl(v, VIDIOC_S_PARM, &p);
		if (ret && ret != -ENOTTY)
			return mvod_errf(err, errlen, ret, "%s: cannot set %g fps: %s", v->path,
					 v->want.fps, strerror(-ret));
	}
	memset(&p.parm, 0, sizeof(p.parm));
	if (xioctl(v, VIDIOC_G_PARM, &p) == 0 && tpf->numerator && tpf->denominator)
		v->info.fps = (double)tpf->denominator / tpf->numerator;
	if (v->want.fps > 0 && fabs(v->info.fps - v->want.fps) > 0.01 * v->want.fps)
		return mvod_errf(err, errlen, -EINVAL, "%s runs at %.4g fps at %dx%d %s, not the %g "
				 "asked: pick a rate it lists in mvod --list-cameras", v->path,
				 v->info.fps, v->info.width, v->info.height,
				 mvod_camfmt_name(v->fmt), v->want.fps);
	return 0;
}

/* A control's value; -ENOENT when the device lacks it or has it disabled. */
static int get_ctrl(const struct v4l2_source *v, uint32_t id, int *value)
{
	struct v4l2_queryctrl q = {.id = id};
	if (xioctl(v, VIDIOC_QUERYCTRL, &q) < 0 || (q.flags & V4L2_CTRL_FLAG_DISABLED))
		return -ENOENT;
	struct v4l2_control c = {.id = id};
	int ret = xioctl(v, VIDIOC_G_CTRL, &c);
	*value = c.value;
	return ret;
}

static int set_ctrl(const struct v4l2_source *v, uint32_t id, int value)
{
	struct v4l2_control c = {.id = id, .value = value};
	return xioctl(v, VIDIOC_S_CTRL, &c);
}

/*
 * A focus or zoom change moves the focal length and the distortion the calibration measured:
 * autofocus and zoom motion are stopped, and the focus the lens stays at is recorded.
 */
static int lock_lens(struct v4l2_source *v, char *err, size_t errlen)
{
	int on = 0, ret = 0;
	if (get_ctrl(v, V4L2_CID_FOCUS_AUTO, &on) == 0 && on)
		ret = set_ctrl(v, V4L2_CID_FOCUS_AUTO, 0);
	if (ret)
		return mvod_errf(err, errlen, ret, "%s: cannot switch autofocus off (%s), and a focus "
				 "change invalidates the calibration", v->path, strerror(-ret));
	if (get_ctrl(v, V4L2_CID_ZOOM_CONTINUOUS, &on) == 0 && on)
		ret = set_ctrl(v, V4L2_CID_ZOOM_CONTINUOUS, 0);
	if (ret)
		return mvod_errf(err, errlen, ret, "%s: cannot stop the zoom (%s), and a zoom "
				 "change invalidates the calibration", v->path, strerror(-ret));
	int focus;
	v->info.focus = get_ctrl(v, V4L2_CID_FOCUS_ABSOLUTE, &focus) == 0 ? focus : NAN;
	return 0;
}

static int set_exposure(struct v4l2_source *v, char *err, size_t errlen)
{
	int mode, ret;
	if (!v->want.set_exposure)
		return 0;
	if (get_ctrl(v, V4L2_CID_EXPOSURE_AUTO, &mode) < 0)
		return mvod_errf(err, errlen, -ENOTSUP, "%s has no exposure control: leave "
				 "exposure= out of the source URI", v->path);
	if (v->want.exposure < 0) {
		/* UVC cameras offer aperture priority as their automatic mode, others full auto. */
		ret = set_ctrl(v, V4L2_CID_EXPOSURE_AUTO, V4L2_EXPOSURE_AUTO);
		if (ret)
			ret = set_ctrl(v, V4L2_CID_EXPOSURE_AUTO, V4L2_EXPOSURE_APERTURE_PRIORITY);
	} else {
		ret = set_ctrl(v, V4L2_CID_EXPOSURE_AUTO, V4L2_EXPOSURE_MANUAL);
		if (!ret)
			ret = set_ctrl(v, V4L2_CID_EXPOSURE_ABSOLUTE, (int)v->want.exposure);
	}
	if (ret)
		return mvod_errf(err, errlen, ret, "%s: cannot set the exposure: %s", v->path,
				 strerror(-ret));
	return 0;
}

static int map_buffers(struct v4l2_source *v, char *err, size_t errlen)
{
	struct v4l2_requestbuffers rb = {.count = WANT_BUFFERS, .type = V4L2_BUF_TYPE_VIDEO_CAPTURE,
					 .memory = V4L2_MEMORY_MMAP};
	int ret = xioctl(v, VIDIOC_REQBUFS, &rb);
	if (ret)
		return mvod_errf(err, errlen, ret, "%s cannot stream through mmap buffers: %s",
				 v->path, strerror(-ret));
	if (rb.count < MIN_BUFFERS)
		return mvod_errf(err, errlen, -ENOMEM, "%s granted %u buffer(s) and mvod needs at "
				 "least %d: close other programs using it", v->path, rb.count,
				 MIN_BUFFERS);
	unsigned n = rb.count < WANT_BUFFERS ? rb.count : WANT_BUFFERS;
	for (v->nbuf = 0; v->nbuf < n; v->nbuf++) {
		struct v4l2_buffer b = {.type = rb.type, .memory = rb.memory, .index = v->nbuf};
		ret = xioctl(v, VIDIOC_QUERYBUF, &b);
		if (ret)
			return mvod_errf(err, errlen, ret, "%s: cannot query buffer %u: %s", v->path,
					 v->nbuf, strerror(-ret));
		void *p = v->io->mmap(NULL, b.length, PROT_READ | PROT_WRITE, MAP_SHARED, v->fd,
				      (off_t)b.m.offset);
		if (p == MAP_FAILED)
			return mvod_errf(err, errlen, -errno, "%s: cannot map buffer %u: %s",
					 v->path, v->nbuf, strerror(errno));
		v->buf[v->nbuf] = (struct buffer){p, b.length};
		ret = xioctl(v, VIDIOC_QBUF, &b);
		if (ret)
			return mvod_errf(err, errlen, ret, "%s: cannot queue buffer %u: %s", v->path,
					 v->nbuf, strerror(-ret));
	}
	return 0;
}

static int start(struct v4l2_source *v, char *err, size_t errlen)
{
	size_t bytes = (size_t)v->info.width * (size_t)v->info.height;
	v->grey = (struct mvod_image){.w = v->info.width, .h = v->info.height,
				      .stride = v->info.width, .fmt = MVOD_PIX_GREY,
				      .data = malloc(bytes)};
	int ret = v->grey.data ? 0 : -ENOMEM;
	if (!ret && v->fmt == MVOD_CAMFMT_MJPEG)
		ret = mvod_mjpeg_create(&v->mjpeg);
	if (ret)
		return mvod_errf(err, errlen, ret, "out of memory for %s frames", v->path);
	ret = map_buffers(v, err, errlen);
	if (ret)
		return ret;
	int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
	ret = xioctl(v, VIDIOC_STREAMON, &type);
	if (ret)
		return mvod_errf(err, errlen, ret, "%s: cannot start streaming: %s", v->path,
				 strerror(-ret));
	v->streaming = true;
	return 0;
}

static void v4l2_close(void *priv)
{
	struct v4l2_source *v = priv;
	int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
	/* A device that is gone refuses STREAMOFF; closing it releases the buffers regardless. */
	if (v->streaming)
		(void)xioctl(v, VIDIOC_STREAMOFF, &type);
	for (unsigned i = 0; i < v->nbuf; i++)
		v->io->munmap(v->buf[i].start, v->buf[i].len);
	if (v->fd >= 0)
		v->io->close(v->fd);
	mvod_mjpeg_destroy(v->mjpeg);
	free(v->grey.data);
}

static int v4l2_open(void *priv, const char *location, char *err, size_t errlen)
{
	struct v4l2_source *v = priv;
	v->io = mvod_v4l2_io;
	v->fd = -1;
	v->want.format = -1;
	v->info = (struct mvod_source_info){.frames = -1, .live = true, .focus = NAN,
					    .monotonic = true};
	int ret = mvod_uri_parse(location, v->path, sizeof(v->path), take_param, &v->want, err,
				 errlen);
	if (!ret)
		ret = open_device(v, err, errlen);
	if (!ret)
		ret = set_format(v, err, errlen);
	if (!ret)
		ret = set_rate(v, err, errlen);
	if (!ret)
		ret = lock_lens(v, err, errlen);
	if (!ret)
		ret = set_exposure(v, err, errlen);
	if (!ret)
		ret = start(v, err, errlen);
	if (ret)
		v4l2_close(v);
	return ret;
}

/* Time of capture on CLOCK_MONOTONIC, from the buffer when the driver stamps it so. */
static int64_t buffer_utime(const struct v4l2_buffer *b)
{
	if ((b->flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) == V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC)
		return (int64_t)b->timestamp.tv_sec * 1000000 + b->timestamp.tv_usec;
	return mvod_now_us();
}

static int take_frame(struct v4l2_source *v, const struct v4l2_buffer *b,
		      const struct mvod_image *into, struct mvod_frame *f)
{
	f->index = mvod_seq_next(&v->seq, b->sequence);
	f->utime = buffer_utime(b);
	const struct buffer *m = &v->buf[b->index];
	size_t used = b->bytesused && b->bytesused <= m->len ? b->bytesused : m->len;
	f->img = into ? *into : v->grey;
	/* A frame the driver flags as corrupt, or one that does not convert, is lost alone. */
	f->bad = MVOD_BAD_CORRUPT;
	if ((b->flags & V4L2_BUF_FLAG_ERROR) ||
	    mvod_camfmt_to_grey(v->fmt, m->start, used, v->stride, v->mjpeg, &f->img) < 0)
		return -EINVAL;
	return 0;
}

/* EIO from the queue ioctls is how some drivers say the device went away; ENODEV how most do. */
static int gone(int ret)
{
	return ret == -EIO ? -ENODEV : ret;
}

static int v4l2_read(void *priv, struct mvod_frame *frame, const struct mvod_image *into)
{
	struct v4l2_source *v = priv;
	struct pollfd p = {.fd = v->fd, .events = POLLIN};
	int n = v->io->poll(&p, 1, MVOD_CAMERA_WAIT_MS);
	if (n < 0)
		return errno == EINTR ? -EAGAIN : gone(-errno);
	if (n == 0)
		return -EAGAIN;
	struct v4l2_buffer b = {.type = V4L2_BUF_TYPE_VIDEO_CAPTURE, .memory = V4L2_MEMORY_MMAP};
	int ret = xioctl(v, VIDIOC_DQBUF, &b);
	if (ret)
		return gone(ret);
	if (b.index >= v->nbuf)
		return -EPROTO; /* a driver bug, not a disconnect */
	ret = take_frame(v, &b, into, frame);
	int qret = xioctl(v, VIDIOC_QBUF, &b);
	return qret ? gone(qret) : ret;
}

static void v4l2_info(void *priv, struct mvod_source_info *info)
{
	const struct v4l2_source *v = priv;
	*info = v->info;
}

const struct mvod_source_ops mvod_source_v4l2_ops = {
	.scheme = "v4l2",
	.summary = "v4l2:/dev/videoN?width=W&height=H&fps=F&format=GREY|YUYV|NV12|MJPEG"
		   "&exposure=auto|N  a V4L2 camera (mvod --list-cameras)",
	.priv_size = sizeof(struct v4l2_source),
	.open = v4l2_open,
	.read = v4l2_read,
	.info = v4l2_info,
	.camera = NULL,
	.close = v4l2_close,
};
