/*
 * Frame sources, chosen by URI scheme (file:, images:, kitti:). Each backend is a
 * const struct mvod_source_ops, the way LCM picks a provider from its URL.
 */
#ifndef MVOD_CAPTURE_H
#define MVOD_CAPTURE_H

#include <stddef.h>
#include <stdint.h>

#include "mvod/calib.h"
#include "mvod/image.h"

#ifdef __cplusplus
extern "C" {
#endif

struct mvod_frame {
	struct mvod_image img; /* borrowed from the source: valid until the next read or close */
	int64_t utime;         /* source clock (media time, times.txt), microseconds */
	int64_t index;         /* 0-based frame number in the source */
};

struct mvod_source_info {
	int width, height; /* pixels of every frame the source will deliver */
	double fps;        /* nominal rate; 0 when unknown */
	int64_t frames;    /* total frames when known, else -1 */
};

struct mvod_source_ops {
	const char *scheme;   /* URI scheme without the colon, e.g. "images" */
	const char *summary;  /* one line for --help */
	size_t priv_size;     /* bytes of backend state, zeroed before open */
	/* location is the URI without "scheme:". Returns 0 or -errno with a reason in err. */
	int (*open)(void *priv, const char *location, char *err, size_t errlen);
	/* 0 = a frame, -ENODATA = end of stream, -EAGAIN = no frame yet, other -errno = failure. */
	int (*read)(void *priv, struct mvod_frame *frame);
	void (*info)(void *priv, struct mvod_source_info *info);
	/* Intrinsics the source carries (KITTI calib.txt); -ENOENT when it has none. May be NULL. */
	int (*camera)(void *priv, struct mvod_camera *cam);
	void (*close)(void *priv);
};

struct mvod_source;

/* Opens a source from a URI such as "file:clip.mkv". -EPROTONOSUPPORT for an unknown scheme. */
int mvod_source_open(const char *uri, struct mvod_source **out, char *err, size_t errlen);
int mvod_source_read(struct mvod_source *src, struct mvod_frame *frame);
void mvod_source_info(struct mvod_source *src, struct mvod_source_info *info);
int mvod_source_camera(struct mvod_source *src, struct mvod_camera *cam);
/* Closes and frees; NULL is a no-op. */
void mvod_source_close(struct mvod_source *src);

/* The registered backends, NULL-terminated (for --help and tests). */
extern const struct mvod_source_ops *const mvod_source_backends[];

#ifdef __cplusplus
}
#endif

#endif
