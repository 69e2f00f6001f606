/*
 * The libcamera door of the libcamera: backend (libcamera_shim.cpp; libcamera_none.c when mvod
 * is built without libcamera). Plain C; every function returns 0 or -errno and lets no
 * exception out. One camera per object; it owns the camera manager while open.
 */
#ifndef MVOD_CAPTURE_LIBCAMERA_SHIM_H
#define MVOD_CAPTURE_LIBCAMERA_SHIM_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "capture/camfmt.h"

#ifdef __cplusplus
extern "C" {
#endif

/* What the URI asks for. */
struct mvod_lcam_want {
	char id[256];    /* a camera id, or "" to pick by index */
	long index;      /* position in libcamera's list when id is "" */
	long width, height; /* 0: the camera's default */
	int format;      /* enum mvod_camfmt, or -1 for the first one mvod reads */
};

/* What the camera was configured to. */
struct mvod_lcam_mode {
	int width, height;
	int stride;      /* bytes between luma rows */
	enum mvod_camfmt fmt;
};

/* One completed buffer, readable until mvod_lcam_release. */
struct mvod_lcam_frame {
	const uint8_t *data;
	size_t len;
	uint32_t sequence;
	int64_t utime;   /* sensor time, CLOCK_MONOTONIC microseconds */
	bool bad;        /* libcamera reported the frame as failed */
};

struct mvod_lcam;

int mvod_lcam_open(const struct mvod_lcam_want *want, struct mvod_lcam **out,
		   struct mvod_lcam_mode *mode, char *err, size_t errlen);
/* 0 with a frame, -EAGAIN when none completed in timeout_ms, -ENODEV once disconnected. */
int mvod_lcam_wait(struct mvod_lcam *c, int timeout_ms, struct mvod_lcam_frame *f);
/* Gives the buffer of the last frame back to the camera. */
int mvod_lcam_release(struct mvod_lcam *c);
/* NULL is a no-op. */
void mvod_lcam_close(struct mvod_lcam *c);
/*
 * Prints the cameras (index, id, model) with their --source URIs; returns how many, or
 * -ENOTSUP in a build without libcamera (libcamera_none.c), which lists nothing.
 */
int mvod_lcam_list(FILE *out);
/* What a build without libcamera says of the libcamera: backend: why, and what to do. */
#define MVOD_LCAM_NOT_BUILT                                                                         \
	"this mvod was built without libcamera: install libcamera-dev and rebuild (meson setup "   \
	"-Dlibcamera=enabled)"

/* Parses the location of a libcamera: URI ("0", "/base/...imx219@10?width=640"). */
int mvod_lcam_parse(const char *location, struct mvod_lcam_want *want, char *err, size_t errlen);

#ifdef __cplusplus
}
#endif

#endif
