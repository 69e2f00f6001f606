/*
 * The OpenCV door of the capture backends: still-image decoding (cv::imdecode; videos are
 * video.c's, FFmpeg directly). Plain C. Every function catches every exception and
 * returns 0 or -errno. Frames are views of a buffer the object keeps and reuses, so steady
 * state does not allocate; a view stays valid until the next read/decode or the destroy.
 */
#ifndef MVOD_VIDEO_SHIM_H
#define MVOD_VIDEO_SHIM_H

#include <stddef.h>
#include <stdint.h>

#include "mvod/capture.h"
#include "mvod/image.h"

#ifdef __cplusplus
extern "C" {
#endif

/*
 * Still images (PNG, JPEG, PNM, BMP, TIFF) from an encoded buffer. The first image decides
 * the pixel format (grey stays grey, anything with colour is BGR); later images are
 * converted to it. 16-bit samples keep their high byte, alpha is dropped.
 */
struct mvod_imgdec;
int mvod_imgdec_create(struct mvod_imgdec **out);
/* -EINVAL when buf is not an image OpenCV can decode. */
int mvod_imgdec_decode(struct mvod_imgdec *d, const void *buf, size_t len, struct mvod_image *img);
/* NULL is a no-op. */
void mvod_imgdec_destroy(struct mvod_imgdec *d);

#ifdef __cplusplus
}
#endif

#endif
