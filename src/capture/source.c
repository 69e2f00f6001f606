#include "mvod/capture.h"

#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "capture/backends.h"
#include "capture/libcamera_shim.h"
#include "capture/v4l2.h"
#include "util/clock.h"

const struct mvod_source_ops *const mvod_source_backends[] = {
	&mvod_source_file_ops,
	&mvod_source_images_ops,
	&mvod_source_kitti_ops,
	&mvod_source_kitti_raw_ops,
	&mvod_source_euroc_ops,
	&mvod_source_tum_ops,
	&mvod_source_v4l2_ops,
	&mvod_source_libcamera_ops,
	NULL,
};

/*
 * A build without libcamera lists no CSI camera: it says so, rather than "no libcamera
 * camera", which read as if libcamera had looked.
 */
int mvod_capture_list_cameras(FILE *out)
{
	int n = mvod_v4l2_list(out);
	int lcam = mvod_lcam_list(out);
	n += lcam > 0 ? lcam : 0;
	const char *none = n ? "" : "No cameras found: no V4L2 capture device in /dev/video*; ";
	if (lcam == -ENOTSUP)
		fprintf(out, "%slibcamera cameras cannot be listed: %s\n", none, MVOD_LCAM_NOT_BUILT);
	else if (n == 0)
		fprintf(out, "No cameras found: no V4L2 capture device in /dev/video*, and no "
			     "libcamera camera.\n");
	return n;
}

struct mvod_source {
	const struct mvod_source_ops *ops;
	struct mvod_source_info info; /* taken once at open; every frame is held to its size */
	max_align_t priv[];           /* ops->priv_size bytes of backend state */
};

/* The backend whose scheme prefixes uri, with *location pointing past the colon. */
static const struct mvod_source_ops *find_backend(const char *uri, const char **location)
{
	const char *colon = strchr(uri, ':');
	if (!colon)
		return NULL;
	size_t len = (size_t)(colon - uri);
	for (const struct mvod_source_ops *const *b = mvod_source_backends; *b; b++) {
		if (strlen((*b)->scheme) == len && strncmp(uri, (*b)->scheme, len) == 0) {
			*location = colon + 1;
			return *b;
		}
	}
	return NULL;
}

/* "file, images, kitti": the schemes for an error message. */
static void list_schemes(char *buf, size_t len)
{
	size_t used = 0;
	buf[0] = '\0';
	for (const struct mvod_source_ops *const *b = mvod_source_backends; *b && used < len; b++)
		used += (size_t)snprintf(buf + used, len - used, "%s%s",
					 b == mvod_source_backends ? "" : ", ", (*b)->scheme);
}

/* Why uri names no backend, with the URI the user most likely meant. */
static int unknown_scheme(const char *uri, char *err, size_t errlen)
{
	char known[128];
	list_schemes(known, sizeof(known));
	const char *colon = strchr(uri, ':');
	/* A colon inside a path ("./a:b.mkv") is no scheme separator. */
	if (colon && colon > uri && !memchr(uri, '/', (size_t)(colon - uri)))
		return mvod_errf(err, errlen, -EPROTONOSUPPORT,
					 "unknown source scheme \"%.*s\" in \"%s\" (known: %s)",
					 (int)(colon - uri), uri, uri, known);
	struct stat st;
	if (stat(uri, &st) == 0 && S_ISDIR(st.st_mode))
		return mvod_errf(err, errlen, -EPROTONOSUPPORT,
					 "source \"%s\" has no scheme: write images:%s or kitti:%s "
					 "(known: %s)", uri, uri, uri, known);
	return mvod_errf(err, errlen, -EPROTONOSUPPORT,
				 "source \"%s\" has no scheme: for a video file write file:%s "
				 "(known: %s)", uri, uri, known);
}

int mvod_source_open(const char *uri, struct mvod_source **out, char *err, size_t errlen)
{
	const char *location = NULL;
	const struct mvod_source_ops *ops = find_backend(uri, &location);
	if (!ops)
		return unknown_scheme(uri, err, errlen);
	struct mvod_source *src = calloc(1, sizeof(*src) + ops->priv_size);
	if (!src)
		return mvod_errf(err, errlen, -ENOMEM, "out of memory opening %s", uri);
	src->ops = ops;
	int ret = ops->open(src->priv, location, err, errlen);
	if (ret < 0)
		goto fail;
	ops->info(src->priv, &src->info);
	*out = src;
	return 0;
fail:
	free(src);
	return ret;
}

bool mvod_source_may_have_gt(const char *uri)
{
	const char *location;
	const struct mvod_source_ops *ops = find_backend(uri, &location);
	return ops && ops->ground_truth;
}

int mvod_source_read(struct mvod_source *src, struct mvod_frame *frame)
{
	return mvod_source_read_into(src, frame, NULL);
}

int mvod_source_read_into(struct mvod_source *src, struct mvod_frame *frame,
			  const struct mvod_image *into)
{
	frame->bad = MVOD_BAD_CORRUPT; /* unless the backend knows better */
	int ret = src->ops->read(src->priv, frame, into);
	frame->delivered_us = mvod_now_us();
	/* Everything downstream is sized from info at start-up; a frame of another size is bad. */
	if (ret == 0 && (frame->img.w != src->info.width || frame->img.h != src->info.height)) {
		frame->bad = MVOD_BAD_SIZE;
		return -EINVAL;
	}
	return ret;
}

const char *mvod_bad_frame_name(enum mvod_bad_frame why)
{
	static const char *const names[MVOD_BAD_COUNT] = {
		[MVOD_BAD_UNREADABLE] = "unreadable",
		[MVOD_BAD_CORRUPT] = "corrupt or not an image",
		[MVOD_BAD_TOO_LARGE] = "too large a file",
		[MVOD_BAD_SIZE] = "of another size",
	};
	return why < MVOD_BAD_COUNT ? names[why] : "bad";
}

void mvod_source_info(struct mvod_source *src, struct mvod_source_info *info)
{
	*info = src->info;
}

int mvod_source_camera(struct mvod_source *src, struct mvod_camera *cam)
{
	if (!src->ops->camera)
		return -ENOENT;
	return src->ops->camera(src->priv, cam);
}

int mvod_source_ground_truth(struct mvod_source *src, struct mvod_traj *gt, char *from,
			     size_t fromlen, char *err, size_t errlen)
{
	if (!src->ops->ground_truth)
		return -ENOENT;
	return src->ops->ground_truth(src->priv, gt, from, fromlen, err, errlen);
}

void mvod_source_close(struct mvod_source *src)
{
	if (!src)
		return;
	src->ops->close(src->priv);
	free(src);
}
