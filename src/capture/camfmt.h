/*
 * The pixel formats mvod takes from cameras (V4L2 and libcamera alike) and their conversion to
 * the 8-bit grey the visual odometry runs on. MJPEG is decoded by libjpeg-turbo straight to grey.
 */
#ifndef MVOD_CAPTURE_CAMFMT_H
#define MVOD_CAPTURE_CAMFMT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "mvod/image.h"

#ifdef __cplusplus
extern "C" {
#endif

enum mvod_camfmt {
	MVOD_CAMFMT_GREY = 0, /* 8-bit luma */
	MVOD_CAMFMT_YUYV = 1, /* packed 4:2:2, Y0 U Y1 V */
	MVOD_CAMFMT_NV12 = 2, /* planar 4:2:0: the Y plane, then interleaved CbCr */
	MVOD_CAMFMT_MJPEG = 3,
	MVOD_CAMFMT_COUNT,
};

/* The camera APIs, each naming the formats by its own fourccs. */
enum mvod_camfmt_api {
	MVOD_CAMFMT_V4L2 = 0,      /* V4L2_PIX_FMT_*: GREY, YUYV, NV12, MJPG */
	MVOD_CAMFMT_LIBCAMERA = 1, /* DRM fourccs: R8, YUYV, NV12, MJPG */
	MVOD_CAMFMT_API_COUNT,
};

/* "GREY", "YUYV", "NV12", "MJPEG" (what users write in format=). */
const char *mvod_camfmt_name(enum mvod_camfmt f);
/*
 * A source URI's format=value (case-insensitive; MJPG is taken for MJPEG) into *format, an
 * enum mvod_camfmt. -EINVAL with the reason, naming the choices, in err.
 */
int mvod_camfmt_param(const char *value, int *format, char *err, size_t errlen);
/* "GREY, YUYV, NV12, MJPEG", for messages. */
extern const char mvod_camfmt_known[];
/* f's fourcc in api; 0 for none. */
uint32_t mvod_camfmt_fourcc(enum mvod_camfmt f, enum mvod_camfmt_api api);
/* The format api's fourcc names; -ENOENT for one mvod does not read. */
int mvod_camfmt_of_fourcc(uint32_t fourcc, enum mvod_camfmt_api api, enum mvod_camfmt *out);

/*
 * Bytes of one w x h frame whose luma rows are stride bytes apart (0 for MJPEG, whose size
 * varies): what a driver must deliver at least.
 */
size_t mvod_camfmt_frame_bytes(enum mvod_camfmt f, int stride, int h);

struct mvod_mjpeg;
/* The decoder state is made once per stream; NULL is a no-op for destroy. */
int mvod_mjpeg_create(struct mvod_mjpeg **out);
void mvod_mjpeg_destroy(struct mvod_mjpeg *d);

/*
 * Converts one camera buffer of len bytes (luma rows stride bytes apart) into dst, a tightly
 * packed w x h grey image. -EBADMSG when the buffer is too short or the JPEG is corrupt,
 * truncated or of another size: the frame is lost, the stream goes on. dec is needed for MJPEG.
 */
int mvod_camfmt_to_grey(enum mvod_camfmt f, const uint8_t *buf, size_t len, int stride,
			struct mvod_mjpeg *dec, struct mvod_image *dst);

/* Milliseconds a camera read waits for a frame before it answers -EAGAIN ("no frame yet"). */
#define MVOD_CAMERA_WAIT_MS 200

/*
 * Frame numbers from a driver's 32-bit sequence counter, so that a frame the driver dropped
 * leaves a gap in them the consumer counts. A driver that leaves the counter at 0 counts one
 * per frame. Zeroed before the first frame.
 */
struct mvod_seq {
	bool started;
	uint32_t last;
	int64_t index;
};
/* The frame number of a buffer with sequence seq; the first is 0. */
int64_t mvod_seq_next(struct mvod_seq *s, uint32_t seq);

#ifdef __cplusplus
}
#endif

#endif
