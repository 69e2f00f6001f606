/*
 * libcamera:ID-or-INDEX?width=W&height=H&format=F, a camera behind libcamera (Raspberry Pi CSI
 * cameras and other ISP pipelines). The C side: URI, format mapping and conversion to grey;
 * libcamera itself is behind libcamera_shim.h.
 */
#include "capture/libcamera_shim.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "capture/backends.h"
#include "capture/uri.h"

static int take_param(void *ctx, const char *key, const char *value, char *err, size_t errlen)
{
	struct mvod_lcam_want *w = ctx;
	if (strcmp(key, "width") == 0)
		return mvod_uri_int(key, value, 1, 16384, &w->width, err, errlen);
	if (strcmp(key, "height") == 0)
		return mvod_uri_int(key, value, 1, 16384, &w->height, err, errlen);
	if (strcmp(key, "format") == 0)
		return mvod_camfmt_param(value, &w->format, err, errlen);
	return mvod_uri_unknown(key, "width, height, format", err, errlen);
}

int mvod_lcam_parse(const char *location, struct mvod_lcam_want *want, char *err, size_t errlen)
{
	*want = (struct mvod_lcam_want){.format = -1};
	int ret = mvod_uri_parse(location, want->id, sizeof(want->id), take_param, want, err,
				 errlen);
	if (ret)
		return ret;
	if (!want->id[0])
		return mvod_errf(err, errlen, -EINVAL, "libcamera: needs a camera id or index, e.g. "
				 "libcamera:0 (mvod --list-cameras shows them)");
	if (strspn(want->id, "0123456789") != strlen(want->id))
		return 0;
	ret = mvod_uri_int("index", want->id, 0, 63, &want->index, err, errlen);
	want->id[0] = '\0';
	return ret;
}

struct lcam_source {
	struct mvod_lcam *cam;
	struct mvod_lcam_mode mode;
	struct mvod_mjpeg *mjpeg;
	struct mvod_image grey;
	struct mvod_seq seq;
	struct mvod_source_info info;
};

static void lcam_close(void *priv)
{
	struct lcam_source *s = priv;
	mvod_lcam_close(s->cam);
	mvod_mjpeg_destroy(s->mjpeg);
	free(s->grey.data);
}

static int lcam_open(void *priv, const char *location, char *err, size_t errlen)
{
	struct lcam_source *s = priv;
	struct mvod_lcam_want want;
	int ret = mvod_lcam_parse(location, &want, err, errlen);
	if (!ret)
		ret = mvod_lcam_open(&want, &s->cam, &s->mode, err, errlen);
	if (ret)
		return ret;
	int w = s->mode.width, h = s->mode.height;
	s->info = (struct mvod_source_info){.width = w, .height = h, .frames = -1, .live = true,
					    .focus = NAN, .monotonic = true};
	s->grey = (struct mvod_image){.w = w, .h = h, .stride = w, .fmt = MVOD_PIX_GREY,
				      .data = malloc((size_t)w * (size_t)h)};
	ret = s->grey.data ? 0 : -ENOMEM;
	if (!ret && s->mode.fmt == MVOD_CAMFMT_MJPEG)
		ret = mvod_mjpeg_create(&s->mjpeg);
	if (ret) {
		lcam_close(s);
		return mvod_errf(err, errlen, ret, "out of memory for libcamera:%s frames", location);
	}
	return 0;
}

static int lcam_read(void *priv, struct mvod_frame *frame, const struct mvod_image *into)
{
	struct lcam_source *s = priv;
	struct mvod_lcam_frame f;
	int ret = mvod_lcam_wait(s->cam, MVOD_CAMERA_WAIT_MS, &f);
	if (ret)
		return ret;
	frame->index = mvod_seq_next(&s->seq, f.sequence);
	frame->utime = f.utime;
	frame->img = into ? *into : s->grey;
	frame->bad = MVOD_BAD_CORRUPT; /* what -EINVAL means here: flagged, or not decoded */
	ret = f.bad || mvod_camfmt_to_grey(s->mode.fmt, f.data, f.len, s->mode.stride, s->mjpeg,
					   &frame->img) < 0 ? -EINVAL : 0;
	int rret = mvod_lcam_release(s->cam);
	return rret ? rret : ret;
}

static void lcam_info(void *priv, struct mvod_source_info *info)
{
	const struct lcam_source *s = priv;
	*info = s->info;
}

const struct mvod_source_ops mvod_source_libcamera_ops = {
	.scheme = "libcamera",
	.summary = "libcamera:ID|INDEX?width=W&height=H&format=F  a libcamera camera "
		   "(mvod --list-cameras)",
	.priv_size = sizeof(struct lcam_source),
	.open = lcam_open,
	.read = lcam_read,
	.info = lcam_info,
	.camera = NULL,
	.close = lcam_close,
};
